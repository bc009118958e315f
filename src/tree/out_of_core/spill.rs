//! The passes over the input before any tree is built: a scan (bounds, count, whether
//! colours fit 8 bits), a count of the points per cell of a grid over the bounds, the
//! split of the grid into jobs of at most a given number of points (a k-d tree over
//! the cells, halving the count at each split), and the spill of every point to its
//! job's file, and to its neighbours' halo files when it lies within their halo
//! ([`super::halo`]).

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use arrayvec::ArrayVec;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, IVec3};

use super::halo::Halo;
use super::write_behind::{Writers, write_behind};
use crate::io::format::PointBatch;
use crate::io::formats::ModelStream;
use crate::io::model::ModelError;
use crate::io::rebase::{MAX_OFFSET, SAMPLE, sample_window, within};
use crate::io::{Bounds, PointAttributes};

/// Cells per axis of the counting grid.
pub const GRID: i32 = 64;

/// A point as the spill files hold it (20 bytes): position relative to the origin,
/// colour and LiDAR attributes.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct SpillPoint {
    pub position: [f32; 3],
    pub color: [u8; 4],
    pub attributes: PointAttributes,
}

/// What the scan found.
#[derive(Debug, Clone)]
pub struct Scan {
    /// Points kept ([`Scan::keeps`]).
    pub count: u64,
    /// Bounding box of the kept points.
    pub bounds: Bounds,
    /// Bounding box of the kept points that are not outliers: the model's size, and
    /// what the counting grid spans (outliers fall in its edge cells).
    pub core: Bounds,
    /// The mean of the kept points (the middle of their box where their sum overflows).
    pub mean: DVec3,
    /// Points dropped: not finite, or further than the rest can be stored from.
    pub dropped: u64,
    /// Kept points outside the core.
    pub outliers: u64,
    pub has_color: bool,
    /// No colour channel exceeds 255: LAS colours are taken as 8-bit.
    pub eight_bit: bool,
    /// When the finite points span more than f32 offsets hold: the point that kept
    /// points lie within `MAX_OFFSET / 2` of, per axis.
    anchor: Option<DVec3>,
}

impl Scan {
    /// Whether the point `p` is kept: finite, and within reach of the others.
    pub fn keeps(&self, p: DVec3) -> bool {
        p.is_finite()
            && self
                .anchor
                .is_none_or(|a| within(p.to_array(), a, MAX_OFFSET / 2.0))
    }

    /// The kept positions of a batch.
    fn kept<'a>(&'a self, b: &'a PointBatch) -> impl Iterator<Item = DVec3> + 'a {
        b.xyz
            .iter()
            .map(|p| DVec3::from(*p))
            .filter(|&p| self.keeps(p))
    }

    /// A pass over the kept points: their count, boxes (the core within `window`)
    /// and mean, and the colours; decoded ahead on another thread, as its work per
    /// point weighs as much as the decoding (the 200 M-point tile from a cold cache,
    /// 2 cores, 2026-12-02: the scan took 10.4 and 11.9 s decoding on this thread,
    /// 8.7 and 7.9 s so).
    fn measure(
        &mut self,
        input: &ModelStream,
        window: Option<Bounds>,
        read: &dyn Fn(u64),
    ) -> anyhow::Result<()> {
        let (mut sum, mut count, mut inliers) = (DVec3::ZERO, 0u64, 0u64);
        let (mut bounds, mut core) = (Bounds::empty(), Bounds::empty());
        let (mut has_color, mut eight_bit) = (false, true);
        let mut rows = 0u64;
        input.points_ahead(|b| {
            rows += b.xyz.len() as u64;
            read(b.xyz.len() as u64);
            for p in self.kept(b) {
                sum += p;
                count += 1;
                bounds = bounds.grow(p.to_array());
                if window.is_none_or(|w| w.contains(p.to_array())) {
                    core = core.grow(p.to_array());
                    inliers += 1;
                }
            }
            // Colours zero everywhere are a writer's empty fields, as the whole-file
            // readers take them: shaded grey.
            has_color |= b.rgb.iter().any(|c| *c != [0; 3]);
            eight_bit &= b.rgb.iter().flatten().all(|&c| c <= 255);
        })?;
        self.count = count;
        self.dropped = rows - count;
        self.mean = sum / count.max(1) as f64;
        if !self.mean.is_finite() {
            // Coordinates near f64's range overflow their sum: the box's middle.
            let (min, max) = (DVec3::from(bounds.min), DVec3::from(bounds.max));
            self.mean = min * 0.5 + max * 0.5;
        }
        self.bounds = bounds;
        // The sample comes from kept points, so the core is empty only for a file
        // that changed between the passes.
        self.core = if inliers > 0 { core } else { bounds };
        self.outliers = count - inliers;
        (self.has_color, self.eight_bit) = (has_color, eight_bit);
        Ok(())
    }
}

