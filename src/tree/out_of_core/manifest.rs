//! The plan of an out-of-core build as a file, `manifest.json` in the job directory:
//! what every step reads ([`super::plan`], [`super::run_job`], [`super::join`]), so
//! that the steps can run as separate processes on machines that share the directory
//! (docs/cluster.md).
//!
//! It holds the model's shared values ([`Model`]), the split (the top tree's shape), and
//! per job its box, its point count and its input files, each with its size and xxh3
//! checksum ([`FileEntry`]): a job refuses an input whose bytes differ. [`BuildParams`] are what every
//! part must be built with; the join may change them (a larger error scale, a mesh
//! turned the other way) and then asks for every part again.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::checksums::FileEntry;
use super::job::Model;
use super::spill::Split;
use crate::io::atomic::write_atomically;

/// The manifest's file name in the job directory.
pub const MANIFEST: &str = "manifest.json";
/// The manifest's format; a directory planned by another format is planned again.
pub const FORMAT: u32 = 1;

/// What every part must be built with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BuildParams {
    /// The model's error scale ([`Model::error_scale`]).
    pub error_scale: f32,
    /// A mesh's normals negated (the orientation vote, [`super::mesh_job`]).
    pub turn: bool,
    /// How many times the join asked for the parts again.
    pub round: u32,
}

/// One job: its box of grid cells, its own points, its input files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobEntry {
    pub lo: [i32; 3],
    pub hi: [i32; 3],
    pub points: u64,
    pub files: Vec<FileEntry>,
}

impl JobEntry {
    /// The path of its file of `role`, if it has one.
    pub fn file(&self, dir: &Path, role: &str) -> Option<PathBuf> {
        (self.files.iter().find(|f| f.role == role)).map(|f| dir.join(&f.name))
    }
}

/// The input file and what its scan found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Input {
    pub path: PathBuf,
    pub bytes: u64,
    /// Its modification time, in nanoseconds since the Unix epoch (0 where unknown).
    pub modified: u64,
    /// Points kept, dropped (not finite, or beyond reach) and kept outside the core.
    pub points: u64,
    pub dropped: u64,
    pub outliers: u64,
    /// A mesh (its jobs carry triangles).
    pub mesh: bool,
    /// The mesh's mean vertex relative to the origin: the centre of its orientation vote.
    pub vote_centre: [f64; 3],
    /// The orientation the parts were first built with (the plan's whole vote).
    pub turn_guess: bool,
}

/// The plan of an out-of-core build.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: u32,
    pub input: Input,
    /// Points per job at most, as planned.
    pub job_points: u64,
    pub model: Model,
    /// The split in pre-order: −1 for a node (its two halves follow), else a job.
    pub split: Vec<i64>,
    pub jobs: Vec<JobEntry>,
    pub build: BuildParams,
}

impl Manifest {
    pub fn path(dir: &Path) -> PathBuf {
        dir.join(MANIFEST)
    }

    /// Reads and checks the manifest of `dir`: its format, its split, its file names.
    pub fn read(dir: &Path) -> anyhow::Result<Manifest> {
        let path = Manifest::path(dir);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            anyhow::anyhow!(
                "{}: {e} (plan the build first: `spt jobs plan INPUT {}`)",
                path.display(),
                dir.display()
            )
        })?;
        let m: Manifest = serde_json::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: not a job manifest: {e}", path.display()))?;
        m.check()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        Ok(m)
    }

    fn check(&self) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.format == FORMAT,
            "format {} (this spt reads {FORMAT}): plan again",
            self.format
        );
        anyhow::ensure!(!self.jobs.is_empty(), "no job");
        self.split_tree()?;
        for (j, job) in self.jobs.iter().enumerate() {
            anyhow::ensure!(job.points > 0, "job {j} has no point");
            for f in &job.files {
                let plain = Path::new(&f.name).file_name() == Some(f.name.as_ref());
                anyhow::ensure!(plain, "job {j}: file name {:?} is not a plain name", f.name);
            }
        }
        Ok(())
    }

    /// Writes the manifest into `dir`, atomically.
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(self)?;
        let path = Manifest::path(dir);
        Ok(write_atomically(&path, |w| w.write_all(text.as_bytes()))?)
    }

    /// The split as a tree, checked: every job once.
    pub fn split_tree(&self) -> anyhow::Result<Split> {
        let mut seen = vec![false; self.jobs.len()];
        let mut codes = self.split.iter();
        let tree = decode(&mut codes, &mut seen, 0)?;
        anyhow::ensure!(codes.next().is_none(), "the split has codes past its end");
        anyhow::ensure!(seen.iter().all(|&s| s), "the split misses a job");
        Ok(tree)
    }

    /// The plan's identity: a hash of everything but the build parameters. A part
    /// records it, so that a part of another plan in the same directory is never taken.
    pub fn id(&self) -> String {
        let key = (
            &self.input,
            self.job_points,
            &self.model,
            &self.split,
            &self.jobs,
        );
        let text = serde_json::to_string(&key).unwrap_or_default();
        format!("{:016x}", xxhash_rust::xxh3::xxh3_64(text.as_bytes()))
    }
}

/// The split in pre-order (see [`Manifest::split`]).
pub fn encode(split: &Split, out: &mut Vec<i64>) {
    match split {
        Split::Job(j) => out.push(*j as i64),
        Split::Node(a, b) => {
            out.push(-1);
            encode(a, out);
            encode(b, out);
        }
    }
}

/// Deeper than a 64³ grid's split can be (3 × 63 planes).
const MAX_DEPTH: usize = 3 * 64;

fn decode(
    codes: &mut std::slice::Iter<i64>,
    seen: &mut [bool],
    depth: usize,
) -> anyhow::Result<Split> {
    anyhow::ensure!(depth <= MAX_DEPTH, "the split is deeper than {MAX_DEPTH}");
    match codes.next().copied() {
        None => anyhow::bail!("the split ends early"),
        Some(-1) => {
            let a = decode(codes, seen, depth + 1)?;
            let b = decode(codes, seen, depth + 1)?;
            Ok(Split::Node(Box::new(a), Box::new(b)))
        }
        Some(j) => {
            let slot = usize::try_from(j).ok().and_then(|j| seen.get_mut(j));
            let Some(slot) = slot.filter(|s| !**s) else {
                anyhow::bail!("the split names job {j}: none, or twice");
            };
            *slot = true;
            Ok(Split::Job(j as usize))
        }
    }
}
