//! Atomic file writes: everything goes to a temporary file beside the target, which is
//! synced and renamed over the target only when complete. A failure at any point leaves
//! no file under the final name, and an existing file there untouched. The
//! temporary file is written to disk as it grows ([`SyncingFile`]), so that the final
//! sync has little left to wait for.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub use super::syncing_file::SyncingFile;

/// The temporary name used while writing `path`.
pub fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// The writer an atomic write's closure gets.
pub type AtomicWriter = BufWriter<SyncingFile>;

/// Like [`write_atomically`], with a writer that can also seek (to fill in a header
/// once what follows it is written).
pub fn write_atomically_seekable<T>(
    path: &Path,
    write: impl FnOnce(&mut AtomicWriter) -> std::io::Result<T>,
) -> std::io::Result<T> {
    let tmp = temporary_path(path);
    let result = (|| {
        let file = SyncingFile::new(File::create(&tmp)?);
        let mut w = BufWriter::with_capacity(1 << 20, file);
        let value = write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?.finish()?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)?;
        Ok(value)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Calls `write` on a buffered writer to a temporary file, then renames it to `path`.
pub fn write_atomically<T>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<T>,
) -> std::io::Result<T> {
    write_atomically_seekable(path, |w| write(w))
}
