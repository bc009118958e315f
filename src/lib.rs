//! spt: a point-based rendering engine.
//!
//! Data flow (see `DESIGN.md` in the project's shared folder):
//! `io` (PLY → [`io::Geometry`]) → `surfel` (leaf disks) → the apps (`spt info`).

// The doc comments are written for the engineers who read the source, and link the
// private items they explain: `cargo doc --document-private-items` renders them.
#![allow(rustdoc::private_intra_doc_links)]

pub mod apps;
pub mod io;
pub mod render;
pub mod surfel;
pub mod tree;
