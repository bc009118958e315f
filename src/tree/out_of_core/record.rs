//! A built job's record, `job{j}.part.json` beside its part file `job{j}.part`: what the
//! join needs of the part ([`Part`]), the part file's size and checksum, and what it was
//! built from (the plan's id and the [`BuildParams`]). The part file is written first and
//! the record last, both atomically: a record names a whole part, and a job whose record
//! is missing, stale or does not match its part's bytes is built again.

use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::checksums::{Check, FileEntry, holds};
use super::job::Part;
use super::manifest::BuildParams;
use crate::io::PointAttributes;
use crate::io::atomic::write_atomically;
use crate::surfel::outward::Vote;

/// A built job's record.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PartRecord {
    pub job: usize,
    /// The id of the plan it was built from ([`super::manifest::Manifest::id`]).
    pub plan: String,
    pub built_with: BuildParams,
    pub file: FileEntry,
    pub part: Part,
    /// A mesh job's terms of the orientation vote.
    pub vote: Option<Vote>,
}

/// The part file's name of job `j`.
pub fn part_name(j: usize) -> String {
    format!("job{j}.part")
}

/// The record's name of job `j`.
pub fn record_name(j: usize) -> String {
    format!("job{j}.part.json")
}

fn record_path(dir: &Path, j: usize) -> PathBuf {
    dir.join(record_name(j))
}

impl PartRecord {
    /// Writes the record into `dir`, atomically.
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        let text = serde_json::to_string(self)?;
        let path = record_path(dir, self.job);
        Ok(write_atomically(&path, |w| w.write_all(text.as_bytes()))?)
    }

    /// The record of job `j` in `dir`; `None` when it has none.
    pub fn read(dir: &Path, j: usize) -> anyhow::Result<Option<PartRecord>> {
        let path = record_path(dir, j);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => anyhow::bail!("{}: {e}", path.display()),
        };
        let mut r: PartRecord = serde_json::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: not a part record: {e}", path.display()))?;
        anyhow::ensure!(
            r.job == j && r.file.name == part_name(j),
            "{}: the record of another job",
            path.display()
        );
        r.part.path = dir.join(&r.file.name);
        Ok(Some(r))
    }

    /// Whether its part file holds the bytes it says, by `check`.
    pub fn part_intact(&self, check: Check) -> std::io::Result<bool> {
        holds(&self.part.path, &self.file, check)
    }

    /// Its part with the intensity sample read from the part file's end.
    pub fn into_part(mut self) -> anyhow::Result<Part> {
        let n = self.part.intensity_count as usize;
        let size = std::mem::size_of::<PointAttributes>() as u64;
        let mut file = std::fs::File::open(&self.part.path)?;
        file.seek(SeekFrom::Start(
            self.file.bytes.saturating_sub(n as u64 * size),
        ))?;
        let mut sample = vec![PointAttributes::default(); n];
        file.read_exact(bytemuck::cast_slice_mut(&mut sample))
            .map_err(|e| anyhow::anyhow!("{}: {e}", self.part.path.display()))?;
        self.part.intensities = sample;
        Ok(self.part)
    }
}

/// Serde for a part's root, as the hex of its records' bytes.
pub mod root_hex {
    use serde::{Deserialize, Deserializer, Serializer};

    use crate::io::PointAttributes;
    use crate::surfel::shape::SplatShape;
    use crate::tree::NodeRecord;

    type Root = (NodeRecord, SplatShape, PointAttributes);

    fn sizes() -> [usize; 3] {
        use std::mem::size_of;
        let r = size_of::<NodeRecord>();
        [
            r,
            r + size_of::<SplatShape>(),
            r + size_of::<SplatShape>() + size_of::<PointAttributes>(),
        ]
    }

    pub fn serialize<S: Serializer>(root: &Root, s: S) -> Result<S::Ok, S::Error> {
        let mut bytes = bytemuck::bytes_of(&root.0).to_vec();
        bytes.extend_from_slice(bytemuck::bytes_of(&root.1));
        bytes.extend_from_slice(bytemuck::bytes_of(&root.2));
        let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        s.serialize_str(&hex)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Root, D::Error> {
        use serde::de::Error;
        let hex = String::deserialize(d)?;
        let [a, b, c] = sizes();
        if hex.len() != 2 * c || !hex.is_ascii() {
            return Err(D::Error::custom(format!(
                "a root of {} hex digits",
                hex.len()
            )));
        }
        let bytes = (0..c)
            .map(|k| u8::from_str_radix(&hex[2 * k..2 * k + 2], 16))
            .collect::<Result<Vec<u8>, _>>()
            .map_err(D::Error::custom)?;
        Ok((
            bytemuck::pod_read_unaligned(&bytes[..a]),
            bytemuck::pod_read_unaligned(&bytes[a..b]),
            bytemuck::pod_read_unaligned(&bytes[b..c]),
        ))
    }
}
