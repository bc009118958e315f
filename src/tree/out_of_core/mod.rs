//! Out-of-core builds (docs/design.md §5, "Chunks"): a model larger than memory turned into
//! an `.spt` file while holding only a bounded part of it, in passes over the input (a
//! LAS, LAZ or PLY cloud, or a PLY mesh, read a batch at a time by
//! [`crate::io::formats::ModelStream`]):
//!
//! ```text
//! scan ─► count per grid cell ─► split into jobs ─► spill to job files ─► build each job ─► top tree, file
//! (bounds)  (64³ cells)        (k-d, ≤ N points)   (own + halo)         (surfels, tree,   (streamed from
//!                                                                          chunks: a part)   the parts)
//! ```
//!
//! A job holds at most N points (from the memory budget, [`Options::job_points`]) and
//! the points of its halo: those of the neighbouring cells within 16 spacings of the
//! sampling of its border ([`halo`]), so that the neighbourhoods of its points near the
//! border see past it.
//! A mesh's jobs get, instead of a halo by distance, exactly the triangles and
//! vertices their surfels read (the two-ring around their border, [`mesh_spill`]),
//! and the model's orientation is voted over every job before any is built
//! ([`mesh_job`]).
//! Each job is built alone from its files ([`job::build`]) into a part file and
//! dropped; the jobs' roots are joined by the top tree of their split, and the file is
//! streamed from the parts ([`assemble`]). Selection needs nothing more: the nodes of
//! every job are chunks of the list (see [`crate::tree::chunks`] for why no hole opens
//! between them).
//!
//! **In steps.** The build is three steps that share only a directory: [`plan::plan`]
//! (scan, count, split, spill, and a [`manifest::Manifest`] naming every job's input
//! files with their checksums), [`run_job::run`] per job (its part file and record), and
//! [`join::join`] (every part checked, the file written). `spt convert` runs them in one
//! process, where each step checks only the sizes of the files the steps before it
//! wrote ([`checksums::Check::Sizes`]); `spt jobs plan|build|join` runs each alone, so
//! that an engine such as Dask can run the jobs on many machines (docs/cluster.md), and
//! each step checks their checksums too.
//!
//! Normals that the file gives are kept, for a cloud's points as for a mesh's vertices.

pub(crate) mod assemble;
pub mod checksums;
pub(crate) mod halo;
pub(crate) mod job;
pub mod join;
mod lanes;
pub mod manifest;
pub(crate) mod mesh_job;
pub(crate) mod mesh_spill;
pub(crate) mod order;
pub mod plan;
mod read_ahead;
pub mod record;
pub mod run_job;
pub(crate) mod spill;
mod write_behind;

use std::path::Path;

use crate::io::heap;
use crate::tree::TreeMeta;
use checksums::Check;
use join::Joined;
pub use lanes::{Behind, in_lanes};
use manifest::Manifest;
pub use read_ahead::AfterRead;

/// Bytes of memory a job takes per point at its peak (its surfels, k-d tree, nodes and
/// list), halo included. Measured on the 200 M-point `gen_cloud` tile's jobs of 6.7 M
/// points: 160, and about 300 with a terrain's averaged normals (each sample's 24
/// neighbours are kept between the fits and their mean, `surfel::cloud`). Its jobs of
/// 12.5 M points peak at 393 (4.58 GiB, docs/cluster.md): such a job takes 57 %
/// of the budget, where [`Options::for_memory`] plans for half.
pub const BYTES_PER_JOB_POINT: u64 = 320;

/// How far the leaves' own error scale may exceed the model's (from the points' box)
/// before the jobs are built again with theirs: errors up to about this many scales fit
/// an f16 (at most 65,504) with room for a tree's depth of sums.
pub const SCALE_SLACK: f32 = 64.0;

/// Jobs that [`build_file`] builds at once, and that [`Options::for_memory`] sizes the
/// jobs to fit the budget together. A job's serial stretches (its triangulations'
/// merges, its files' reads) leave cores idle that a second job fills (its part is
/// written behind it, [`lanes`]): on 2 cores one job at a time kept 1.5 of them busy.
/// Three at a time took as long (12 of the 200 M-point tile's jobs, alternated twice:
/// 50.4 and 50.6 s against 50.5 and 50.7 s, peak 2.50–2.69 against 1.84–1.89 GiB; 2 AMD
/// EPYC cores, 2026-12-03). Fixed, not taken from the core count, so that every machine
/// plans the same jobs.
pub const LANES: usize = 2;

