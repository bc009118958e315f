//! LAS and LAZ as one of the engine's formats ([`crate::io::format`]): the whole file
//! ([`super::read_las`]) or a batch of points at a time ([`LasBatches`]).

use std::path::{Path, PathBuf};

use super::in_order::{BLOCK, points_in_order};
use super::{LasBatches, read_las_telling};
use crate::io::format::{Format, PointStream, Told};
use crate::io::format::{PointBatch, every_stride_th};
use crate::io::model::{Model, ModelError, Summary};
use crate::io::up::UpAxis;

/// ASPRS LAS 1.0–1.4, and LAZ (LASzip-compressed LAS).
pub struct LasFormat;

impl Format for LasFormat {
    fn recognises(&self, head: &[u8]) -> bool {
        head.starts_with(b"LASF")
    }

    fn read(&self, path: &Path, told: Told) -> Result<Model, ModelError> {
        let m = read_las_telling(path, told)?;
        let kind = if m.summary.compressed { "LAZ" } else { "LAS" };
        let format = format!(
            "{kind} {}, point format {}",
            m.summary.version, m.summary.point_format
        );
        Ok(Model {
            summary: Summary {
                format,
                las: Some(m.summary),
                up: Some(UpAxis::Z),
                ..Summary::default()
            },
            geometry: m.geometry,
            stats: m.stats,
            file_bytes: m.file_bytes,
            load_time: m.load_time,
        })
    }

    fn stream(&self, path: &Path) -> Result<Box<dyn PointStream>, ModelError> {
        let reader = LasBatches::open(path)?;
        Ok(Box::new(LasStream {
            path: path.to_owned(),
            points: reader.point_count(),
            compressed: reader.compressed(),
        }))
    }
}

/// A LAS or LAZ file read a batch at a time: each pass over the points opens it anew.
struct LasStream {
    path: PathBuf,
    points: u64,
    /// LAZ: a seek decodes from its chunk's start, so a strided sample takes a pass.
    compressed: bool,
}

impl LasStream {
    /// The threads that decode a pass ([`points_in_order`]): one per thread of the
    /// pool, at most [`MAX_DECODERS`], for an uncompressed file of more than a block;
    /// None where one reader reads it (a LAZ file's chunks are decoded in parallel by
    /// `laz` instead).
    fn decoders(&self) -> Option<usize> {
        let workers = rayon::current_num_threads().min(MAX_DECODERS);
        (!self.compressed && workers > 1 && self.points > BLOCK).then_some(workers)
    }
}

/// Most threads that decode a LAS file's pass. Each holds at most three batches (a
/// block of two decoded ahead, and the one it decodes), and a batch of 65,536 points
/// takes 2.2 MB (34 bytes a point: positions in f64, colours, attributes): eight hold
/// at most some 55 MB.
const MAX_DECODERS: usize = 8;

impl PointStream for LasStream {
    fn point_count(&self) -> u64 {
        self.points
    }

    fn has_faces(&self) -> bool {
        false
    }

    fn has_normals(&self) -> bool {
        false
    }

    fn has_attributes(&self) -> bool {
        true
    }

    fn up(&self) -> Option<UpAxis> {
        Some(UpAxis::Z)
    }

    fn points(&self, f: &mut dyn FnMut(&PointBatch)) -> Result<(), ModelError> {
        if let Some(workers) = self.decoders() {
            return Ok(points_in_order(&self.path, (workers, BLOCK), f)?);
        }
        let mut batch = PointBatch::default();
        let mut reader = LasBatches::open(&self.path)?;
        while reader.next_batch(&mut batch)? {
            f(&batch);
        }
        Ok(())
    }

    fn decodes_ahead(&self) -> bool {
        self.decoders().is_some()
    }

    fn strided_positions(
        &self,
        stride: u64,
        f: &mut dyn FnMut([f64; 3]),
    ) -> Result<(), ModelError> {
        if self.compressed {
            return self.points(&mut every_stride_th(stride, f));
        }
        Ok(LasBatches::open(&self.path)?.strided(stride, f)?)
    }

    fn triangles(&self, _: &mut dyn FnMut(&[[u32; 3]])) -> Result<(), ModelError> {
        Ok(())
    }
}