/// The first passes, with [`crate::io::rebase`]'s rule (the whole-file readers'): an
/// evenly strided sample of the finite points gives the outlier window (a LAS file's
/// sampled records are read alone, not in a pass: on the 200 M-point tile the scan
/// took 5.7–7.5 s instead of 11.2–14.8 s); a pass measures the finite points. When
/// some lies beyond `MAX_OFFSET / 2` of the core's centre, only those within it of the
/// sample's median are kept, measured again. The first pass's rows are told to `read`
/// batch by batch.
pub fn scan(input: &ModelStream, path: &Path, read: &dyn Fn(u64)) -> anyhow::Result<Scan> {
    if input.point_count() == 0 {
        return Err(ModelError::Empty {
            path: path.to_owned(),
        }
        .into());
    }
    let stride = input.point_count().div_ceil(SAMPLE as u64);
    let mut sample = Vec::new();
    input.strided_positions(stride, |p| {
        if p.iter().all(|c| c.is_finite()) {
            sample.push(p);
        }
    })?;
    let none = || anyhow::anyhow!("{}: the file holds no finite point", path.display());
    let (median, window) = sample_window(&sample).ok_or_else(none)?;
    let mut scan = Scan {
        count: 0,
        bounds: Bounds::empty(),
        core: Bounds::empty(),
        mean: DVec3::ZERO,
        dropped: 0,
        outliers: 0,
        has_color: false,
        eight_bit: true,
        anchor: None,
    };
    scan.measure(input, window, read)?;
    let reach = MAX_OFFSET / 2.0;
    let origin = scan.core.center();
    if !(within(scan.bounds.min, origin, reach) && within(scan.bounds.max, origin, reach)) {
        sample.retain(|&p| within(p, median, reach));
        let window = sample_window(&sample).and_then(|(_, w)| w);
        scan.anchor = Some(median);
        scan.measure(input, window, &|_| {})?;
    }
    anyhow::ensure!(
        scan.count > 0,
        "{}: the file holds no finite point",
        path.display()
    );
    Ok(scan)
}

/// The counting grid over the bounds.
#[derive(Debug, Clone)]
pub struct Grid {
    pub min: DVec3,
    pub cell: DVec3,
}

impl Grid {
    pub fn over(bounds: &Bounds) -> Grid {
        let min = DVec3::from(bounds.min);
        let extent = (DVec3::from(bounds.max) - min).max(DVec3::splat(1e-30));
        Grid {
            min,
            cell: extent / GRID as f64,
        }
    }

    /// The cell of `p` (clamped to the grid) and its position within it, 0–1 per axis.
    pub fn locate(&self, p: DVec3) -> (IVec3, DVec3) {
        let f = (p - self.min) / self.cell;
        let i = f
            .floor()
            .as_ivec3()
            .clamp(IVec3::ZERO, IVec3::splat(GRID - 1));
        (i, f - i.as_dvec3())
    }

    pub fn index(i: IVec3) -> usize {
        ((i.z * GRID + i.y) * GRID + i.x) as usize
    }

    /// The cell whose [`Grid::index`] is `index`.
    pub fn cell(index: usize) -> IVec3 {
        let i = index as i32;
        IVec3::new(i % GRID, (i / GRID) % GRID, i / (GRID * GRID))
    }
}

/// A job of the split: a box of cells (`lo..hi` per axis) and its points.
#[derive(Debug, Clone, PartialEq)]
pub struct JobBox {
    pub lo: IVec3,
    pub hi: IVec3,
    pub points: u64,
}

/// The split of the grid into jobs: a binary tree whose leaves are the jobs.
#[derive(Debug, Clone, PartialEq)]
pub enum Split {
    Job(usize),
    Node(Box<Split>, Box<Split>),
}

/// Pass 3: kept points per cell; the rows read are told to `read` batch by batch.
pub fn count_cells(
    input: &ModelStream,
    (scan, grid): (&Scan, &Grid),
    read: &dyn Fn(u64),
) -> anyhow::Result<Vec<u64>> {
    let mut counts = vec![0u64; (GRID * GRID * GRID) as usize];
    input.points(|b| {
        read(b.xyz.len() as u64);
        for p in scan.kept(b) {
            counts[Grid::index(grid.locate(p).0)] += 1;
        }
    })?;
    Ok(counts)
}