/// How an out-of-core build runs.
#[derive(Debug, Clone)]
pub struct Options {
    /// Points per job at most (a cell of the counting grid holding more is one job).
    pub job_points: u64,
    /// Bytes of write buffers for the spill files, all together.
    pub spill_buffers: u64,
    /// Where the spill and part files go (removed afterwards).
    pub temp_dir: std::path::PathBuf,
}

impl Options {
    /// The options for a budget of `memory` bytes: [`LANES`] jobs together in half the
    /// budget over [`BYTES_PER_JOB_POINT`] (at least 2¹⁶ points each), an eighth of
    /// it for the spill's buffers, the rest for the grid, the parts' roots and the page
    /// cache.
    pub fn for_memory(memory: u64, temp_dir: std::path::PathBuf) -> Options {
        Options {
            job_points: (memory / 2 / LANES as u64 / BYTES_PER_JOB_POINT).max(1 << 16),
            spill_buffers: memory / 8,
            temp_dir,
        }
    }

    /// The budget that plans jobs of `job_points` points: [`Options::for_memory`]'s
    /// inverse (above its floor).
    pub fn budget_of(job_points: u64) -> u64 {
        job_points * 2 * LANES as u64 * BYTES_PER_JOB_POINT
    }
}

/// What a build did.
#[derive(Debug, Clone)]
pub struct Built {
    pub meta: TreeMeta,
    pub jobs: usize,
    /// Points dropped (not finite, or beyond reach of the rest) and outliers kept
    /// ([`spill::Scan`]).
    pub dropped: u64,
    pub outliers: u64,
    /// A terrain's wall surfels, among the leaves ([`crate::surfel::walls`]): each job
    /// finds its own samples' walls among its samples and halo, so near a job's border
    /// they may differ from an in-memory build's.
    pub walls: u64,
    /// A mesh's jobs were built twice: the parts' orientation vote did not decide as
    /// the plan's had ([`mesh_job`]).
    pub rebuilt: bool,
}

/// Hears how a build goes: a stage starts (with its total of points, 0 if unknown),
/// points go by; the next stage's start ends the one before.
pub trait Progress: Sync {
    fn stage(&self, name: &'static str, total: u64);
    fn advance(&self, points: u64);
    /// The join wrote nothing: the jobs are built again, for `reason`
    /// ([`join::Joined::Rebuild`]).
    fn rebuild(&self, _reason: &str) {}
    /// The join starts to write a file of `bytes` bytes: what [`Progress::advance`]
    /// counts from now on is bytes written.
    fn writing(&self, _bytes: u64) {}
}

/// Builds the `.spt` file of the model `input` (a LAS, LAZ or PLY cloud, or a PLY
/// mesh) at `output` within `options`: the three steps in one process, in a temporary
/// job directory. Each job's inputs are removed once its part is built, and the join
/// frees each part's blocks as it copies them, so the directory never holds the inputs,
/// the parts and the file whole together; where the join sends the jobs back, the
/// input is planned again ([`plan::plan_again`]).
pub fn build_file(
    input: &Path,
    output: &Path,
    options: &Options,
    progress: &dyn Progress,
) -> anyhow::Result<Built> {
    let dir = tempfile::Builder::new()
        .prefix("spt-build-")
        .tempdir_in(&options.temp_dir)?;
    plan::plan(input, dir.path(), options, progress)?;
    loop {
        let manifest = Manifest::read(dir.path())?;
        progress.stage("build", manifest.input.points);
        run_jobs(dir.path(), &manifest, progress)?;
        progress.stage("write", 0);
        match join::join(
            dir.path(),
            output,
            (Check::Sizes, AfterRead::Free),
            progress,
        )? {
            Joined::Written(built) => return Ok(built),
            Joined::Rebuild(reason) => {
                progress.rebuild(&reason);
                plan::plan_again(input, dir.path(), options, progress)?;
            }
        }
    }
}

/// Runs every job of `manifest` (in `dir`), [`LANES`] at a time ([`in_lanes`]), the
/// memory each frees given back as [`heap::give_back_freed_memory`] decides, and its
/// inputs removed once it has read them.
fn run_jobs(dir: &Path, manifest: &Manifest, progress: &dyn Progress) -> anyhow::Result<()> {
    let all: Vec<usize> = (0..manifest.jobs.len()).collect();
    in_lanes(&all, &|j, behind| {
        run_job::run_behind(dir, manifest, j, Check::Sizes, behind)?;
        plan::remove_job_inputs(dir, &manifest.jobs[j])?;
        heap::give_back_freed_memory();
        progress.advance(manifest.jobs[j].points);
        Ok(())
    })
}
