//! Out-of-core builds (docs/design.md §5, "Chunks"): a model larger than memory turned into
//! an `.spt` file while holding only a bounded part of it, in passes over the input (a
//! LAS, LAZ or PLY cloud, or a PLY mesh, read a batch at a time by
//! [`ModelStream`]):
//!
//! ```text
//! scan ─► count per grid cell ─► split into jobs ─► spill to job files ─► build each job ─► top tree, file
//! (bounds)  (64³ cells)        (k-d, ≤ N points)   (own + halo)         (surfels, tree,   (streamed from
//!                                                                          chunks: a part)   the parts)
//! ```
//!
//! A job holds at most N points (from the memory budget, [`Options::job_points`]) and
//! the points of its halo: those of the neighbouring cells within a quarter cell of
//! its border, so that the neighbourhoods of its points near the border see past it.
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
//! **On many machines.** A job's input is two files and the model's shared values
//! ([`job::Model`]: origin, bounds, error scale); its output is a part file and a
//! [`job::Part`] of a few hundred bytes plus a sample of intensities. On an engine such
//! as Spark or a batch queue, the spill would write the job files to shared storage
//! (one writer per input split, files concatenated per job), a map stage would run
//! [`job::build`] per job, and a single reducer would run [`assemble::write_file`]
//! over the parts it collects: the only step that sees every part, and it streams them.
//! A mesh adds one step between the map stages: the vote's two sums from each job
//! ([`mesh_job::flux`]), added up by the driver, which passes the orientation to the
//! build stage.
//!
//! Normals that the file gives are kept, for a cloud's points as for a mesh's vertices.

pub(crate) mod assemble;
pub(crate) mod job;
pub(crate) mod mesh_job;
pub(crate) mod mesh_spill;
pub(crate) mod order;
pub(crate) mod spill;

use std::path::Path;

use glam::{DVec3, IVec3};

use crate::io::formats::ModelStream;
use crate::surfel::outward::Vote;
use crate::tree::TreeMeta;
use job::{Model, Part};
use spill::{GRID, Grid};

/// Bytes of memory a job takes per point at its peak (its surfels, k-d tree, nodes and
/// list), halo included. Measured on the 200 M-point `gen_cloud` tile's jobs of 6.7 M
/// points: 160, and about 300 with a terrain's averaged normals (each sample's 24
/// neighbours are kept between the fits and their mean, `surfel::cloud`).
pub const BYTES_PER_JOB_POINT: u64 = 320;

/// How far the leaves' own error scale may exceed the model's (from the points' box)
/// before the jobs are built again with theirs: errors up to about this many scales fit
/// an f16 (at most 65,504) with room for a tree's depth of sums.
pub const SCALE_SLACK: f32 = 64.0;

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
    /// The options for a budget of `memory` bytes: jobs of half the budget over
    /// [`BYTES_PER_JOB_POINT`] (at least 2¹⁶ points), an eighth of it for the spill's
    /// buffers, the rest for the grid, the parts' roots and the page cache.
    pub fn for_memory(memory: u64, temp_dir: std::path::PathBuf) -> Options {
        Options {
            job_points: (memory / 2 / BYTES_PER_JOB_POINT).max(1 << 16),
            spill_buffers: memory / 8,
            temp_dir,
        }
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
    /// A mesh's jobs were built twice: the first job's guess of the orientation was
    /// not the whole model's vote ([`mesh_job`]).
    pub rebuilt: bool,
}

