//! spt: a point-based rendering engine: sequential point trees for level of detail and
//! three-pass deferred EWA splatting (`docs/design.md`).
//!
//! Data flow, and the layers, each importing only those to its right:
//!
//! ```text
//! apps ─► eval ─► render ─► tree ─► surfel ─► io
//! ```
//!
//! [`io`] reads PLY, LAS and LAZ into rebased [`io::Geometry`]; [`surfel`] makes a leaf
//! splat per sample; [`tree`] builds the hierarchy, its errors and the sorted list, and
//! reads and writes `.spt` files; [`render`] draws a [`tree::scene::Scene`] with wgpu,
//! headless or into a window's surface. With the `eval` feature, [`eval`] scores images
//! against a reference; with `apps` (the default), [`apps`] holds the `spt` commands and
//! the viewer.

// The doc comments are written for the engineers who read the source, and link the
// private items they explain: `cargo doc --document-private-items` renders them.
#![allow(rustdoc::private_intra_doc_links)]

#[cfg(feature = "apps")]
pub mod apps;
#[cfg(feature = "eval")]
pub mod eval;
pub mod io;
pub mod render;
pub mod surfel;
pub mod tree;
