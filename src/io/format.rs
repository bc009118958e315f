//! What a file format is to the engine. Each format's module (PLY in [`super::ply`],
//! LAS and LAZ in [`super::las`]) implements [`Format`]: whether a file's first bytes
//! are its own, the whole file read into a [`Model`], and the file read a batch of
//! points at a time ([`PointStream`], handing out [`PointBatch`]es).
//! [`super::formats::FORMATS`] lists the formats; adding one is a module that implements
//! the trait and one line there.

use std::path::Path;

use glam::Vec3;

use super::PointAttributes;
use super::geometry::channel;
use super::model::{Model, ModelError};
use super::scalar::Scalar;
use super::up::UpAxis;

/// Hears a read's progress: each call adds that many bytes of the file to those read,
/// and all of them add up to at most its size.
pub type Told<'a> = &'a dyn Fn(u64);

/// How many of a file's first bytes [`Format::recognises`] is shown.
pub const HEAD_BYTES: usize = 16;

/// One file format.
pub trait Format: Sync {
    /// Whether a file whose first bytes are `head` (at most [`HEAD_BYTES`]) is of this
    /// format.
    fn recognises(&self, head: &[u8]) -> bool;

    /// Reads the whole file: its rebased geometry and what the file says of itself,
    /// telling `told` the file's bytes as they are read ([`Told`]).
    fn read(&self, path: &Path, told: Told) -> Result<Model, ModelError>;

    /// Opens the file to be read a batch of points at a time.
    fn stream(&self, path: &Path) -> Result<Box<dyn PointStream>, ModelError>;
}

/// A model file open for reading a batch at a time: points, then (for a mesh)
/// triangles, each in file order.
pub trait PointStream: Send + Sync {
    /// Points (vertex rows) the file declares.
    fn point_count(&self) -> u64;
    /// Whether the file has faces: a mesh.
    fn has_faces(&self) -> bool;
    /// Whether the file gives normals.
    fn has_normals(&self) -> bool;
    /// Whether the points carry LiDAR attributes.
    fn has_attributes(&self) -> bool;
    /// The up axis the file gives ([`crate::io::model::Summary::up`]).
    fn up(&self) -> Option<UpAxis>;
    /// Calls `f` on every batch of points, in file order.
    fn points(&self, f: &mut dyn FnMut(&PointBatch)) -> Result<(), ModelError>;
    /// Whether [`PointStream::points`] decodes on other threads, ahead of `f`.
    fn decodes_ahead(&self) -> bool {
        false
    }
    /// Calls `f` on the positions of rows 0, `stride`, 2 `stride`, … in file order. By
    /// default from a pass over every point; a format whose records lie at known
    /// offsets reads only those.
    fn strided_positions(
        &self,
        stride: u64,
        f: &mut dyn FnMut([f64; 3]),
    ) -> Result<(), ModelError> {
        self.points(&mut every_stride_th(stride, f))
    }
    /// Calls `f` on the triangles, a batch at a time, in file order (none for a cloud).
    fn triangles(&self, f: &mut dyn FnMut(&[[u32; 3]])) -> Result<(), ModelError>;
}

/// What a pass hands each batch to so that `f` gets the positions of rows 0, `stride`,
/// 2 `stride`, … of the whole pass.
pub fn every_stride_th(stride: u64, f: &mut dyn FnMut([f64; 3])) -> impl FnMut(&PointBatch) + '_ {
    let mut row = 0u64;
    move |b| {
        for p in &b.xyz {
            if row.is_multiple_of(stride) {
                f(*p);
            }
            row += 1;
        }
    }
}

/// One batch of points, in file order.
#[derive(Debug, Default, Clone)]
pub struct PointBatch {
    /// Positions as the file gives them.
    pub xyz: Vec<[f64; 3]>,
    /// Colour channels, 16-bit in LAS and LAZ files, 8-bit (already converted) from
    /// PLY; empty when the file has no colours.
    pub rgb: Vec<[u16; 3]>,
    /// Given unit normals (zero where unusable); empty when the file has none (LAS).
    pub normals: Vec<Vec3>,
    /// LiDAR attributes; empty when the file has none (PLY).
    pub attributes: Vec<PointAttributes>,
}

impl PointBatch {
    pub fn clear(&mut self) {
        self.xyz.clear();
        self.rgb.clear();
        self.normals.clear();
        self.attributes.clear();
    }

    /// Makes this batch rows `rows` of `from`.
    pub fn copy_rows(&mut self, from: &PointBatch, rows: std::ops::Range<usize>) {
        fn copy<T: Clone>(to: &mut Vec<T>, from: &[T], rows: std::ops::Range<usize>) {
            to.clear();
            if !from.is_empty() {
                to.extend_from_slice(&from[rows]);
            }
        }
        copy(&mut self.xyz, &from.xyz, rows.clone());
        copy(&mut self.rgb, &from.rgb, rows.clone());
        copy(&mut self.normals, &from.normals, rows.clone());
        copy(&mut self.attributes, &from.attributes, rows);
    }

    /// Point `i`'s colour as RGBA8, converted as the whole-file reader converts it
    /// ([`crate::io::geometry`]'s channels: 8-bit values as they are, 16-bit ones
    /// over 257); `None` when the file has no colours.
    pub fn color(&self, i: usize, eight_bit: bool) -> Option<[u8; 4]> {
        let scalar = if eight_bit { Scalar::U8 } else { Scalar::U16 };
        let c = self.rgb.get(i)?.map(|v| channel(f64::from(v), scalar));
        Some([c[0], c[1], c[2], 255])
    }

    /// Point `i`'s attributes (the defaults when the file has none).
    pub fn attributes(&self, i: usize) -> PointAttributes {
        self.attributes.get(i).copied().unwrap_or_default()
    }
}
