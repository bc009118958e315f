//! A model file read, whatever its format, as one [`Model`]: the rebased geometry and
//! what the format says of the file ([`Summary`]); or why it could not be read
//! ([`ModelError`]).

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Serialize;

use super::las::{LasError, LasSummary};
use super::ply::PlyError;
use super::up::UpAxis;
use super::{Geometry, GeometryStats};

/// What a file says of itself, in terms every format fills (those a format does not
/// have stay empty).
#[derive(Debug, Clone, Default)]
pub struct Summary {
    /// The format, its encoding and version: `PLY binary_little_endian 1.0`,
    /// `LAZ 1.4, point format 6`.
    pub format: String,
    /// Free-text comments of the header.
    pub comments: Vec<String>,
    /// PLY's `obj_info` lines.
    pub obj_info: Vec<String>,
    /// The file's elements (a PLY file's `element` lines) as declared.
    pub elements: Vec<ElementSummary>,
    /// Elements the reader skips (neither the vertices nor the faces it reads).
    pub skipped_elements: Vec<String>,
    /// What a LAS or LAZ file says of itself (software, counts by class and return,
    /// scale, offset, CRS).
    pub las: Option<LasSummary>,
    /// The up axis the file gives: z for LAS and LAZ, a PLY header's comment's
    /// ([`UpAxis::from_comments`]); `None` when it gives none.
    pub up: Option<UpAxis>,
}

/// One element of a file: its name, row count and property declarations.
#[derive(Debug, Clone, Serialize)]
pub struct ElementSummary {
    pub name: String,
    pub count: u64,
    pub properties: Vec<String>,
}

/// A model file read.
#[derive(Debug, Clone)]
pub struct Model {
    pub summary: Summary,
    pub geometry: Geometry,
    pub stats: GeometryStats,
    pub file_bytes: u64,
    pub load_time: Duration,
}

/// A model file that cannot be read; every variant names the file.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ModelError {
    #[error(transparent)]
    Ply(#[from] PlyError),
    #[error(transparent)]
    Las(#[from] LasError),
    #[error("{}: cannot read: {message}", path.display())]
    Io { path: PathBuf, message: String },
    /// A valid file without points: `spt info` describes it, nothing else has anything
    /// to do with it.
    #[error("{}: the file holds no points: nothing to draw", path.display())]
    Empty { path: PathBuf },
}

impl ModelError {
    /// The file at `path` could not be read: `error`.
    pub fn io(path: &Path, error: &std::io::Error) -> ModelError {
        ModelError::Io {
            path: path.to_owned(),
            message: error.to_string(),
        }
    }
}

impl Model {
    /// The model read, or [`ModelError::Empty`] when it has no vertex to draw.
    pub fn drawable(self, path: &Path) -> Result<Model, ModelError> {
        if self.geometry.positions.is_empty() {
            return Err(ModelError::Empty {
                path: path.to_owned(),
            });
        }
        Ok(self)
    }
}
