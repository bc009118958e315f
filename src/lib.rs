//! spt: a point-based rendering engine.
//!
//! Data flow (see `DESIGN.md` in the project's shared folder):
//! `io` (PLY → [`io::Geometry`]) → `surfel` (leaf disks) → the apps (`spt info`).

pub mod apps;
pub mod io;
pub mod render;
pub mod surfel;
pub mod tree;
