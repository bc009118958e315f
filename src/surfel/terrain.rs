//! A terrain's splats from its triangulated irregular network (TIN): the 2.5D
//! Delaunay triangulation of its samples in x–y, long triangles dropped
//! ([`crate::io::triangulate::height_field`], the surface docs/point-clouds.md measures
//! a tile's splats against and the one terrain tools hill-shade; kept under a
//! [`Cover`]), drawn as a sensor frame's grid is ([`long_triangles::disks`]).
//!
//! An airborne tile's TIN has two kinds of triangles. Most join samples about the
//! tile's spacing s apart (the median horizontal edge) on a roof, a street or a
//! canopy; their vertices' one-ring ellipses cover them, with the vertex normals'
//! shading field. The rest stand between a roof's edge and the street below it, or a
//! tree's crown and the ground: walls, which the scanner sees edge-on or not at all. A
//! triangle whose longest edge exceeds [`LONG_SPACINGS`] s gets a splat of its own, in
//! its own plane ([`TIN_REACH`]), and a sample on such triangles only keeps a circle of
//! half a spacing's diagonal. A wall's triangles are needles a spacing wide and many
//! high, a tree's a fan of them from its top. Their ellipses are as thin as they are:
//! held to [`super::shape::MIN_RATIO`], as a fitted ellipse is, a mast's needles 1/30
//! as wide as long drew a sail several metres wide across a river. Before, the walls
//! were guessed from each sample's steepest drop among its neighbours (`super::walls`),
//! and each splat was the cloud's covering in the plane of its TIN vertex normal
//! (`super::cloud`, which still draws a terrain without triangles).
//!
//! The triangulation keeps one of the samples that share an x–y (215,298 of
//! terrain_utm's 522,674 samples do, 3 cm apart in height at the median): each other
//! takes the kept one's splat at its own position ([`twins`]), so that every sample of
//! the file is drawn.
//!
//! Why (`cloud_quality --terrain`, 4 views, medians, lavapipe): terrain_utm 0.1531 →
//! 0.1242 (SSIM 0.437 → 0.571), autzen_trim 0.1616 → 0.1270 with the TIN's splats held
//! to MIN_RATIO (long beyond 2 spacings, ellipses of the triangle's area); 0.1191 and
//! 0.1097 as thin as the triangles (see [`LONG_SPACINGS`] and [`TIN_REACH`], whose
//! scans were made then), and 0.1188 and 0.1097 once a node's errors saw its children
//! as ellipses (`crate::tree::errors`, which took level of detail at ε = 1 px from
//! 1.14× and 1.50× the leaves' FLIP to 1.00× and 1.08×).

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::long_triangles::{self, Looks, Reach};
use super::progress::{Progress, Stages};
use super::{Surfel, SurfelStats};
use crate::io::parallel;
use crate::io::triangulate::drop_long;

/// Longest edge, in the tile's spacings, beyond which a TIN triangle gets a splat of
/// its own. With [`TIN_REACH`], terrain_utm / autzen_trim FLIP: 0.1191 / 0.1097 at
/// 1.5; 0.1185 / 0.1135 at 1, which draws 1.23 times the splats (1.06 M against
/// 867 k on terrain_utm); 0.1204 / 0.1090 at 2; 0.1192 / 0.1144 at 0 (every triangle
/// its own splat).
pub const LONG_SPACINGS: f32 = 1.5;

/// A TIN triangle's splat: a wall's 0.85 times its circumellipse (1.75 times its
/// area), any other's the circumellipse, as thin as the triangle. Scales 0.75, 0.8,
/// 0.85, 0.9 and 1 for every long triangle, when a tree's crown still stood on a fan
/// of them: FLIP 0.1209, 0.1197, 0.1191, 0.1188, 0.1193 on terrain_utm and 0.1079,
/// 0.1084, 0.1097, 0.1125, 0.1179 on autzen_trim, where the fans overlapped more the
/// larger they were. Held to MIN_RATIO, a needle's ellipse was too wide, and 0.643 (the
/// triangle's own area, long beyond 2 spacings) scored best: 0.1242 and 0.1270. Where
/// the ground runs on under a bridge deck, its needles span the deck's width; at 0.85
/// their tips left rows of slits beside the deck (the simulated scan's invented surface
/// under the deck 1.7–2.1 % → 0.0–0.6 % with the circumellipse; terrain_utm FLIP 0.1712
/// → 0.1711, autzen_trim 0.1580 → 0.1600).
pub const TIN_REACH: Reach = Reach {
    scale: 1.0,
    wall_scale: 0.85,
    min_ratio: super::shape::MIN_PACKED_RATIO,
    wall_colour_from_above: true,
};

