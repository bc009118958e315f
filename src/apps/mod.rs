//! The command-line applications built on the library.

pub mod bench;
pub mod cloud_quality;
pub mod convert;
pub mod convert_large;
pub mod frame_args;
pub mod info;
pub mod info_scene;
pub mod jobs;
pub mod progress;
pub mod render;
pub mod render_scene;
pub mod scatter;
pub mod stats;
pub mod text;
pub mod view;
