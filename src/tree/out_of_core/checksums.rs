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

/// What a step checks of the files that the steps before it wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Check {
    /// Their sizes and checksums: a job directory that machines and runs share, where a
    /// file may be stale, truncated or damaged (`spt jobs`).
    Checksums,
    /// Their sizes alone: the one process that wrote them moments before (`spt
    /// convert`), where reading every input and part once more only to hash it took
    /// as long as the join itself (the 200 M-point tile's parts are 19 GB).
    Sizes,
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

/// Whether the file at `path` holds what `entry` says, by `check`: an error only where
/// it cannot be read (a missing file does not hold it).
pub fn holds(path: &Path, entry: &FileEntry, check: Check) -> std::io::Result<bool> {
    let found = match check {
        Check::Checksums => checksum(path).map(|(bytes, xxh3)| (bytes, Some(xxh3))),
        Check::Sizes => std::fs::metadata(path).map(|m| (m.len(), None)),
    };
    let (bytes, xxh3) = match found {
        Ok(found) => found,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(e),
    };
    Ok(bytes == entry.bytes && xxh3.is_none_or(|x| x == entry.xxh3))
}

/// Checks that the file of `entry` in `dir` has its bytes, by `check`: an error names
/// the file, and what it holds against what the manifest says.
pub fn verify(dir: &Path, entry: &FileEntry, check: Check) -> anyhow::Result<()> {
    let path = dir.join(&entry.name);
    let io = |e: std::io::Error| anyhow::anyhow!("{}: {e}", path.display());
    // By checksums the file is read once; by sizes it is hashed only to say how it
    // differs.
    if check == Check::Sizes && holds(&path, entry, check).map_err(io)? {
        return Ok(());
    }
    let (bytes, xxh3) = checksum(&path).map_err(io)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_catch_a_truncated_file_and_checksums_a_changed_byte() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a"), b"twelve bytes").unwrap();
        let written = entry(dir.path(), "own", "a").unwrap();
        let path = dir.path().join("a");
        for check in [Check::Sizes, Check::Checksums] {
            assert!(holds(&path, &written, check).unwrap(), "{check:?}");
            assert!(verify(dir.path(), &written, check).is_ok());
        }
        std::fs::write(&path, b"twelve bytez").unwrap();
        assert!(holds(&path, &written, Check::Sizes).unwrap());
        assert!(!holds(&path, &written, Check::Checksums).unwrap());
        std::fs::write(&path, b"twelve").unwrap();
        for check in [Check::Sizes, Check::Checksums] {
            assert!(!holds(&path, &written, check).unwrap(), "{check:?}");
            let refused = verify(dir.path(), &written, check).unwrap_err().to_string();
            assert!(refused.contains("damaged: 6 bytes"), "{refused}");
        }
        std::fs::remove_file(&path).unwrap();
        assert!(!holds(&path, &written, Check::Sizes).unwrap());
        assert!(verify(dir.path(), &written, Check::Sizes).is_err());
    }
}
