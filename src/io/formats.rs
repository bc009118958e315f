//! The formats the engine reads, and a file read in its own: [`FORMATS`] in the order
//! they are tried, [`format_of`] a file by its first bytes, [`read_model`] the whole
//! file ([`read_model_telling`] with its progress), [`ModelStream`] a batch at a time.

use std::io::Read;
use std::path::Path;

use super::format::{Format, HEAD_BYTES, PointBatch, PointStream, Told};
use super::las::LasFormat;
use super::model::{Model, ModelError};
use super::ply::PlyFormat;
use super::up::UpAxis;

/// Every format the engine reads, in the order they are tried. The last (PLY) also
/// reads any file that no format recognises, and its reader says what is wrong with it.
pub const FORMATS: &[&dyn Format] = &[&LasFormat, &PlyFormat];

/// The format of the file at `path`, from its first bytes.
pub fn format_of(path: &Path) -> Result<&'static dyn Format, ModelError> {
    let mut head = Vec::with_capacity(HEAD_BYTES);
    std::fs::File::open(path)
        .and_then(|f| f.take(HEAD_BYTES as u64).read_to_end(&mut head))
        .map_err(|e| ModelError::io(path, &e))?;
    let last = *FORMATS.last().expect("a format");
    Ok(FORMATS
        .iter()
        .copied()
        .find(|f| f.recognises(&head))
        .unwrap_or(last))
}

/// Reads a model file of any format the engine reads, by its first bytes (a file that
/// no format recognises is read as PLY, whose reader says what is wrong with it).
pub fn read_model(path: &Path) -> Result<Model, ModelError> {
    read_model_telling(path, &|_| {})
}

/// [`read_model`], telling `told` the file's bytes as they are read.
pub fn read_model_telling(path: &Path, told: Told) -> Result<Model, ModelError> {
    format_of(path)?.read(path, told)
}

/// Batches a [`ModelStream::points_ahead`] pass decodes ahead of its consumer.
pub const BATCHES_AHEAD: usize = 2;
/// Most points of a batch that [`ModelStream::points_ahead`] hands on: a LAZ file's
/// batches of a million points, held ahead whole, had raised the peak of a 20 M-point
/// LAZ file's plan at `--memory 512` from 147 to 255 MB.
pub const POINTS_AHEAD_BATCH: usize = 1 << 16;

/// A model file open for reading a batch at a time, whatever its format.
pub struct ModelStream(Box<dyn PointStream>);

impl ModelStream {
    /// Opens `path` in its format ([`format_of`]).
    pub fn open(path: &Path) -> Result<ModelStream, ModelError> {
        Ok(ModelStream(format_of(path)?.stream(path)?))
    }

    /// Points (vertex rows) the file declares.
    pub fn point_count(&self) -> u64 {
        self.0.point_count()
    }

    /// Whether the file has faces: a mesh.
    pub fn has_faces(&self) -> bool {
        self.0.has_faces()
    }

    /// Whether the file gives normals (PLY's `nx ny nz`).
    pub fn has_normals(&self) -> bool {
        self.0.has_normals()
    }

    /// Whether the points carry LiDAR attributes (LAS and LAZ).
    pub fn has_attributes(&self) -> bool {
        self.0.has_attributes()
    }

    /// The up axis the file gives ([`crate::io::model::Summary::up`]).
    pub fn up(&self) -> Option<UpAxis> {
        self.0.up()
    }

    /// Calls `f` on every batch of points, in file order.
    pub fn points(&self, mut f: impl FnMut(&PointBatch)) -> Result<(), ModelError> {
        self.0.points(&mut f)
    }

    /// As [`ModelStream::points`], with the file decoded on another thread up to
    /// [`BATCHES_AHEAD`] batches ahead of `f`, in batches of at most
    /// [`POINTS_AHEAD_BATCH`] points: for a pass whose own work per point weighs as
    /// much as the decoding. A format that decodes ahead itself
    /// ([`PointStream::decodes_ahead`]) is read as it is.
    pub fn points_ahead(&self, mut f: impl FnMut(&PointBatch)) -> Result<(), ModelError> {
        if self.0.decodes_ahead() {
            return self.points(f);
        }
        use std::sync::mpsc::{channel, sync_channel};
        let (full, decoded) = sync_channel::<PointBatch>(BATCHES_AHEAD);
        let (used, recycled) = channel::<PointBatch>();
        std::thread::scope(|scope| {
            // The LAZ decoder's deep stack (`las::DECODER_STACK`); without a thread, the
            // caller's decodes.
            let decoder = std::thread::Builder::new().stack_size(crate::io::las::DECODER_STACK);
            let spawned = decoder.spawn_scoped(scope, move || {
                self.0.points(&mut |b| {
                    for start in (0..b.xyz.len()).step_by(POINTS_AHEAD_BATCH) {
                        let mut copy = recycled.try_recv().unwrap_or_default();
                        copy.copy_rows(b, start..(start + POINTS_AHEAD_BATCH).min(b.xyz.len()));
                        // Refused only once `f` has panicked: the pass then runs out unread.
                        let _ = full.send(copy);
                    }
                })
            });
            let Ok(decoder) = spawned else {
                return self.points(&mut f);
            };
            for batch in decoded {
                f(&batch);
                let _ = used.send(batch);
            }
            decoder
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p))
        })
    }

    /// Calls `f` on the positions of rows 0, `stride` (at least 1), 2 `stride`, … in
    /// file order, reading only those where the format allows.
    pub fn strided_positions(
        &self,
        stride: u64,
        mut f: impl FnMut([f64; 3]),
    ) -> Result<(), ModelError> {
        self.0.strided_positions(stride.max(1), &mut f)
    }

    /// Calls `f` on the triangles, a batch at a time, in file order (none for a cloud).
    pub fn triangles(&self, mut f: impl FnMut(&[[u32; 3]])) -> Result<(), ModelError> {
        self.0.triangles(&mut f)
    }
}
