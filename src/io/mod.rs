//! Model files in: PLY reading and writing, LAS and LAZ reading ([`model::read_model`]
//! takes any of them; [`stream::ModelStream`] reads any of them a batch at a time), and
//! the rebased [`Geometry`] they produce.
//! This layer imports no other module of the crate (`.spt` files, which hold trees,
//! live in [`crate::tree::spt_file`]).

pub mod atomic;
pub mod bounds;
pub mod geometry;
pub mod las;
pub mod model;
pub mod ply;
pub mod rebase;
pub mod stream;
pub(crate) mod syncing_file;
pub mod torus_knot;
pub mod triangulate;

pub use bounds::Bounds;
pub use geometry::{Geometry, GeometryStats, PointAttributes};
