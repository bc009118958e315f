//! A model file of any format the engine reads (PLY, LAS, LAZ), told apart by its first
//! bytes, as one [`Model`]: the rebased geometry and what the format says of itself.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::las::{LasError, LasSummary, is_las, read_las};
use super::ply::header::Header;
use super::ply::{PlyError, read_ply};
use super::{Geometry, GeometryStats};

/// What the file's format says of it.
#[derive(Debug, Clone)]
pub enum Source {
    Ply(Header),
    Las(Box<LasSummary>),
}

/// A model file read.
#[derive(Debug, Clone)]
pub struct Model {
    pub source: Source,
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
}

/// Whether `path` is a LAS or LAZ file (it starts with `LASF`): the other files are
/// read as PLY.
pub fn is_las_file(path: &Path) -> Result<bool, ModelError> {
    let mut magic = [0u8; 4];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut magic))
        .map_err(|e| ModelError::Io {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
    Ok(is_las(&magic[..n]))
}

/// Reads a PLY, LAS or LAZ file (LAS and LAZ start with `LASF`; anything else is read
/// as PLY, whose reader says what is wrong with a file that is neither).
pub fn read_model(path: &Path) -> Result<Model, ModelError> {
    if is_las_file(path)? {
        let m = read_las(path)?;
        return Ok(Model {
            source: Source::Las(Box::new(m.summary)),
            geometry: m.geometry,
            stats: m.stats,
            file_bytes: m.file_bytes,
            load_time: m.load_time,
        });
    }
    let m = read_ply(path)?;
    Ok(Model {
        source: Source::Ply(m.header),
        geometry: m.geometry,
        stats: m.stats,
        file_bytes: m.file_bytes,
        load_time: m.load_time,
    })
}