/// Hears how a build goes: a stage starts (with its total of points, 0 if unknown),
/// points go by; the next stage's start ends the one before.
pub trait Progress: Sync {
    fn stage(&self, name: &'static str, total: u64);
    fn advance(&self, points: u64);
}

/// Builds the `.spt` file of the model `input` (a LAS, LAZ or PLY cloud, or a PLY
/// mesh) at `output` within `options`.
pub fn build_file(
    input: &Path,
    output: &Path,
    options: &Options,
    progress: &dyn Progress,
) -> anyhow::Result<Built> {
    let stream = ModelStream::open(input)?;
    progress.stage("scan", 0);
    let scan = spill::scan(&stream, input)?;
    progress.stage("count", scan.count);
    let grid = Grid::over(&scan.core);
    let counts = spill::count_cells(&stream, &scan, &grid)?;
    let mut jobs = Vec::new();
    let whole = (IVec3::ZERO, IVec3::splat(GRID));
    let split = spill::split(&counts, &grid, whole, options.job_points, &mut jobs);
    let dir = tempfile::Builder::new()
        .prefix("spt-build-")
        .tempdir_in(&options.temp_dir)?;
    let model = Model {
        // The centre of the core, as the whole-file readers take it.
        origin: scan.core.center(),
        bounds: scan.bounds,
        core: scan.core,
        error_scale: scan.bounds.extent().max_element().max(1e-30) as f32,
        has_colors: scan.has_color,
        has_normals: stream.has_normals(),
        has_attributes: stream.has_attributes(),
        up: stream.up(),
        // A tree has about 1.5 nodes per point.
        chunk_nodes: crate::tree::chunks::chunk_nodes_for((scan.count + scan.count / 2) as usize),
    };
    let mut model = model;
    let (parts, rebuilt, two_sided) = loop {
        let run = Run {
            stream: &stream,
            scan: &scan,
            grid: &grid,
            jobs: &jobs,
            model: &model,
            dir: dir.path(),
            options,
            progress,
        };
        let (parts, rebuilt, two_sided) = if stream.has_faces() {
            run.mesh_parts()?
        } else {
            (run.cloud_parts()?, false, false)
        };
        // Errors are stored as f16 multiples of the scale, so it must not be far below
        // the leaves' own (their disks reach past the points' box by their radii, which
        // the scale from the points cannot know: on degenerate models, by far). Then
        // everything is built again with theirs; on other models this never happens.
        let needed = parts.iter().map(|p| p.disk_extent).fold(0.0, f32::max);
        if needed <= SCALE_SLACK * model.error_scale {
            break (parts, rebuilt, two_sided);
        }
        model.error_scale = needed;
    };
    progress.stage("write", 0);
    let split = drop_empty(split, &jobs);
    let meta = assemble::write_file(output, &model, (&split, &parts), two_sided)?;
    Ok(Built {
        meta,
        jobs: parts.len(),
        dropped: scan.dropped,
        outliers: scan.outliers,
        walls: parts.iter().map(|p| p.walls).sum(),
        rebuilt,
    })
}

/// What the stages after the split share.
struct Run<'a> {
    stream: &'a ModelStream,
    scan: &'a spill::Scan,
    grid: &'a Grid,
    jobs: &'a [spill::JobBox],
    model: &'a Model,
    dir: &'a Path,
    options: &'a Options,
    progress: &'a dyn Progress,
}