/// The share of [`terrain_disks`]' time, in percent, that its triangles take to be
/// trimmed and ordered before their rings are shaped, for its progress: 0.25 s of 0.91
/// s on the ground of a 2 M-point slice of the generated city (`gen_cloud --points
/// 2000000 --size 400`, 2 cores, Intel, 2026-12-04).
const TRIM_WEIGHT: u32 = 27;

/// The splats of the first `own` of a terrain's `points` (the rest: the halo of a
/// piece, [`crate::tree::out_of_core`]) from their TIN (see the module doc: their
/// `delaunay` triangulation, [`delaunay_xy`](crate::io::delaunay::delaunay_xy), long
/// triangles dropped), into
/// `surfels` (one per point; `given` normals kept; `looks` for the long triangles'
/// splats): returns the splats of the long triangles that the piece owns (the piece of
/// their least corner, [`owner`]). None where the samples make no triangle, or lie
/// closer than a normal f32 apart. A sample that no triangle holds and no twin shares
/// its x–y with (a stray return, a sample in a gap the TIN leaves open) keeps the disk
/// its neighbours give it, as a cloud's, turned up: every sample of the file is drawn,
/// in memory and in out-of-core jobs alike (a mesh leaves out such a vertex where a
/// triangle's splat reaches it, `super::isolated`; which ones a job's splats reach
/// differs from the whole's). The trim and then the shaped vertices are told to
/// `progress` ([`TRIM_WEIGHT`]).
pub fn terrain_disks(
    (points, delaunay, scale): (&[Vec3], Vec<[u32; 3]>, f32),
    (own, cover): (usize, &Cover),
    (given, looks): (Option<&[Vec3]>, Looks),
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> Option<TinSplats> {
    let stages = Stages::new(own, 100, progress);
    let mut triangles = drop_long(points, &delaunay, |c, median| cover.covers(c, median));
    drop(delaunay);
    in_canonical_order(&mut triangles, points.len());
    let spacing = median_horizontal_edge(points, &triangles).filter(|s| s.is_normal())?;
    triangles.par_iter_mut().for_each(|t| {
        let [a, b, c] = t.map(|v| points[v as usize]);
        if (b - a).cross(c - a).z < 0.0 {
            t.swap(1, 2);
        }
    });
    let is_long = |t: &[u32; 3]| long_triangles::longest_edge(points, t) > LONG_SPACINGS * spacing;
    let lone_radius = |_: Vec3| std::f32::consts::FRAC_1_SQRT_2 * spacing;
    stages.ended(TRIM_WEIGHT);
    let share = stages.share(100 - TRIM_WEIGHT);
    let split = long_triangles::disks(
        (points, scale),
        &triangles,
        (is_long, lone_radius),
        given,
        (surfels, own),
        stats,
        Progress::to(&share),
    );
    drop(triangles);
    let isolated = twins(points, &split.isolated, surfels);
    for &v in &isolated {
        let s = &mut surfels[v as usize];
        let estimated = given.is_none_or(|g| g[v as usize] == Vec3::ZERO);
        if estimated && s.normal.z < 0.0 {
            s.normal = -s.normal;
        }
    }
    let owned: Vec<[u32; 3]> = (split.long.into_par_iter())
        .filter(|t| (owner(points, t) as usize) < own)
        .collect();
    let reach = (looks, TIN_REACH);
    let splats = long_triangles::splats(points, scale, &owned, &split.normals, reach);
    stats.triangle_splats = splats.len() as u64;
    Some(TinSplats { splats, spacing })
}

/// The samples of the layers over a terrain's ground (a bridge deck, vegetation): the
/// gap they leave in the ground's samples is their own extent, widened by what they
/// hide from an oblique pulse. Where one of them lies within [`COVER_EDGES`] median
/// edges (in x–y) of a long triangle's centroid, the ground's TIN keeps that triangle:
/// the ground runs on under them.
pub struct Cover {
    tree: Option<ImmutableKdTree<f32, 2>>,
}

/// How near (in x–y, in the TIN's median edges) a covering sample must lie to a long
/// triangle's centroid for the ground's TIN to keep it.
pub const COVER_EDGES: f64 = 2.0;

impl Cover {
    /// No cover: the TIN keeps no long triangle.
    pub fn none() -> Cover {
        Cover { tree: None }
    }

    /// The cover of `points` (none when there are none).
    pub fn of(points: impl Iterator<Item = Vec3>) -> Cover {
        let xy: Vec<[f32; 2]> = points.map(|p| [p.x, p.y]).collect();
        Cover {
            tree: ImmutableKdTree::<f32, 2>::new_from_slice(&xy).ok(),
        }
    }

    /// Whether a covering sample lies within [`COVER_EDGES`] `median` edges of `p`.
    pub fn covers(&self, p: Vec3, median: f64) -> bool {
        self.tree.as_ref().is_some_and(|tree| {
            let nearest = tree
                .query(&[p.x, p.y])
                .nearest_one::<SquaredEuclidean<f32>>()
                .execute();
            (nearest.distance as f64).sqrt() <= COVER_EDGES * median
        })
    }
}

/// What [`terrain_disks`] adds to the samples' own surfels.
pub struct TinSplats {
    /// The long triangles' splats that the piece owns.
    pub splats: Vec<Surfel>,
    /// The tile's spacing: the median horizontal length of its TIN's edges.
    pub spacing: f32,
}

/// Turns each triangle to start at its least corner (its winding kept) and sorts them:
/// the TIN's splats do not depend on the order a triangulation lists its triangles in
/// ([`crate::io::delaunay`] makes them in more than one way). The triangles are grouped
/// by least corner (below `vertex_count`, [`parallel::grouped`]) and each group, of
/// two on average, sorted alone: on a 2.5 M-sample job's 5 M triangles a comparison
/// sort of them all took 0.24 s of one core.
fn in_canonical_order(triangles: &mut Vec<[u32; 3]>, vertex_count: usize) {
    triangles.par_iter_mut().for_each(|t| {
        let least = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
        t.rotate_left(least);
    });
    let grouped = parallel::grouped(
        (vertex_count, triangles.len()),
        |k| triangles[k][0],
        |k| triangles[k],
    );
    *triangles = grouped.1;
    (triangles.par_chunk_by_mut(|a, b| a[0] == b[0])).for_each(|group| group.sort_unstable());
}

/// The median horizontal length of `triangles`' edges; None when there are none. It is
/// the root of the median squared length (√ is monotone and correctly rounded), so
/// each edge's square is all that is selected.
fn median_horizontal_edge(points: &[Vec3], triangles: &[[u32; 3]]) -> Option<f32> {
    let mut squares = vec![[0.0f32; 3]; triangles.len()];
    (squares.par_iter_mut().zip(triangles)).for_each(|(edges, t)| {
        let [a, b, c] = t.map(|v| points[v as usize].truncate());
        *edges = [a - b, b - c, c - a].map(|d| d.length_squared());
    });
    let squares = squares.as_flattened_mut();
    let mid = squares.len().checked_sub(1)? / 2;
    Some(squares.select_nth_unstable_by(mid, f32::total_cmp).1.sqrt())
}

/// The corner of triangle `t` least in (x, y, z) order: the same in every piece that
/// holds the triangle, whatever its indices there.
fn owner(points: &[Vec3], t: &[u32; 3]) -> u32 {
    let key = |v: &&u32| points[**v as usize].to_array();
    let least = t.iter().min_by(|a, b| {
        let (a, b) = (key(a), key(b));
        (a[0].total_cmp(&b[0]))
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
    });
    *least.unwrap_or(&t[0])
}

/// Gives each of the `isolated` vertices (ascending) that shares its x–y with a vertex
/// a triangle holds that vertex's normal, radius and shape, and returns the rest: still
/// isolated.
fn twins(points: &[Vec3], isolated: &[u32], surfels: &mut [Surfel]) -> Vec<u32> {
    if isolated.is_empty() {
        return Vec::new();
    }
    let xy = |v: &u32| {
        let p = points[*v as usize];
        (p.x.to_bits(), p.y.to_bits())
    };
    let mut by_xy: Vec<u32> = (0..points.len() as u32).collect();
    by_xy.par_sort_unstable_by_key(xy);
    let is_isolated = |v: u32| isolated.binary_search(&v).is_ok();
    let mut still = Vec::new();
    for run in by_xy.chunk_by(|a, b| xy(a) == xy(b)) {
        let held = run.iter().copied().find(|&v| !is_isolated(v));
        for &v in run.iter().filter(|&&v| is_isolated(v)) {
            match held {
                Some(h) => {
                    let kept = surfels[h as usize];
                    let s = &mut surfels[v as usize];
                    (s.normal, s.radius, s.shape) = (kept.normal, kept.radius, kept.shape);
                }
                None => still.push(v),
            }
        }
    }
    still.sort_unstable();
    still
}

#[cfg(test)]
mod tests {
    use super::super::cloud::{Orientation, neighbour_disks};
    use super::super::covering::RadiusRule;
    use super::*;
    use crate::io::delaunay::delaunay_xy;

    fn terrain_surfels(points: &[Vec3], scale: f32) -> Vec<Surfel> {
        let mut surfels: Vec<Surfel> = points.iter().map(|&p| Surfel::unsized_at(p)).collect();
        let mut stats = SurfelStats::default();
        let all = points.len();
        terrain_disks(
            (points, delaunay_xy(points), scale),
            (all, &Cover::none()),
            (None, (None, None)),
            &mut surfels,
            &mut stats,
            Progress::NONE,
        )
        .unwrap();
        surfels
    }

    /// An unknown cloud's surfels: normals fitted to their neighbours.
    fn cloud_surfels(points: &[Vec3], scale: f32) -> Vec<Surfel> {
        let mut surfels: Vec<Surfel> = points.iter().map(|&p| Surfel::unsized_at(p)).collect();
        let all: Vec<u32> = (0..points.len() as u32).collect();
        let rule = (
            RadiusRule::Surrounding,
            Orientation::Unknown,
            Progress::NONE,
        );
        let mut stats = SurfelStats::default();
        neighbour_disks(points, scale, &all, rule, None, &mut surfels, &mut stats);
        surfels
    }

    #[test]
    fn a_terrain_s_roof_ridge_stays_sharper_than_its_fits() {
        // A gabled roof z = 9 − |x − 9| sampled as an airborne scan stores it: lines
        // 0.5 apart in y, jittered samples along them (proptest's seeded generator). A
        // terrain's normals (its TIN's, over one ring) must lie nearer each
        // roof plane's than the fits to 24 neighbours (an unknown cloud's normals),
        // which round the ridge off.
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let points: Vec<Vec3> = (0..60 * 40)
            .map(|i| {
                let x = (i % 60) as f32 * 0.3 + rng.random::<f32>() * 0.2;
                let y = (i / 60) as f32 * 0.5 + rng.random::<f32>() * 0.02;
                Vec3::new(x, y, 9.0 - (x - 9.0).abs())
            })
            .collect();
        let plane = |x: f32| Vec3::new((x - 9.0).signum(), 0.0, 1.0).normalize();
        let mean_error = |orientation: Orientation| {
            let surfels = match orientation {
                Orientation::Up => terrain_surfels(&points, 0.05),
                _ => cloud_surfels(&points, 0.05),
            };
            let angles = surfels
                .iter()
                .map(|s| s.normal.dot(plane(s.position.x)).abs().min(1.0).acos());
            angles.sum::<f32>().to_degrees() / points.len() as f32
        };
        let (terrain, fits) = (
            mean_error(Orientation::Up),
            mean_error(Orientation::Unknown),
        );
        eprintln!("mean error: terrain {terrain:.3}°, fits {fits:.3}°");
        assert!(
            terrain < 0.6 * fits,
            "terrain {terrain:.2}° against fits {fits:.2}°"
        );
    }
}
