//! The first step of an out-of-core build: scan the input, count its points per grid
//! cell, split the grid into jobs, spill every point (a mesh's vertices and
//! triangles) to its job's input files, and write the [`Manifest`] with each file's
//! size and checksum.

use std::path::Path;
use std::sync::OnceLock;

use glam::IVec3;

use super::checksums::{self, FileEntry};
use super::halo::Halo;
use super::job::Model;
use super::manifest::{self, BuildParams, Input, JobEntry, Manifest};
use super::spill::{self, GRID, Grid, JobBox, Scan, Split};
use super::{Options, Progress, in_lanes, mesh_job, mesh_spill, record};
use crate::io::formats::ModelStream;
use crate::surfel::outward::Vote;

/// What [`plan`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Planned {
    /// A new plan, written.
    New(Manifest),
    /// The directory already held the plan of this input with these options.
    Kept(Manifest),
}

impl Planned {
    pub fn manifest(&self) -> &Manifest {
        match self {
            Planned::New(m) | Planned::Kept(m) => m,
        }
    }
}

/// Plans the build of `input` into the job directory `dir` (created if needed), unless
/// it holds the plan of this input (same path, size and modification time) with these
/// options already.
pub fn plan(
    input: &Path,
    dir: &Path,
    options: &Options,
    progress: &dyn Progress,
) -> anyhow::Result<Planned> {
    std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    let path =
        std::fs::canonicalize(input).map_err(|e| anyhow::anyhow!("{}: {e}", input.display()))?;
    let metadata = std::fs::metadata(&path)?;
    let (bytes, modified) = (metadata.len(), modified_nanos(&metadata));
    let old = Manifest::read(dir).ok();
    if let Some(m) = &old
        && (&m.input.path, m.input.bytes, m.input.modified) == (&path, bytes, modified)
        && m.job_points == options.job_points
    {
        return Ok(Planned::Kept(m.clone()));
    }
    if let Some(m) = &old {
        remove_files(dir, m)?;
    }
    let stream = ModelStream::open(input)?;
    // Both passes read every row of the file, kept or not.
    let read = |n| progress.advance(n);
    progress.stage("scan", stream.point_count());
    let scan = spill::scan(&stream, input, &read)?;
    progress.stage("count", stream.point_count());
    let grid = Grid::over(&scan.core);
    let counts = spill::count_cells(&stream, (&scan, &grid), &read)?;
    let mut boxes = Vec::new();
    let whole = (IVec3::ZERO, IVec3::splat(GRID));
    let split = spill::split(&counts, &grid, whole, options.job_points, &mut boxes);
    let halo = Halo::of(&counts, grid.cell);
    drop(counts);
    let (split, boxes) = drop_empty(split, boxes);
    let model = model_of(&stream, &scan);
    let spilling = Spilling {
        stream: &stream,
        scan: &scan,
        grid: &grid,
        halo: &halo,
        jobs: &boxes,
        model: &model,
        dir,
        options,
        progress,
    };
    let (files, turn_guess) = if stream.has_faces() {
        spilling.mesh()?
    } else {
        (spilling.cloud()?, false)
    };
    let mut codes = Vec::new();
    manifest::encode(&split, &mut codes);
    let manifest = Manifest {
        format: manifest::FORMAT,
        input: Input {
            path,
            bytes,
            modified,
            points: scan.count,
            dropped: scan.dropped,
            outliers: scan.outliers,
            mesh: stream.has_faces(),
            vote_centre: (scan.mean - model.origin).to_array(),
            turn_guess,
        },
        job_points: options.job_points,
        build: BuildParams {
            error_scale: model.error_scale,
            turn: turn_guess,
            round: 0,
        },
        model,
        split: codes,
        jobs: (boxes.iter().zip(files))
            .map(|(b, files)| JobEntry {
                lo: b.lo.to_array(),
                hi: b.hi.to_array(),
                points: b.points,
                files,
            })
            .collect(),
    };
    manifest.write(dir)?;
    Ok(Planned::New(manifest))
}

/// Plans `input` in `dir` again with the build parameters that the join wrote into its
/// manifest, for a build that removed each job's inputs once its part was built
/// (`spt convert`) and must build every job again: the same input and options give the
/// same jobs and files.
pub fn plan_again(
    input: &Path,
    dir: &Path,
    options: &Options,
    progress: &dyn Progress,
) -> anyhow::Result<()> {
    let build = Manifest::read(dir)?.build;
    // Without its manifest the directory holds no plan to keep: the input is read again.
    let path = Manifest::path(dir);
    std::fs::remove_file(&path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let (Planned::New(mut m) | Planned::Kept(mut m)) = plan(input, dir, options, progress)?;
    m.build = build;
    m.write(dir)
}

/// A file's modification time in nanoseconds since the Unix epoch; 0 where unknown.
fn modified_nanos(metadata: &std::fs::Metadata) -> u64 {
    let since = |t: std::time::SystemTime| t.duration_since(std::time::UNIX_EPOCH).ok();
    (metadata.modified().ok().and_then(since)).map_or(0, |d| d.as_nanos() as u64)
}

/// The model's shared values from its scan.
fn model_of(stream: &ModelStream, scan: &Scan) -> Model {
    Model {
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
    }
}

/// Removes the files of an earlier plan in `dir`: its jobs' inputs, parts and records.
pub fn remove_files(dir: &Path, m: &Manifest) -> anyhow::Result<()> {
    let built = (0..m.jobs.len()).flat_map(|j| [record::part_name(j), record::record_name(j)]);
    remove_named(dir, input_names(m).chain(built))
}

/// Removes the jobs' inputs of the plan in `dir`.
pub fn remove_inputs(dir: &Path, m: &Manifest) -> anyhow::Result<()> {
    remove_named(dir, input_names(m))
}

/// Removes the input files of `job` (of the plan in `dir`).
pub fn remove_job_inputs(dir: &Path, job: &JobEntry) -> anyhow::Result<()> {
    remove_named(dir, job.files.iter().map(|f| f.name.clone()))
}

/// The names of the jobs' input files.
fn input_names(m: &Manifest) -> impl Iterator<Item = String> + '_ {
    m.jobs
        .iter()
        .flat_map(|job| job.files.iter().map(|f| f.name.clone()))
}