impl Run<'_> {
    /// Write buffers for `files` files per job.
    fn buffer(&self, files: u64) -> usize {
        let per = self.options.spill_buffers / (files * self.jobs.len() as u64);
        per.clamp(1 << 12, 1 << 20) as usize
    }

    fn part_path(&self, j: usize) -> std::path::PathBuf {
        self.dir.join(format!("job{j}.part"))
    }

    /// A cloud's spill and jobs: its points with their halos.
    fn cloud_parts(&self) -> anyhow::Result<Vec<Part>> {
        self.progress.stage("spill", self.scan.count);
        let table = spill::cell_jobs(self.jobs);
        let files = spill::spill(
            self.stream,
            (self.grid, &table, self.jobs.len()),
            (self.scan, self.model.origin),
            self.dir,
            self.buffer(2),
            |n| self.progress.advance(n),
        )?;
        self.progress.stage("build", self.scan.count);
        let mut parts: Vec<Part> = Vec::with_capacity(self.jobs.len());
        for (j, job) in self.jobs.iter().enumerate() {
            if job.points == 0 {
                continue;
            }
            parts.push(job::build(self.model, files.of(j), &self.part_path(j))?);
            files.of(j).remove()?;
            self.progress.advance(job.points);
        }
        Ok(parts)
    }

    /// A mesh's spill and jobs: its vertices with the triangles and vertices their
    /// surfels read, the orientation vote over every job, then each job's build.
    /// Also says whether the jobs were built twice, and whether the model is open
    /// ([`TreeMeta::two_sided`]).
    fn mesh_parts(&self) -> anyhow::Result<(Vec<Part>, bool, bool)> {
        anyhow::ensure!(
            self.jobs.len() < mesh_spill::NO_JOB as usize,
            "{} jobs: a mesh is split into fewer than {}; raise --memory",
            self.jobs.len(),
            mesh_spill::NO_JOB
        );
        self.progress.stage("jobs", self.scan.count);
        let table = spill::cell_jobs(self.jobs);
        let own = mesh_spill::own_jobs(self.stream, (self.scan, self.grid), &table)?;
        self.progress.advance(own.len() as u64);
        self.progress.stage("spill", self.scan.count);
        let files = mesh_spill::spill(
            self.stream,
            &own,
            (self.model.origin, self.jobs.len()),
            self.dir,
            self.buffer(3),
            |n| self.progress.advance(n),
        )?;
        drop(own);
        let of = |j: usize| (&*files.own[j], &*files.halo[j], &*files.triangles[j]);
        let live: Vec<usize> = (0..self.jobs.len())
            .filter(|&j| self.jobs[j].points > 0)
            .collect();
        // The orientation is the whole model's vote (the model one piece: whether it
        // faces inward, where it is closed), which needs every job's face normals.
        // Rather than a pass of its own, the first job's vote is the guess that the
        // jobs are built with, each adding its terms as it is built; in the rare case
        // that the model's vote decides otherwise, they are built again. A job is a
        // part of the model and looks open: its guess is not to turn, wrong only for a
        // closed model wound inward. Whether the model is open changes nothing in its
        // parts: it is said in the file's flags.
        let c = self.scan.mean - self.model.origin;
        let guess = mesh_job::flux(self.model, of(live[0]), c)?.turns();
        let mut built = self.build_mesh_jobs(&live, &of, (guess, c))?;
        let rebuilt = built.1.turns() != guess;
        if rebuilt {
            built = self.build_mesh_jobs(&live, &of, (!guess, c))?;
        }
        for &j in &live {
            for f in [of(j).0, of(j).1, of(j).2] {
                std::fs::remove_file(f)?;
            }
        }
        Ok((built.0, rebuilt, !built.1.closed()))
    }

    /// Builds the mesh jobs `live` with their normals turned when `turn`; returns the
    /// parts and the model's orientation vote about `c`.
    fn build_mesh_jobs<'f>(
        &self,
        live: &[usize],
        of: &dyn Fn(usize) -> mesh_job::Files<'f>,
        (turn, c): (bool, DVec3),
    ) -> anyhow::Result<(Vec<Part>, Vote)> {
        self.progress.stage("build", self.scan.count);
        let mut parts: Vec<Part> = Vec::with_capacity(live.len());
        let mut vote = Vote::default();
        for &j in live {
            let (part, terms) = mesh_job::build(self.model, of(j), (turn, c), &self.part_path(j))?;
            parts.push(part);
            vote = vote.plus(terms);
            self.progress.advance(self.jobs[j].points);
        }
        Ok((parts, vote))
    }
}

/// The split without its empty jobs, the rest renumbered in order.
fn drop_empty(split: spill::Split, jobs: &[spill::JobBox]) -> spill::Split {
    use spill::Split;
    let mut number = vec![usize::MAX; jobs.len()];
    let mut k = 0;
    for (j, job) in jobs.iter().enumerate() {
        if job.points > 0 {
            number[j] = k;
            k += 1;
        }
    }
    fn walk(s: Split, number: &[usize]) -> Option<Split> {
        match s {
            Split::Job(j) => (number[j] != usize::MAX).then(|| Split::Job(number[j])),
            Split::Node(a, b) => match (walk(*a, number), walk(*b, number)) {
                (Some(a), Some(b)) => Some(Split::Node(Box::new(a), Box::new(b))),
                (a, b) => a.or(b),
            },
        }
    }
    walk(split, &number).expect("a cloud with points has a job with points")
}
