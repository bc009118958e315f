//! Files known by their size and xxh3-64 checksum: a job's inputs in the manifest, a
//! part in its record. A file whose bytes differ is refused, with both sizes and
//! checksums in the error.

use std::path::Path;

use serde::{Deserialize, Serialize};
use xxhash_rust::xxh3::Xxh3;

/// A file of the job directory (a job's input, or a part), by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileEntry {
    /// What the file holds: `own`, `halo`, `own_normals`, `halo_normals`, `tri`, `part`.
    pub role: String,
    pub name: String,
    pub bytes: u64,
    /// xxh3-64 of its bytes, 16 hex digits.
    pub xxh3: String,
}

/// The size and xxh3-64 of the file at `path`, read a MiB at a time.
pub fn checksum(path: &Path) -> std::io::Result<(u64, String)> {
    use std::io::Read;
    let mut file = std::fs::File::open(path)?;
    let mut hash = Xxh3::new();
    let mut buffer = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buffer)?;
        if n == 0 {
            break;
        }
        hash.update(&buffer[..n]);
        bytes += n as u64;
    }
    Ok((bytes, format!("{:016x}", hash.digest())))
}

/// The entry of the file `name` in `dir`, with its size and checksum.
pub fn entry(dir: &Path, role: &str, name: &str) -> std::io::Result<FileEntry> {
    let (bytes, xxh3) = checksum(&dir.join(name))?;
    Ok(FileEntry {
        role: role.to_owned(),
        name: name.to_owned(),
        bytes,
        xxh3,
    })
}

/// Checks that the file of `entry` in `dir` has its bytes: an error names the file, and
/// what it holds against what the manifest says.
pub fn verify(dir: &Path, entry: &FileEntry) -> anyhow::Result<()> {
    let path = dir.join(&entry.name);
    let (bytes, xxh3) = checksum(&path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    anyhow::ensure!(
        bytes == entry.bytes && xxh3 == entry.xxh3,
        "{}: damaged: {bytes} bytes with checksum {xxh3}, where the plan wrote {} bytes \
         with checksum {}",
        path.display(),
        entry.bytes,
        entry.xxh3
    );
    Ok(())
}