fn box_count(counts: &[u64], lo: IVec3, hi: IVec3) -> u64 {
    let mut n = 0;
    for z in lo.z..hi.z {
        for y in lo.y..hi.y {
            for x in lo.x..hi.x {
                n += counts[Grid::index(IVec3::new(x, y, z))];
            }
        }
    }
    n
}

/// Splits the cells `lo..hi` until each part holds at most `max_points` (or is one
/// cell): along the axis of the box's longest extent, at the cell plane nearest to
/// half its points. Jobs are numbered in the order of the tree's leaves.
pub fn split(
    counts: &[u64],
    grid: &Grid,
    (lo, hi): (IVec3, IVec3),
    max_points: u64,
    jobs: &mut Vec<JobBox>,
) -> Split {
    let points = box_count(counts, lo, hi);
    let size = hi - lo;
    let extent = size.as_dvec3() * grid.cell;
    let axis = (0..3)
        .filter(|&k| size[k] > 1)
        .max_by(|&a, &b| extent[a].total_cmp(&extent[b]));
    let Some(axis) = axis.filter(|_| points > max_points) else {
        jobs.push(JobBox { lo, hi, points });
        return Split::Job(jobs.len() - 1);
    };
    // The plane where the running count first reaches half, kept inside the box.
    let mut running = 0;
    let mut at = lo[axis] + 1;
    for plane in lo[axis]..hi[axis] - 1 {
        let (mut a, mut b) = (lo, hi);
        a[axis] = plane;
        b[axis] = plane + 1;
        running += box_count(counts, a, b);
        at = plane + 1;
        if 2 * running >= points {
            break;
        }
    }
    let (mut left_hi, mut right_lo) = (hi, lo);
    left_hi[axis] = at;
    right_lo[axis] = at;
    let left = split(counts, grid, (lo, left_hi), max_points, jobs);
    let right = split(counts, grid, (right_lo, hi), max_points, jobs);
    Split::Node(Box::new(left), Box::new(right))
}

/// A cell of no job (a cell of an empty box, dropped from the split: no point lies in it).
pub const NO_CELL_JOB: u32 = u32::MAX;

/// Each cell's job ([`NO_CELL_JOB`] outside every box of `jobs`).
pub fn cell_jobs(jobs: &[JobBox]) -> Vec<u32> {
    let mut table = vec![NO_CELL_JOB; (GRID * GRID * GRID) as usize];
    for (j, job) in jobs.iter().enumerate() {
        for z in job.lo.z..job.hi.z {
            for y in job.lo.y..job.hi.y {
                for x in job.lo.x..job.hi.x {
                    table[Grid::index(IVec3::new(x, y, z))] = j as u32;
                }
            }
        }
    }
    table
}

/// The spill files of the jobs: each job's own points, and its halo.
pub struct SpillFiles {
    pub own: Vec<PathBuf>,
    pub halo: Vec<PathBuf>,
    /// When the input gives normals: each point's, in the order of `own` and `halo`
    /// (files of `[f32; 3]`), one file beside each.
    pub normals: Option<(Vec<PathBuf>, Vec<PathBuf>)>,
}

/// One job's spill files.
#[derive(Debug, Clone, Copy)]
pub struct JobFiles<'a> {
    pub own: &'a Path,
    pub halo: &'a Path,
    pub normals: Option<(&'a Path, &'a Path)>,
}

/// Where a point's halo copies go: the cell table ([`cell_jobs`]), the cells whose 26
/// neighbours all belong to their own job or to none (a point there is in no other
/// job's halo), and the halo's reach.
struct HaloRoute<'a> {
    table: &'a [u32],
    inner: Vec<bool>,
    halo: &'a Halo,
}

impl<'a> HaloRoute<'a> {
    fn new(table: &'a [u32], halo: &'a Halo) -> Self {
        let last = GRID - 1;
        let inner = (0..table.len())
            .map(|i| {
                let cell = Grid::cell(i);
                let near = (-1..=1).flat_map(|z| {
                    (-1..=1).flat_map(move |y| (-1..=1).map(move |x| IVec3::new(x, y, z)))
                });
                let job = table[i];
                near.map(|d| cell + d)
                    .filter(|c| c.min_element() >= 0 && c.max_element() <= last)
                    .all(|c| matches!(table[Grid::index(c)], j if j == job || j == NO_CELL_JOB))
            })
            .collect();
        HaloRoute { table, inner, halo }
    }

