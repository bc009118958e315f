//! Model files in: PLY reading and writing, and the rebased [`Geometry`] they produce.

pub mod geometry;
pub mod ply;

pub use geometry::{Bounds, Geometry, GeometryStats};
