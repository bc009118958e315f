//! A model file read a batch at a time, whatever its format, for builders that never
//! hold a whole file ([`crate::tree::out_of_core`]): LAS and LAZ through
//! [`LasBatches`], PLY through [`PlyStream`] (its vertex rows as points, its faces as
//! triangles).

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::PointAttributes;
use super::geometry::channel;
use super::las::LasBatches;
use super::model::{ModelError, is_las_file};
use super::ply::{PlyStream, Scalar};

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

/// A model file open for reading a batch at a time.
pub enum ModelStream {
    Las { path: PathBuf, points: u64 },
    Ply(Box<PlyStream>),
}

impl ModelStream {
    /// Opens `path`: LAS and LAZ by their magic `LASF`, anything else as PLY.
    pub fn open(path: &Path) -> Result<ModelStream, ModelError> {
        Ok(if is_las_file(path)? {
            let points = LasBatches::open(path)?.point_count();
            ModelStream::Las {
                path: path.to_owned(),
                points,
            }
        } else {
            ModelStream::Ply(Box::new(PlyStream::open(path)?))
        })
    }

    /// Points (vertex rows) the file declares.
    pub fn point_count(&self) -> u64 {
        match self {
            ModelStream::Las { points, .. } => *points,
            ModelStream::Ply(p) => p.vertex_count(),
        }
    }

    /// Whether the file has faces: a mesh.
    pub fn has_faces(&self) -> bool {
        matches!(self, ModelStream::Ply(p) if p.has_faces())
    }

    /// Whether the file gives normals (PLY's `nx ny nz`).
    pub fn has_normals(&self) -> bool {
        matches!(self, ModelStream::Ply(p) if p.has_normals())
    }

    /// Whether the points carry LiDAR attributes (LAS and LAZ).
    pub fn has_attributes(&self) -> bool {
        matches!(self, ModelStream::Las { .. })
    }

    /// Calls `f` on every batch of points, in file order.
    pub fn points(&self, mut f: impl FnMut(&PointBatch)) -> Result<(), ModelError> {
        let mut batch = PointBatch::default();
        match self {
            ModelStream::Las { path, .. } => {
                let mut reader = LasBatches::open(path)?;
                while reader.next_batch(&mut batch)? {
                    f(&batch);
                }
            }
            ModelStream::Ply(p) => p.vertices(|v| {
                batch.clear();
                batch.xyz.extend_from_slice(&v.xyz);
                batch.normals.extend_from_slice(&v.normals);
                batch
                    .rgb
                    .extend(v.colors.iter().map(|c| [c[0], c[1], c[2]].map(u16::from)));
                f(&batch);
            })?,
        }
        Ok(())
    }

    /// Calls `f` on the triangles, a batch at a time, in file order (none for LAS).
    pub fn triangles(&self, f: impl FnMut(&[[u32; 3]])) -> Result<(), ModelError> {
        if let ModelStream::Ply(p) = self {
            p.triangles(f)?;
        }
        Ok(())
    }
}