    /// The jobs other than `job` whose cells lie within the halo's reach of the point
    /// at `frac` (0–1 per axis) within `cell`, in `out`. Called for every point of the
    /// spill, so nothing here allocates: three small vectors a point had made the
    /// 200 M-point city tile's spill take 32.7–33.8 s, against 19.5 s so (2 cores,
    /// 2026-11-30, alternated).
    fn jobs(&self, (cell, frac): (IVec3, DVec3), job: u32, out: &mut Vec<u32>) {
        out.clear();
        if self.inner[Grid::index(cell)] {
            return;
        }
        let steps = |k: usize| {
            let mut s = ArrayVec::<i32, 3>::new();
            s.push(0);
            if frac[k] < self.halo.reach[k] && cell[k] > 0 {
                s.push(-1);
            }
            if frac[k] > 1.0 - self.halo.reach[k] && cell[k] < GRID - 1 {
                s.push(1);
            }
            s
        };
        let (sx, sy, sz) = (steps(0), steps(1), steps(2));
        for &dz in &sz {
            for &dy in &sy {
                for &dx in &sx {
                    let other = self.table[Grid::index(cell + IVec3::new(dx, dy, dz))];
                    if other != job && other != NO_CELL_JOB && !out.contains(&other) {
                        out.push(other);
                    }
                }
            }
        }
    }
}

/// The last pass: every kept point to its job's file and to the halo files of the jobs
/// within `reach` of it, relative to `origin`, colours as 8-bit RGBA.
pub fn spill(
    input: &ModelStream,
    (grid, table, job_count): (&Grid, &[u32], usize),
    reach: &Halo,
    (scan, origin): (&Scan, DVec3),
    dir: &Path,
    buffer_bytes: usize,
    mut progress: impl FnMut(u64),
) -> anyhow::Result<SpillFiles> {
    let names = |kind| job_paths(dir, job_count, kind);
    let files = SpillFiles {
        own: names("own"),
        halo: names("halo"),
        normals: input
            .has_normals()
            .then(|| (names("own_normals"), names("halo_normals"))),
    };
    let mut paths: Vec<PathBuf> = [&files.own[..], &files.halo[..]].concat();
    if let Some((own, halo)) = &files.normals {
        paths.extend(own.iter().chain(halo).cloned());
    }
    let route = HaloRoute::new(table, reach);
    let mut around = Vec::new();
    // The files in `paths`: own 0..J, halo J..2J, then their normals the same way (J = job_count).
    let fill = |w: &mut Writers| {
        input.points_ahead(|b| {
            for (i, p) in b.xyz.iter().enumerate() {
                let p = DVec3::from(*p);
                if !scan.keeps(p) {
                    continue;
                }
                let color = b
                    .color(i, scan.eight_bit)
                    .unwrap_or(crate::surfel::DEFAULT_COLOR);
                let point = SpillPoint {
                    position: (p - origin).as_vec3().to_array(),
                    color,
                    attributes: b.attributes(i),
                };
                let located = grid.locate(p);
                let job = table[Grid::index(located.0)] as usize;
                let normal = b.normals.get(i).map(bytemuck::bytes_of);
                let mut write = |file: usize| {
                    w.write(file, bytemuck::bytes_of(&point));
                    if let Some(n) = normal {
                        w.write(2 * job_count + file, n);
                    }
                };
                write(job);
                route.jobs(located, job as u32, &mut around);
                for &other in &around {
                    write(job_count + other as usize);
                }
            }
            progress(b.xyz.len() as u64);
        })
    };
    write_behind(create_files(&paths)?, buffer_bytes, fill).map_err(|e| spill_failed(dir, e))??;
    Ok(files)
}

/// A failed write of the spill files in `dir` (most often a full disk), naming the
/// folder: a buffered write may fail for any of its files.
pub fn spill_failed(dir: &Path, e: std::io::Error) -> anyhow::Error {
    anyhow::anyhow!("{}: cannot write the spill files: {e}", dir.display())
}

/// The spill file of each of `jobs` jobs for records of `kind`: `dir/job{j}.{kind}`.
pub fn job_paths(dir: &Path, jobs: usize, kind: &str) -> Vec<PathBuf> {
    (0..jobs)
        .map(|j| dir.join(format!("job{j}.{kind}")))
        .collect()
}

