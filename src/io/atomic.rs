//! Atomic file writes: everything goes to a temporary file beside the target, which is
//! synced and renamed over the target only when complete. A failure at any point leaves
//! no file under the final name, and an existing file there untouched. The
//! temporary file's writeback starts as it is written ([`SyncingFile`]), so that the
//! final sync has little left to wait for.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The temporary name used while writing `path`.
pub fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Bytes written between two starts of the writeback.
pub(crate) const WRITEBACK_STEP: u64 = 32 << 20;

/// The temporary file of an atomic write: every [`WRITEBACK_STEP`] bytes written past
/// the last start, it starts their writeback ([`start_writeback`]). Seeking back (to
/// fill in a header) starts none.
pub struct SyncingFile {
    file: File,
    /// The write position, and the end of the bytes whose writeback has started.
    position: u64,
    written_back: u64,
}

impl Write for SyncingFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.file.write(buf)?;
        self.position += n as u64;
        if self.position >= self.written_back + WRITEBACK_STEP {
            start_writeback(&self.file, self.written_back..self.position);
            self.written_back = self.position;
        }
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for SyncingFile {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.position = self.file.seek(to)?;
        Ok(self.position)
    }
}

/// The writer an atomic write's closure gets.
pub type AtomicWriter = BufWriter<SyncingFile>;

/// Asks the kernel to start writing the bytes `range` of `file` to disk, without
/// waiting for them (Linux `sync_file_range` with `SYNC_FILE_RANGE_WRITE`; elsewhere
/// nothing). A large file so written as it goes leaves little to its final sync: the
/// Lucy-size mesh's 1.26 GB `.spt`, its writeback started every 32 MB, synced in 1.4 ms
/// instead of 0.48 s, and its write stage took a median 2.83 s instead of 3.27 s (2
/// cores, 2026-11-24). Advisory: errors are the final sync's to report.
fn start_writeback(file: &File, range: std::ops::Range<u64>) {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        let (Ok(offset), Ok(length)) = (
            libc::off64_t::try_from(range.start),
            libc::off64_t::try_from(range.end.saturating_sub(range.start)),
        ) else {
            return;
        };
        // SAFETY: a plain system call on an open descriptor; it reads no memory of ours.
        unsafe {
            libc::sync_file_range(
                file.as_raw_fd(),
                offset,
                length,
                libc::SYNC_FILE_RANGE_WRITE,
            );
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (file, range);
}

/// Like [`write_atomically`], with a writer that can also seek (to fill in a header
/// once what follows it is written).
pub fn write_atomically_seekable<T>(
    path: &Path,
    write: impl FnOnce(&mut AtomicWriter) -> std::io::Result<T>,
) -> std::io::Result<T> {
    let tmp = temporary_path(path);
    let result = (|| {
        let file = SyncingFile {
            file: File::create(&tmp)?,
            position: 0,
            written_back: 0,
        };
        let mut w = BufWriter::with_capacity(1 << 20, file);
        let value = write(&mut w)?;
        let SyncingFile { file, .. } = w.into_inner().map_err(|e| e.into_error())?;
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