/// Removes the files `names` of `dir`; one already gone is no error.
fn remove_named(dir: &Path, names: impl Iterator<Item = String>) -> anyhow::Result<()> {
    for name in names {
        match std::fs::remove_file(dir.join(&name)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                anyhow::bail!("{}: {e}", dir.join(name).display())
            }
            _ => {}
        }
    }
    Ok(())
}

/// What the spill needs.
struct Spilling<'a> {
    stream: &'a ModelStream,
    scan: &'a Scan,
    grid: &'a Grid,
    /// A cloud's halo (a mesh's jobs read the rings their surfels need instead).
    halo: &'a Halo,
    jobs: &'a [JobBox],
    model: &'a Model,
    dir: &'a Path,
    options: &'a Options,
    progress: &'a dyn Progress,
}

impl Spilling<'_> {
    /// Write buffers for `files` files per job.
    fn buffer(&self, files: u64) -> usize {
        let per = self.options.spill_buffers / (files * self.jobs.len() as u64);
        per.clamp(1 << 12, 1 << 20) as usize
    }

    /// Each job's entries of the files `(role, paths)`, checksummed in parallel.
    fn entries(
        &self,
        files: &[(&str, &[std::path::PathBuf])],
    ) -> anyhow::Result<Vec<Vec<FileEntry>>> {
        use rayon::prelude::*;
        (0..self.jobs.len())
            .into_par_iter()
            .map(|j| {
                (files.iter())
                    .map(|(role, paths)| {
                        let name = paths[j].file_name().unwrap_or_default().to_string_lossy();
                        checksums::entry(self.dir, role, &name)
                            .map_err(|e| anyhow::anyhow!("{}: {e}", paths[j].display()))
                    })
                    .collect()
            })
            .collect()
    }

    /// A cloud's spill: each job's points and halo (and their normals, when given).
    fn cloud(&self) -> anyhow::Result<Vec<Vec<FileEntry>>> {
        self.progress.stage("spill", self.scan.count);
        let table = spill::cell_jobs(self.jobs);
        let files = spill::spill(
            self.stream,
            (self.grid, &table, self.jobs.len()),
            self.halo,
            (self.scan, self.model.origin),
            self.dir,
            self.buffer(2),
            |n| self.progress.advance(n),
        )?;
        let mut roles = vec![("own", &files.own[..]), ("halo", &files.halo[..])];
        if let Some((own, halo)) = &files.normals {
            roles.extend([("own_normals", &own[..]), ("halo_normals", &halo[..])]);
        }
        self.entries(&roles)
    }

    /// A mesh's spill: each job's vertices, the halo its surfels read and its
    /// triangles; also whether the whole mesh's orientation vote turns its normals,
    /// the orientation the parts are built with ([`mesh_job`]).
    fn mesh(&self) -> anyhow::Result<(Vec<Vec<FileEntry>>, bool)> {
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
        let turn = self.whole_vote(&files)?.turns();
        let roles = [
            ("own", &files.own[..]),
            ("halo", &files.halo[..]),
            ("tri", &files.triangles[..]),
        ];
        Ok((self.entries(&roles)?, turn))
    }

    /// The whole mesh's orientation vote about its mean vertex: every job's terms
    /// ([`mesh_job::flux`]), read back from its spill files, [`in_lanes`], added in the
    /// jobs' order as the join adds them.
    fn whole_vote(&self, files: &mesh_spill::MeshFiles) -> anyhow::Result<Vote> {
        let c = self.scan.mean - self.model.origin;
        let terms: Vec<OnceLock<Vote>> = files.own.iter().map(|_| OnceLock::new()).collect();
        let jobs: Vec<usize> = (0..terms.len()).collect();
        self.progress.stage("vote", self.scan.count);
        let (model, boxes, progress) = (self.model, self.jobs, self.progress);
        in_lanes(&jobs, &|j, _| {
            let job = (&*files.own[j], &*files.halo[j], &*files.triangles[j]);
            let _ = terms[j].set(mesh_job::flux(model, job, c)?);
            progress.advance(boxes[j].points);
            Ok(())
        })?;
        let each = terms.iter().map(|t| t.get().copied().unwrap_or_default());
        Ok(each.fold(Vote::default(), Vote::plus))
    }
}

/// The split without its empty jobs, the rest renumbered in order.
fn drop_empty(split: Split, jobs: Vec<JobBox>) -> (Split, Vec<JobBox>) {
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
    let split = walk(split, &number).expect("a model with points has a job with points");
    (split, jobs.into_iter().filter(|j| j.points > 0).collect())
}