/// One buffered writer per path, each file created ([`create_files`]).
pub fn writers(paths: &[PathBuf], buffer: usize) -> anyhow::Result<Vec<BufWriter<File>>> {
    let files = create_files(paths)?;
    Ok(files
        .into_iter()
        .map(|f| BufWriter::with_capacity(buffer, f))
        .collect())
}

/// The files at `paths`, created. An error names the file, and says what to do when
/// too many files are open at once.
pub fn create_files(paths: &[PathBuf]) -> anyhow::Result<Vec<File>> {
    paths
        .iter()
        .map(|p| {
            File::create(p).map_err(|e| {
                let hint = if e.raw_os_error() == Some(24) {
                    " (too many files open at once: raise `ulimit -n`, or give a larger \
                     --memory for fewer jobs)"
                } else {
                    ""
                };
                anyhow::anyhow!("{}: cannot create a spill file: {e}{hint}", p.display())
            })
        })
        .collect()
}

/// The points of a spill file, read straight into their vector.
pub fn read_spill(path: &Path) -> anyhow::Result<Vec<SpillPoint>> {
    read_records(path)
}

/// The records of a spill file of `T`s, read straight into their vector.
pub fn read_records<T: Pod>(path: &Path) -> anyhow::Result<Vec<T>> {
    let mut file = File::open(path)?;
    let bytes = file.metadata()?.len() as usize;
    let size = std::mem::size_of::<T>();
    anyhow::ensure!(
        bytes.is_multiple_of(size),
        "{}: a spill file of {bytes} bytes",
        path.display()
    );
    let mut records = vec![T::zeroed(); bytes / size];
    std::io::Read::read_exact(&mut file, bytemuck::cast_slice_mut(&mut records))?;
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table giving each cell a job of its own: its index.
    fn cell_per_job() -> Vec<u32> {
        (0..(GRID * GRID * GRID) as u32).collect()
    }

    #[test]
    fn a_point_takes_the_jobs_across_the_faces_it_lies_near() {
        let table = cell_per_job();
        let halo = Halo {
            reach: DVec3::splat(0.25),
        };
        let route = HaloRoute::new(&table, &halo);
        let cell = IVec3::new(5, 6, 7);
        assert_eq!(Grid::cell(Grid::index(cell)), cell);
        let job = table[Grid::index(cell)];
        let jobs_near = |frac: DVec3| {
            let mut out = Vec::new();
            route.jobs((cell, frac), job, &mut out);
            out.sort_unstable();
            out
        };
        assert!(
            jobs_near(DVec3::splat(0.5)).is_empty(),
            "the middle of its cell"
        );
        let low_x = table[Grid::index(cell - IVec3::X)];
        assert_eq!(jobs_near(DVec3::new(0.1, 0.5, 0.5)), [low_x]);
        // Near a corner: the 7 cells that share it.
        let near_corner = jobs_near(DVec3::new(0.9, 0.1, 0.9));
        let mut corner: Vec<u32> = (0..8)
            .map(|k| IVec3::new(k & 1, -((k >> 1) & 1), (k >> 2) & 1))
            .filter(|&d| d != IVec3::ZERO)
            .map(|d| table[Grid::index(cell + d)])
            .collect();
        corner.sort_unstable();
        assert_eq!(near_corner, corner);
        // At the grid's edge there is no cell beyond.
        let mut out = Vec::new();
        route.jobs((IVec3::ZERO, DVec3::splat(0.1)), 0, &mut out);
        assert!(out.is_empty(), "{out:?}");
    }

    #[test]
    fn a_point_away_from_other_jobs_goes_to_no_halo() {
        // Two jobs, split at x = 32, reaching a whole cell: a point near the faces of a
        // cell whose neighbours are all its job's goes to no halo; one in the column
        // beside the split goes to the other job's, from any y or z.
        let table: Vec<u32> = (0..(GRID * GRID * GRID))
            .map(|i| u32::from(i % GRID >= 32))
            .collect();
        let halo = Halo { reach: DVec3::ONE };
        let route = HaloRoute::new(&table, &halo);
        let mut out = Vec::new();
        route.jobs((IVec3::new(10, 5, 7), DVec3::splat(0.01)), 0, &mut out);
        assert!(out.is_empty(), "{out:?}");
        route.jobs((IVec3::new(31, 63, 0), DVec3::splat(0.01)), 0, &mut out);
        assert_eq!(out, [1]);
        route.jobs((IVec3::new(32, 20, 40), DVec3::splat(0.99)), 1, &mut out);
        assert_eq!(out, [0]);
    }
}
