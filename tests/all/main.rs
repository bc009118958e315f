//! The integration tests, one crate (one binary to link): each module holds the tests
//! of one area, `common` their shared helpers. The tests that measure allocations are
//! in `tests/allocation/`, a binary of their own.

mod common;

mod bad_input;
mod bad_outputs;
mod bad_scenes;
mod bench;
mod cli_help;
mod cloud_quality;
mod cloud_rows;
mod docs;
mod file_quirks;
mod hostile_inputs;
mod instances;
mod jobs;
mod layers;
mod mesh_sides;
mod out_of_core;
mod ply_roundtrip;
mod ply_tristrips;
mod read_progress;
mod render_chunks;
mod render_compute;
mod render_flip;
mod render_lidar;
mod render_lod_ewa;
mod render_quality;
mod render_streaming;
mod shared_data;
mod spt_file;
mod surfel_hard_cases;
mod surfel_progress;
mod surfel_properties;
mod tree_hard_cases;
mod tree_properties;
mod up_axis;
mod viewer_interaction;
mod viewer_window;
