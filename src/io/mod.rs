//! Model files in: PLY reading and writing, and the rebased [`Geometry`] they produce.
//! This layer imports no other module of the crate (`.spt` files, which hold trees,
//! live in [`crate::tree::spt_file`]).

pub mod atomic;
pub mod geometry;
pub mod ply;
pub mod rebase;

pub use geometry::{Bounds, Geometry, GeometryStats};
