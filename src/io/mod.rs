//! Model files: PLY reading and writing, the rebased [`Geometry`] they produce, and
//! `.spt` files (sequential point trees).

pub mod atomic;
pub mod geometry;
pub mod ply;
pub mod rebase;
pub mod spt_file;

pub use geometry::{Bounds, Geometry, GeometryStats};
