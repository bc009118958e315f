//! Surfels of a point cloud from its k nearest neighbours (a uniform grid, [`cells`]), made to
//! hold on real sampling: scan lines, quantised coordinates, rows of an RGB-D frame
//! sparser than its columns, stray samples.
//!
//! * normal: the smallest principal axis of the neighbourhood (self + [`K`] − 1
//!   neighbours: enough to span several scan lines), unless the file gives a non-zero
//!   one; on a quantised frame where it lies on one depth step ([`super::levels`]) the
//!   mean of its neighbours' that span steps (`smoothed`); oriented afterwards where a
//!   direction is known ([`Orientation`]);
//! * radius and ellipse: the covering of [`super::covering`], from the same
//!   neighbourhood; a capped one is counted ([`SurfelStats::capped_radii`]); held
//!   within [`TILE_SPACINGS`] of a terrain's median spacing, [`CLOUD_SPACINGS`] of any
//!   other cloud's;
//! * clip: a splat on a boundary of the sampling ends there ([`boundary_clip`]), a
//!   terrain's edge sample at its wall (counted: [`SurfelStats::clipped_boundaries`]);
//! * walls: a terrain's steep edges stand on wall surfels of their own ([`walls`]).
//!
//! A terrain whose samples make a TIN is drawn from it instead ([`super::terrain`]);
//! the terrain rules here (the tile's spacing, walls) serve a terrain whose samples
//! make no triangle, or whose file gives every normal.
//!
//! Duplicated samples do not shrink a radius (only distinct neighbours count). A surfel
//! whose neighbours all coincide with it takes the median radius of the others
//! ([`fallback_radius`]).

mod cells;
mod orientation;
mod search;
mod smoothed;
mod within;

use arrayvec::ArrayVec;
use glam::Vec3;
use rayon::prelude::*;

use super::covering::{Covering, MAX_NEIGHBOURS, RadiusRule, covering};
use super::pca::plane_normal;
use super::progress::{Progress, Stages};
use super::shape::{Clip, Shape, SplatShape};
use super::{Surfel, SurfelStats};
use super::{footprint, walls};
pub use orientation::{NormalsTurned, Orientation};
use search::Search;
use smoothed::{Steps, smoothed_disks};

/// Neighbourhood size, the point itself included. An RGB-D frame's quantised depth
/// puts a 16-neighbourhood at its far wall on one step of one row, whose normal faces
/// the sensor and whose ellipse leaves streaks of holes between the steps; 24 see the
/// next step (the frame's holes 0.93 % → 0.10 %, docs/point-clouds.md). 16 would cost
/// little less: 7.4 % fewer instructions on the knot's 210,000 vertices as a cloud
/// (`tools/count_convert.sh`, the whole convert), 10 % more mispredicted branches, the
/// Lucy-size cloud's surfels within the machine's noise (2026-12-02).
pub const K: usize = 24;
const _: () = assert!(K <= MAX_NEIGHBOURS, "the covering takes every neighbour");

/// Radius for surfels without a measured one: the median of the measured radii, or
/// 1/1024 of the model's extent (of one unit for a model without extent) when none was.
pub fn fallback_radius(radii: &[f32], scale: f32) -> f32 {
    median_of_positive(radii.par_iter().copied()).unwrap_or(1.0 / 1024.0 / scale)
}

