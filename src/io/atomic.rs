//! Atomic file writes: everything goes to a temporary file beside the target, which is
//! synced and renamed over the target only when complete. A failure at any point leaves
//! no file under the final name, and an existing file there untouched. The
//! temporary file is written to disk as it grows ([`SyncingFile`]), so that the final
//! sync has little left to wait for. Every error names the target: "cannot write
//! PATH: " and the cause (a full disk, a missing directory, or the closure's own).

use std::fs::File;
use std::io::{BufWriter, ErrorKind, Write};
use std::path::{Path, PathBuf};

pub use super::syncing_file::SyncingFile;

/// The temporary name used while writing `path`: its name, this process's id and a
/// token drawn once per process from the clock, so that processes on machines sharing
/// a directory (whose ids may coincide) never write the same temporary file.
pub fn temporary_path(path: &Path) -> PathBuf {
    static TOKEN: std::sync::OnceLock<u32> = std::sync::OnceLock::new();
    let token = TOKEN.get_or_init(|| {
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH);
        let nanos = now.map_or(0, |d| d.as_nanos());
        let key = (nanos, std::process::id(), std::thread::current().id());
        xxhash_rust::xxh3::xxh3_64(format!("{key:?}").as_bytes()) as u32
    });
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}-{token:08x}", std::process::id()))
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
    result.map_err(|e: std::io::Error| {
        let _ = std::fs::remove_file(&tmp);
        std::io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))
    })
}

/// Calls `write` on a buffered writer to a temporary file, then renames it to `path`.
pub fn write_atomically<T>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<T>,
) -> std::io::Result<T> {
    write_atomically_seekable(path, |w| write(w))
}

/// Checks, before any work is done, that [`write_atomically`] can write `path`: it is not
/// a directory, not the same file as any of `inputs` (whatever the path that names it:
/// a command never replaces what it reads), and its directory exists and takes a new
/// file (the temporary one is made there and removed). The errors read as the write's
/// own: "cannot write PATH: " and why.
pub fn check_writable(path: &Path, inputs: &[&Path]) -> std::io::Result<()> {
    let fail = |kind, why: String| {
        std::io::Error::new(kind, format!("cannot write {}: {why}", path.display()))
    };
    if path.is_dir() {
        return Err(fail(ErrorKind::IsADirectory, "it is a directory".into()));
    }
    if let Some(input) = inputs
        .iter()
        .find(|i| same_file::is_same_file(path, i).unwrap_or(false))
    {
        let why = format!(
            "it is the input {}, which the output would replace; name another file",
            input.display()
        );
        return Err(fail(ErrorKind::AlreadyExists, why));
    }
    let dir = folder_of(path);
    if !dir.is_dir() {
        let what = if dir.exists() {
            "is not a directory"
        } else {
            "does not exist"
        };
        return Err(fail(
            ErrorKind::NotFound,
            format!("{} {what}", dir.display()),
        ));
    }
    let probe = temporary_path(path);
    let made = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe);
    match made {
        Ok(_) => std::fs::remove_file(&probe).map_err(|e| fail(e.kind(), e.to_string())),
        // A temporary file of this process is already there: the directory takes files.
        Err(e) if e.kind() == ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(fail(e.kind(), e.to_string())),
    }
}

/// The folder a file is written in: its parent, or "." for a bare name.
pub fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}
