//! `spt jobs plan|build|join`: the three steps of an out-of-core build
//! ([`crate::tree::out_of_core`]) as separate commands over a job directory that every
//! machine sees, for a cluster's engine to run (docs/cluster.md; `tools/cluster/`).
//! `spt convert --out-of-core` runs the same steps in one process.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Subcommand;

use crate::apps::convert_large::{Bars, keep_freed_memory_within, options, summary};
use crate::apps::disk;
use crate::apps::stats::peak_memory_bytes;
use crate::apps::text::count;
use crate::tree::out_of_core::AfterRead;
use crate::tree::out_of_core::checksums::Check;
use crate::tree::out_of_core::join::{Joined, join};
use crate::tree::out_of_core::manifest::Manifest;
use crate::tree::out_of_core::plan::{Planned, plan};
use crate::tree::out_of_core::run_job::{Ran, run_behind};
use crate::tree::out_of_core::{Options, Progress, in_lanes};

/// Exit status of `spt jobs join` when the parts must be built again: the manifest now
/// holds the new build parameters; build every job again, then join.
pub const REBUILD_STATUS: u8 = 3;

/// `spt jobs join` found that the parts must be built again (exit status
/// [`REBUILD_STATUS`]).
#[derive(Debug, thiserror::Error)]
#[error("{0}: the manifest now asks for it; build every job again, then join")]
pub struct RebuildNeeded(pub String);

#[derive(Subcommand)]
pub enum JobsCommand {
    /// Scans the model, splits it into jobs within the memory budget and spills each
    /// job's points into DIR, with `manifest.json` naming every job's input files,
    /// sizes and checksums. Keeps DIR's plan when it is of the same input and budget.
    Plan {
        /// The model: a PLY, LAS or LAZ file.
        input: PathBuf,
        /// The job directory, seen by every machine that builds a job.
        dir: PathBuf,
        /// Memory budget of one job's machine in MiB (default: half of this machine's
        /// memory). `spt convert --out-of-core` with the same budget makes the same file.
        #[arg(long, value_name = "MIB")]
        memory: Option<u64>,
    },
    /// Builds jobs of DIR's plan (all, when none is named), two at a time, each into its
    /// part file `jobN.part` and record `jobN.part.json`, written atomically. A job already built
    /// for this plan, whole, is kept; a job's input that differs from its checksum is
    /// refused. The same job gives the same bytes wherever it runs.
    Build {
        /// The job directory that `spt jobs plan` wrote.
        dir: PathBuf,
        /// Job numbers (0 to jobs − 1).
        jobs: Vec<usize>,
    },
    /// Checks every part against its record and the plan, and writes the .spt file
    /// atomically. Exits 3 when the parts must be built again with new parameters
    /// (a larger error scale, a mesh's orientation), which the manifest then holds.
    Join {
        /// The job directory, every job built.
        dir: PathBuf,
        /// The .spt file to write (replaced if it exists).
        output: PathBuf,
        /// Remove the job directory's files (manifest, inputs, parts) once written.
        #[arg(long)]
        clean: bool,
    },
}

pub fn run(command: &JobsCommand) -> anyhow::Result<()> {
    match command {
        JobsCommand::Plan { input, dir, memory } => run_plan(input, dir, *memory),
        JobsCommand::Build { dir, jobs } => run_build(dir, jobs),
        JobsCommand::Join { dir, output, clean } => run_join(dir, output, *clean),
    }
}

fn run_plan(input: &Path, dir: &Path, memory: Option<u64>) -> anyhow::Result<()> {
    let memory = memory.map_or_else(crate::apps::convert_large::default_memory, |m| m << 20);
    let options = options(dir, memory);
    let points = crate::io::formats::ModelStream::open(input)?.point_count();
    let needed = points.saturating_mul(disk::OUT_OF_CORE_BYTES_PER_POINT);
    disk::say_room(dir, needed, "the job inputs and parts", true);
    let bars = Bars::default();
    let planned = plan(input, dir, &options, &bars)?;
    bars.finish();
    let m = planned.manifest();
    let bytes: u64 = (m.jobs.iter().flat_map(|j| &j.files))
        .map(|f| f.bytes)
        .sum();
    let how = match planned {
        Planned::New(_) => "planned",
        Planned::Kept(_) => "kept the plan already there:",
    };
    say!(
        "{how} {} jobs over {} points, {:.2} GB of job inputs, in {}",
        m.jobs.len(),
        count(m.input.points),
        bytes as f64 / 1e9,
        dir.display()
    );
    Ok(())
}

fn run_build(dir: &Path, jobs: &[usize]) -> anyhow::Result<()> {
    let m = Manifest::read(dir)?;
    keep_freed_memory_within(Options::budget_of(m.job_points));
    let all: Vec<usize> = (0..m.jobs.len()).collect();
    let named = if jobs.is_empty() { &all[..] } else { jobs };
    in_lanes(named, &|j, behind| {
        let start = Instant::now();
        let (how, record) = match run_behind(dir, &m, j, Check::Checksums, behind)? {
            Ran::Built(r) => ("built", r),
            Ran::Kept(r) => ("kept (already built)", r),
        };
        say!(
            "job {j}: {how}: {} points, {} nodes, part {:.1} MB, {:.2} s",
            count(m.jobs[j].points),
            count(record.part.nodes),
            record.file.bytes as f64 / 1e6,
            start.elapsed().as_secs_f64()
        );
        Ok(())
    })?;
    if let Some(b) = peak_memory_bytes() {
        say!("peak memory {:.2} GiB", b as f64 / (1u64 << 30) as f64);
    }
    Ok(())
}

fn run_join(dir: &Path, output: &Path, clean: bool) -> anyhow::Result<()> {
    crate::io::atomic::check_writable(output, &[])?;
    let start = Instant::now();
    let bars = Bars::default();
    bars.stage("write", 0);
    let joined = join(dir, output, (Check::Checksums, AfterRead::Keep), &bars)?;
    match joined {
        Joined::Rebuild(reason) => {
            bars.finish();
            Err(RebuildNeeded(reason).into())
        }
        Joined::Written(built) => {
            bars.finish_written(output);
            summary(&built, output, start);
            if clean {
                remove_job_files(dir)?;
            }
            Ok(())
        }
    }
}

/// Removes the plan's files from `dir`, and `dir` itself when nothing else is left.
fn remove_job_files(dir: &Path) -> anyhow::Result<()> {
    let m = Manifest::read(dir)?;
    crate::tree::out_of_core::plan::remove_files(dir, &m)?;
    std::fs::remove_file(Manifest::path(dir))?;
    let _ = std::fs::remove_dir(dir);
    Ok(())
}
