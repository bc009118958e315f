//! Model files in: the formats ([`formats::FORMATS`]: PLY, LAS and LAZ) fill one
//! format-neutral row model ([`rows`]), from which the rebased [`Geometry`] is built;
//! [`formats::read_model`] reads a whole file of any of them, [`formats::ModelStream`] a
//! batch at a time. Also PLY writing, PNG writing, and atomic writes.
//! This layer imports no other module of the crate (`.spt` files, which hold trees,
//! live in [`crate::tree::spt_file`]).

pub mod atomic;
pub(crate) mod bounds;
pub mod delaunay;
pub(crate) mod direct;
pub mod disk_space;
pub mod format;
pub mod formats;
pub(crate) mod geometry;
pub mod heap;
pub mod las;
pub mod model;
pub mod parallel;
pub mod ply;
pub mod png;
pub mod rebase;
pub mod release;
pub(crate) mod rows;
pub mod scalar;
pub(crate) mod syncing_file;
pub mod torus_knot;
pub mod triangulate;
pub mod up;

pub use bounds::Bounds;
pub use geometry::{Geometry, GeometryStats, PointAttributes};