/// The (upper) median of the positive, finite `values`; `None` when there are none.
fn median_of_positive(values: impl ParallelIterator<Item = f32>) -> Option<f32> {
    let mut kept: Vec<f32> = values.filter(|v| *v > 0.0 && v.is_finite()).collect();
    if kept.is_empty() {
        return None;
    }
    let mid = kept.len() / 2;
    Some(*kept.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// The search grid's share of a cloud's surfels time, in percent, for its progress: 0.39
/// s of 2.54 s on a 3.07 M-point cloud (`gen_model --segments 3000 --sides 1024
/// --no-faces --no-colors`, 2 cores, Intel, 2026-12-04); the neighbourhoods take the rest.
pub(crate) const GRID_WEIGHT: u32 = 15;

/// Normal, radius and ellipse from the neighbours of each point listed in `which`
/// (ascending), searching among all `points` (unit-scaled by `scale` for the search),
/// written into `surfels`. Non-zero `given` normals are kept, the estimated ones turned
/// by `orientation` (on a quantised frame, smoothed first: `smoothed_disks`); a radius
/// already set (from faces) is only grown. A boundary splat ends where its sampling
/// does ([`boundary_clip`]), a terrain's edge sample where its wall stands
/// ([`walls`]). Afterwards every listed surfel whose radius is still 0 gets
/// [`fallback_radius`]. Returns a terrain's wall surfels (none for any other cloud).
/// The search's grid and then the neighbourhoods' fits are told to `progress`
/// ([`GRID_WEIGHT`]).
pub fn neighbour_disks(
    points: &[Vec3],
    scale: f32,
    which: &[u32],
    (rule, orientation, progress): (RadiusRule, Orientation, Progress),
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
) -> Vec<Surfel> {
    if which.is_empty() {
        return Vec::new();
    }
    let stages = Stages::new(which.len(), 100, progress);
    let search = Search::new(points, scale);
    stages.ended(GRID_WEIGHT);
    let share = stages.share(100 - GRID_WEIGHT);
    let given_normal = |i: u32| given.map_or(Vec3::ZERO, |g| g[i as usize]);
    let mut disks = disks(
        &search,
        (points, scale),
        which,
        (rule, orientation, Progress::to(&share)),
        &given_normal,
        stats,
    );
    if orientation == Orientation::Up {
        stats.tile_capped += cap_to_spacing(&mut disks, TILE_SPACINGS);
    } else {
        stats.capped_radii += cap_to_spacing(&mut disks, CLOUD_SPACINGS);
    }
    if let Orientation::Toward(sensor) = orientation {
        within_pixels(
            &search,
            (points, scale),
            which,
            sensor * scale,
            &mut disks,
            stats,
        );
    }
    // Each wall with its sample's index in `which`, ascending (none but on a terrain).
    let walls = if orientation == Orientation::Up && !search.is_empty() {
        let queries: Vec<Vec3> = which.iter().map(|&i| points[i as usize] * scale).collect();
        walls::terrain_walls(&search.coords, &queries)
    } else {
        Vec::new()
    };
    drop(search);
    // Each listed surfel updated in place on every core: `which` ascends, so its
    // pieces own disjoint parts of `surfels`.
    debug_assert!(which.windows(2).all(|w| w[0] < w[1]), "which ascends");
    let update = |k: usize, i: u32, s: &mut Surfel| -> [u64; 2] {
        let wall = walls
            .binary_search_by_key(&k, |(j, _)| *j)
            .ok()
            .map(|w| &walls[w].1);
        let estimated = given_normal(i) == Vec3::ZERO;
        let at = (points[i as usize] * scale, scale);
        let u = updated(s, &disks[k], (at, wall), estimated.then_some(orientation));
        s.normal = u.normal;
        let mut clipped = false;
        if let Some((radius, shape, clip)) = u.disk {
            (s.radius, s.shape, clipped) = (radius, shape, clip);
        }
        [clipped as u64, u.capped as u64]
    };
    let [clipped, capped] = pieces_of(surfels, which, UPDATE_PIECE)
        .into_par_iter()
        .map(|(first, ids, owned)| {
            let base = ids[0] as usize;
            (ids.iter().enumerate())
                .map(|(j, &i)| update(first + j, i, &mut owned[i as usize - base]))
                .fold([0, 0], |a, b| [a[0] + b[0], a[1] + b[1]])
        })
        .reduce(|| [0, 0], |a, b| [a[0] + b[0], a[1] + b[1]]);
    stats.clipped_boundaries += clipped;
    stats.capped_radii += capped;
    let missing: Vec<u32> = which
        .iter()
        .copied()
        .filter(|&i| surfels[i as usize].radius <= 0.0)
        .collect();
    if !missing.is_empty() {
        let radii: Vec<f32> = surfels.par_iter().map(|s| s.radius).collect();
        let r = fallback_radius(&radii, scale);
        for i in &missing {
            surfels[*i as usize].radius = r;
        }
        stats.fallback_radii += missing.len() as u64;
    }
    let walls: Vec<Surfel> = walls
        .iter()
        .flat_map(|(k, w)| w.surfels(scale, &surfels[which[*k] as usize]))
        .collect();
    stats.wall_splats += walls.len() as u64;
    walls
}

/// Listed points updated per job of [`neighbour_disks`]. Written into in one pass on
/// one thread, the Lucy-size cloud's updates took 0.24 s while the other core idled.
const UPDATE_PIECE: usize = 1 << 12;

/// `which` (ascending) in pieces of at most `size` entries, each with the place of its
/// first entry in `which` and the part of `surfels` from its first listed surfel to
/// its last (disjoint, as the entries ascend).
fn pieces_of<'a>(
    surfels: &'a mut [Surfel],
    which: &'a [u32],
    size: usize,
) -> Vec<(usize, &'a [u32], &'a mut [Surfel])> {
    let (mut rest, mut at) = (surfels, 0);
    let mut pieces = Vec::with_capacity(which.len().div_ceil(size));
    for (p, ids) in which.chunks(size).enumerate() {
        let (first, last) = (ids[0] as usize, ids[ids.len() - 1] as usize);
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(first - at);
        let (owned, tail) = tail.split_at_mut(last + 1 - first);
        pieces.push((p * size, ids, owned));
        (rest, at) = (tail, last + 1);
    }
    pieces
}

/// What a listed point's neighbourhood makes of its surfel: its normal, and where the
/// covering is at least the radius it has, that radius, its packed shape and whether a
/// clip ends it; whether the covering was capped.
struct Update {
    normal: Vec3,
    disk: Option<(f32, SplatShape, bool)>,
    capped: bool,
}

/// The update of surfel `s` from its estimated or given `normal` and covering `c`
/// (unit-scaled, at unit-scaled position `p` in a model of `scale`): the normal turned
/// by `orientation` where it was estimated; the shape clipped at its terrain `wall`, or
/// where its sampling ends.
fn updated(
    s: &Surfel,
    (normal, c): &(Vec3, Covering),
    ((p, scale), wall): ((Vec3, f32), Option<&walls::Wall>),
    orientation: Option<Orientation>,
) -> Update {
    let normal = orientation.map_or(*normal, |o| o.apply(s.position, *normal));
    let radius = c.radius / scale;
    let disk = (radius >= s.radius).then(|| {
        let n = normal.as_dvec3();
        let mut shape = Shape::ellipse(n, c.axis.as_dvec3(), c.ratio as f64);
        shape.clip = match wall {
            Some(w) => w.clip_of(p, (&shape, n, c.radius)),
            None => c.open.map(|d| boundary_clip(&shape, n, d)),
        };
        (radius, shape.pack(), shape.clip.is_some())
    });
    Update {
        normal,
        disk,
        capped: c.capped,
    }
}

/// Each of the points `which`'s normal (given, or fitted to its neighbourhood and, on a
/// quantised frame, smoothed: [`Steps`], which turns its fits before their means) and
/// covering; [`neighbour_disks`] turns every estimated normal after.
fn disks(
    search: &Search,
    (points, scale): (&[Vec3], f32),
    which: &[u32],
    (rule, orientation, progress): (RadiusRule, Orientation, Progress),
    given_normal: &(dyn Fn(u32) -> Vec3 + Sync),
    stats: &mut SurfelStats,
) -> Vec<(Vec3, Covering)> {
    if search.is_empty() {
        vec![(Vec3::Z, covering(Vec3::ZERO, Vec3::Z, &[], rule)); which.len()]
    } else if let Some(steps) = Steps::of(search, scale, orientation) {
        let how = (rule, steps, progress);
        let disks = smoothed_disks(search, (points, scale), which, how, given_normal);
        stats.step_treads += disks.iter().filter(|d| d.0 != d.1).count() as u64;
        disks
            .into_iter()
            .map(|(normal, _, covering)| (normal, covering))
            .collect()
    } else {
        let disk = |&i: &u32, found: &[u32]| {
            let near: ArrayVec<Vec3, K> = found.iter().map(|&f| search.point(f)).collect();
            let normal = Some(given_normal(i))
                .filter(|n| *n != Vec3::ZERO)
                .unwrap_or_else(|| plane_normal(near.iter().copied()));
            let p = points[i as usize] * scale;
            (normal, covering(p, normal, &near, rule))
        };
        search.map_neighbourhoods(which, &|&i| points[i as usize] * scale, &disk, progress)
    }
}

/// Whether each of `points` (unit-scaled by `scale` for the search) has a
/// neighbourhood of [`K`] that scatters in three dimensions rather than lying on a
/// surface ([`super::covering::samples_no_surface`]). The searched samples are told
/// to `progress`.
pub fn scattered(points: &[Vec3], scale: f32, progress: Progress) -> Vec<bool> {
    let search = Search::new(points, scale);
    if search.is_empty() {
        return vec![false; points.len()];
    }
    let distinct: Vec<u32> = (0..search.coords.len() as u32).collect();
    let neighbourhoods: Vec<ArrayVec<u32, K>> = search.map_neighbourhoods(
        &distinct,
        &|&i| search.point(i),
        &|_, found| found.iter().copied().collect(),
        progress,
    );
    let seeds: Vec<bool> = (neighbourhoods.par_iter().enumerate())
        .map(|(i, found)| {
            let p = search.point(i as u32);
            let offsets: ArrayVec<Vec3, K> = found.iter().map(|&f| search.point(f) - p).collect();
            super::covering::samples_no_surface(&offsets)
        })
        .collect();
    let dilated: Vec<bool> = (neighbourhoods.par_iter().zip(&seeds))
        .map(|(found, &seed)| {
            seed || 2 * found.iter().filter(|&&f| seeds[f as usize]).count() > found.len()
        })
        .collect();
    points
        .par_iter()
        .map(|p| {
            search
                .index_of(*p * scale)
                .is_some_and(|i| dilated[i as usize])
        })
        .collect()
}

/// Longest semi-axis of a terrain's splat, in the tile's spacing s (the median of its
/// samples' neighbourhood spacings, [`Covering::spacing`]). The covering gives a sample
/// of a square grid of spacing s a circle of √2 s; 1.5 s leaves 6 % over that.
pub const TILE_SPACINGS: f32 = 1.5;
/// Longest semi-axis of any other cloud's splat, in the cloud's median spacing: the
/// covering's own cap ([`super::covering::MAX_GAP_SPACINGS`]) counts in each point's
/// neighbourhood, which in a sparse scatter (vegetation) is as wide as the gaps it
/// should not close. laspy's `vegetation_1_3.las` (a plant 4 × 6 × 5 m, median spacing
/// 4 cm) had discs up to 1.5 m in radius; held here, 0.33 m (docs/point-clouds.md). A
/// scan whose density falls with range keeps its far samples' coverings while they lie
/// within 8 of its median spacings.
pub const CLOUD_SPACINGS: f32 = 8.0;

/// Holds every semi-axis of `disks` within `spacings` of their median spacing (a
/// terrain's [`TILE_SPACINGS`], any other cloud's [`CLOUD_SPACINGS`]); returns how many
/// it shortened. A minor semi-axis already within the cap is kept.
///
/// An airborne scanner samples the ground evenly, and its triangulation (docs/point-clouds.md's
/// reference) joins no samples further apart than 4 median edges. The covering, counted
/// in each sample's own neighbourhood, does not know the tile: where the returns thin
/// out (water, scan shadows) their neighbourhood spacing grows with them, and their
/// disks closed those gaps by the tens of spacings (autzen_trim's river: one sheet of
/// disks up to 164 feet across, where the reference leaves it open); on the scan lines
/// its major semi-axes reach a median 2.3 s across them (terrain_utm; minor 1.4 s), and
/// blur what the samples resolve. Held to 1.5 s, both tiles' FLIP fell (docs/point-clouds.md)
/// while their holes stayed under 0.4 %: neighbouring splats and pass 3's gap fill close
/// what the shortened axes open.
fn cap_to_spacing(disks: &mut [(Vec3, Covering)], spacings: f32) -> u64 {
    let Some(spacing) = median_of_positive(disks.par_iter().map(|(_, c)| c.spacing)) else {
        return 0;
    };
    let cap = spacings * spacing;
    (disks.par_iter_mut())
        .filter(|(_, c)| c.radius > cap)
        .map(|(_, c)| {
            let minor = c.ratio * c.radius;
            c.ratio = (minor.min(cap) / cap).max(c.ratio);
            c.radius = cap;
        })
        .count() as u64
}

/// Shrinks the `disks` of a sensor frame seen from `sensor` (unit-scaled) to its
/// pixels ([`footprint::cap`]), if its samples lie on a grid of rays.
fn within_pixels(
    search: &Search,
    (points, scale): (&[Vec3], f32),
    which: &[u32],
    sensor: Vec3,
    disks: &mut [(Vec3, Covering)],
    stats: &mut SurfelStats,
) {
    if search.is_empty() {
        return;
    }
    if let Some(pitch) = sensor_pitch(search, (points, scale), which, sensor) {
        for (&i, (n, c)) in which.iter().zip(disks) {
            let p = points[i as usize] * scale;
            stats.footprint_capped += footprint::cap(c, *n, p, sensor, pitch) as u64;
        }
    }
}

/// The pixel pitch of a sensor frame seen from `sensor` ([`footprint::angular_pitch`]),
/// over an evenly strided sample of at most [`PITCH_SAMPLE`] of the points `which`;
/// `None` when they lie on no grid of rays.
fn sensor_pitch(
    search: &Search,
    (points, scale): (&[Vec3], f32),
    which: &[u32],
    sensor: Vec3,
) -> Option<f32> {
    let stride = which.len().div_ceil(PITCH_SAMPLE).max(1);
    let sample: Vec<u32> = which.iter().step_by(stride).copied().collect();
    let pair = |&i: &u32, found: &[u32]| {
        let nearest = found.get(1)?;
        Some((points[i as usize] * scale, search.point(*nearest)))
    };
    let at = |&i: &u32| points[i as usize] * scale;
    let pairs = search.map_neighbourhoods(&sample, &at, &pair, Progress::NONE);
    footprint::angular_pitch(sensor, pairs.into_iter().flatten())
}

/// How many samples [`sensor_pitch`] measures.
const PITCH_SAMPLE: usize = 16_384;

/// Where a boundary splat's kept side ends, major radii from its centre: at the
/// sample itself, as a triangulation of the samples ends at its border vertices.
pub const BOUNDARY_CLIP_OFFSET: f64 = 0.0;

/// The clip of a boundary splat of normal `n` and `shape`, whose sampling ends in the
/// tangent direction `open`: the line ⟂ `open` at [`BOUNDARY_CLIP_OFFSET`]. A sensor
/// frame's or a scan's boundary is an occlusion edge or the scan's end, and the splat's
/// disk beyond it draws surface that nothing sampled. A terrain's too, since its steep
/// edges stand on walls ([`walls`]): before them its boundary disks were left whole to
/// bridge its scan shadows; with walls, clipping them lowers the tile's FLIP by 0.002
/// (`cloud_quality --terrain`: 0.2183 → 0.2164).
fn boundary_clip(shape: &Shape, n: glam::DVec3, open: Vec3) -> Clip {
    let d = open.as_dvec3();
    let normal = shape.along_axes(n, d);
    Clip::Line {
        normal: normal.normalize_or(glam::DVec2::X),
        offset: BOUNDARY_CLIP_OFFSET,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quantised_frame_s_step_treads_take_the_floor_s_slope() {
        // A plane z = 2 + y tan 25° seen by a sensor at the origin looking along +z on
        // a 320 × 240 grid of rays 1/400 apart (samples 5 mm apart), its depth rounded
        // to 11 mm steps: each step's tread is about 5 samples wide, and a
        // neighbourhood that lies on one faces along z whatever the plane's slope.
        let slope = 25f32.to_radians().tan();
        let points: Vec<Vec3> = (0..320 * 240)
            .map(|i| {
                let (u, v) = ((i % 320) as f32 - 160.0, (i / 320) as f32 - 120.0);
                let (u, v) = (u / 400.0, v / 400.0);
                let z = 2.0 / (1.0 - v * slope);
                let z = (z / 0.011).round() * 0.011;
                Vec3::new(u * z, v * z, z)
            })
            .collect();
        let treads = |orientation: Orientation| {
            let surfels = surfels_of(&points, 0.5, orientation);
            let tread = |s: &Surfel| s.normal.z.abs() > 10f32.to_radians().cos();
            surfels.iter().filter(|s| tread(s)).count() as f64 / surfels.len() as f64
        };
        let (frame, fits) = (
            treads(Orientation::Toward(Vec3::ZERO)),
            treads(Orientation::Unknown),
        );
        assert!(fits > 0.05, "the fits' treads: {:.1} %", fits * 100.0);
        assert!(
            frame < 0.5 * fits,
            "treads: {:.1} % of the frame's, {:.1} % of the fits",
            frame * 100.0,
            fits * 100.0
        );
    }

    #[test]
    fn a_sensor_frame_s_splats_span_at_most_a_few_of_its_pixels() {
        // A wall z = 2 seen from the origin on rays 1/400 apart, with every row but
        // one in eight missing on its right half (a sensor's dropouts): there the
        // coverings reach across 8 rows, more than the sensor's pixels let them.
        let pitch = 1.0 / 400.0;
        let points: Vec<Vec3> = (0..200 * 200)
            .filter(|i| i % 200 < 100 || (i / 200) % 8 == 0)
            .map(|i| {
                Vec3::new((i % 200) as f32 - 100.0, (i / 200) as f32 - 100.0, 400.0) * 2.0 * pitch
            })
            .collect();
        let widest = |orientation: Orientation| {
            let surfels = surfels_of(&points, 1.0, orientation);
            // Each semi-axis across the ray, in pitches at the sample's distance.
            let across = |s: &Surfel| {
                let (n, d) = (s.normal.as_dvec3(), s.position.as_dvec3().normalize());
                let shape = s.shape.unpack(n);
                let major = s.radius as f64 * shape.axis.cross(d).length();
                let minor = s.radius as f64 * shape.ratio * shape.minor_axis(n).cross(d).length();
                major.max(minor) / (pitch as f64 * s.position.length() as f64)
            };
            surfels.iter().map(across).fold(0.0, f64::max)
        };
        let (frame, cloud) = (
            widest(Orientation::Toward(Vec3::ZERO)),
            widest(Orientation::Unknown),
        );
        assert!(
            cloud > 2.0 * footprint::MAX_PITCHES as f64,
            "{cloud:.2} pitches"
        );
        assert!(
            frame <= footprint::MAX_PITCHES as f64 * 1.01,
            "{frame:.2} pitches"
        );
    }

    #[test]
    fn a_terrain_s_sparse_returns_get_splats_of_the_tile_s_spacing() {
        // Ground sampled every 1 on a 60 × 60 grid, and beside it a 'river' sampled
        // every 8: its samples' own coverings reach about 8√2, the tile's cap 1.5.
        let ground = (0..60 * 60).map(|i| Vec3::new((i % 60) as f32, (i / 60) as f32, 0.0));
        let river =
            (0..8 * 8).map(|i| Vec3::new(64.0 + (i % 8) as f32 * 8.0, (i / 8) as f32 * 8.0, 0.0));
        let points: Vec<Vec3> = ground.chain(river).collect();
        let largest = |orientation: Orientation, range: std::ops::Range<usize>| {
            let surfels = surfels_of(&points, 0.01, orientation);
            surfels[range].iter().map(|s| s.radius).fold(0.0, f32::max)
        };
        let (inner, sparse) = (0..60 * 60, 60 * 60..points.len());
        let cloud = largest(Orientation::Unknown, sparse.clone());
        let terrain = largest(Orientation::Up, sparse);
        assert!(cloud > 6.0, "an unknown cloud's river splats reach {cloud}");
        assert!(
            terrain <= TILE_SPACINGS * 1.0001,
            "a terrain's river splats reach {terrain}"
        );
        // The ground's own coverings (√2 inside, more on its border) are within the cap.
        let ground = largest(Orientation::Up, inner);
        assert!(
            (1.0..=TILE_SPACINGS * 1.0001).contains(&ground),
            "the ground's splats reach {ground}"
        );
    }

    /// The surfels of the cloud `points` (unit-scaled by `scale`) with its normals
    /// turned by `orientation`.
    fn surfels_of(points: &[Vec3], scale: f32, orientation: Orientation) -> Vec<Surfel> {
        let mut surfels: Vec<Surfel> = points.iter().map(|&p| Surfel::unsized_at(p)).collect();
        let all: Vec<u32> = (0..points.len() as u32).collect();
        let rule = (RadiusRule::Surrounding, orientation, Progress::NONE);
        let mut stats = SurfelStats::default();
        neighbour_disks(points, scale, &all, rule, None, &mut surfels, &mut stats);
        surfels
    }
}
