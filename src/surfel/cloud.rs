//! Surfels of a point cloud from its k nearest neighbours (kiddo's k-d tree), made to
//! hold on real sampling: scan lines, quantised coordinates, rows of an RGB-D frame
//! sparser than its columns, stray samples.
//!
//! * normal: the smallest principal axis of the neighbourhood (self + [`K`] − 1
//!   neighbours: enough to span several scan lines), unless the file gives a non-zero
//!   one; on a terrain, the mean of its neighbours' ([`terrain_disks`]); oriented
//!   afterwards where a direction is known ([`Orientation`]);
//! * radius and ellipse: the covering of [`super::covering`], from the same
//!   neighbourhood; a capped one is counted ([`SurfelStats::capped_radii`]);
//! * clip: a splat on a boundary of the sampling ends there ([`boundary_clip`]), a
//!   terrain's edge sample at its wall (counted: [`SurfelStats::clipped_boundaries`]);
//! * walls: a terrain's steep edges stand on wall surfels of their own ([`walls`]).
//!
//! Duplicated samples do not shrink a radius (only distinct neighbours count). A surfel
//! whose neighbours all coincide with it takes the median radius of the others
//! ([`fallback_radius`]).

use std::num::NonZero;

use arrayvec::ArrayVec;
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::covering::{Covering, RadiusRule, covering};
use super::pca::plane_normal;
use super::shape::{Clip, Shape};
use super::walls;
use super::{Surfel, SurfelStats};

/// Neighbourhood size, the point itself included. An RGB-D frame's quantised depth
/// puts a 16-neighbourhood at its far wall on one step of one row, whose normal faces
/// the sensor and whose ellipse leaves streaks of holes between the steps; 24 see the
/// next step (issue 13: the frame's holes 0.93 % → 0.10 %).
pub const K: usize = 24;

/// Radius for surfels without a measured one: the median of the measured radii, or
/// 1/1024 of the model's extent (of one unit for a model without extent) when none was.
pub fn fallback_radius(radii: &[f32], scale: f32) -> f32 {
    let mut measured: Vec<f32> = radii
        .iter()
        .copied()
        .filter(|r| *r > 0.0 && r.is_finite())
        .collect();
    if measured.is_empty() {
        return 1.0 / 1024.0 / scale;
    }
    let mid = measured.len() / 2;
    *measured.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The distinct positions of a cloud, unit-scaled and sorted by [`position_key`], and
/// the k-d tree its neighbourhoods are searched in.
struct Search {
    coords: Vec<[f32; 3]>,
    /// `None` when no tree could be built: every disk is left to the fallbacks.
    tree: Option<ImmutableKdTree<f32, 3>>,
    /// [`K`], or fewer when the cloud has fewer distinct positions.
    k: NonZero<usize>,
}

/// A position's sort key: its coordinates' bits, −0 counted as +0.
fn position_key(c: &[f32; 3]) -> [u32; 3] {
    c.map(|x| if x == 0.0 { 0 } else { x.to_bits() })
}

impl Search {
    /// The distinct positions among `points`, scaled by `scale`. Searching among
    /// distinct positions keeps each query O(log n) however many samples coincide (10⁵
    /// copies of one point would otherwise make the search quadratic), and coinciding
    /// samples add nothing to a neighbourhood's shape.
    fn new(points: &[Vec3], scale: f32) -> Search {
        // Scaled coordinates stay within ±2⁶⁰ (`super::unit_scale`): squared distances fit f32.
        let mut coords: Vec<[f32; 3]> =
            points.par_iter().map(|p| (*p * scale).to_array()).collect();
        coords.par_sort_unstable_by_key(position_key);
        coords.dedup_by_key(|c| position_key(c));
        let tree = ImmutableKdTree::<f32, 3>::new_from_slice(&coords).ok();
        let k = NonZero::new(K.min(coords.len())).unwrap_or(NonZero::<usize>::MIN);
        Search { coords, tree, k }
    }

    fn point(&self, i: u32) -> Vec3 {
        Vec3::from(self.coords[i as usize])
    }

    /// The neighbourhoods of `queries` (nearest first), in blocks of [`QUERY_BLOCK`].
    fn neighbourhoods<'s, Q: Sync>(
        &'s self,
        queries: &'s [Q],
        position: &'s (dyn Fn(&Q) -> Vec3 + Sync),
    ) -> impl ParallelIterator<Item = (&'s Q, ArrayVec<u32, K>)> + 's {
        queries.par_chunks(QUERY_BLOCK).flat_map_iter(move |block| {
            let found = self
                .tree
                .as_ref()
                .map(|tree| nearest_in_order(tree, self.k, block.iter().map(position)));
            block.iter().zip(found.into_iter().flatten())
        })
    }
}

/// Normal, radius and ellipse from the neighbours of each point listed in `which`, searching
/// among all `points` (unit-scaled by `scale` for the search), written into `surfels`.
/// Non-zero `given` normals are kept, the estimated ones turned by `orientation` (on a
/// terrain, smoothed first: [`terrain_disks`]); a radius already set (from faces) is
/// only grown. A boundary splat ends where its sampling does ([`boundary_clip`]), a
/// terrain's edge sample where its wall stands ([`walls`]). Afterwards every listed
/// surfel whose radius is still 0 gets [`fallback_radius`]. Returns a terrain's wall
/// surfels (none for any other cloud).
pub fn neighbour_disks(
    points: &[Vec3],
    scale: f32,
    which: &[u32],
    (rule, orientation): (RadiusRule, Orientation),
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
) -> Vec<Surfel> {
    if which.is_empty() {
        return Vec::new();
    }
    let search = Search::new(points, scale);
    let given_normal = |i: u32| given.map_or(Vec3::ZERO, |g| g[i as usize]);
    let disks: Vec<(Vec3, Covering)> = if search.tree.is_none() {
        vec![(Vec3::Z, covering(Vec3::ZERO, Vec3::Z, &[], rule)); which.len()]
    } else if orientation == Orientation::Up {
        terrain_disks(&search, (points, scale), which, rule, &given_normal)
    } else {
        search
            .neighbourhoods(which, &|&i| points[i as usize] * scale)
            .map(|(&i, found)| {
                let near: ArrayVec<Vec3, K> = found.iter().map(|&f| search.point(f)).collect();
                let normal = Some(given_normal(i))
                    .filter(|n| *n != Vec3::ZERO)
                    .unwrap_or_else(|| plane_normal(near.iter().copied()));
                let p = points[i as usize] * scale;
                (normal, covering(p, normal, &near, rule))
            })
            .collect()
    };
    // Each wall with its sample's index in `which`, ascending (none but on a terrain).
    let walls = if orientation == Orientation::Up && search.tree.is_some() {
        let queries: Vec<Vec3> = which.iter().map(|&i| points[i as usize] * scale).collect();
        walls::terrain_walls(&search.coords, &queries)
    } else {
        Vec::new()
    };
    let mut next_wall = walls.iter().peekable();
    for (k, (&i, (normal, c))) in which.iter().zip(disks).enumerate() {
        let wall = next_wall.next_if(|(j, _)| *j == k).map(|(_, w)| w);
        let s = &mut surfels[i as usize];
        let estimated = given_normal(i) == Vec3::ZERO;
        s.normal = if estimated {
            orientation.apply(s.position, normal)
        } else {
            normal
        };
        let radius = c.radius / scale;
        if radius >= s.radius {
            s.radius = radius;
            let n = s.normal.as_dvec3();
            let mut shape = Shape::ellipse(n, c.axis.as_dvec3(), c.ratio as f64);
            let p = points[i as usize] * scale;
            shape.clip = match wall {
                Some(w) => w.clip_of(p, (&shape, n, c.radius)),
                None => c.open.map(|d| boundary_clip(&shape, n, d)),
            };
            stats.clipped_boundaries += shape.clip.is_some() as u64;
            s.shape = shape.pack();
        }
        stats.capped_radii += c.capped as u64;
    }
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

/// A terrain's disks: each sample's normal is the mean of its neighbours' fitted
/// normals (each the plane of its own neighbourhood, turned up), and its covering is
/// measured in the plane of its own fit, where its sampling's gaps lie.
///
/// An airborne scan's lines and quantised steps turn one neighbourhood's plane at
/// random, and at 1–2 pixels a splat such planes read as dark blotches across the
/// roofs and streets, where the 2.5D triangulation of the same samples shades with
/// vertex normals averaged over each one-ring. Averaged once over the neighbourhood
/// (issue 13, `cloud_quality --terrain`, 4 views, medians): FLIP 0.2572 → 0.2280, SSIM
/// 0.172 → 0.242, holes 0.167 % → 0.221 % (worst view 0.483 % → 0.468 %). Not done on
/// other clouds: on the RGB-D frame, whose reference shades the ridges of its
/// quantised depth, the same mean (turned toward the sensor) raised FLIP (0.2983 →
/// 0.3299) and opened holes (up to 2.8 % on a view). Each sample's neighbourhood is
/// kept between the two steps (K indices, 100 bytes a sample) rather than searched
/// twice (+35 % of the surfels' time on the tile, for 27 MB less at its peak).
fn terrain_disks(
    search: &Search,
    (points, scale): (&[Vec3], f32),
    which: &[u32],
    rule: RadiusRule,
    given_normal: &(dyn Fn(u32) -> Vec3 + Sync),
) -> Vec<(Vec3, Covering)> {
    // Every sample's neighbourhood, halo included, in the samples' own order (which
    // keeps `nearest_in_order`'s bounds tight); its nearest is its own position.
    let neighbourhoods: Vec<ArrayVec<u32, K>> = search
        .neighbourhoods(points, &|p| *p * scale)
        .map(|(_, found)| found)
        .collect();
    let near = |i: usize| neighbourhoods[i].iter().map(|&f| search.point(f));
    // Each distinct position's fit, up (its samples' neighbourhoods are the same).
    let mut fitted = vec![Vec3::ZERO; search.coords.len()];
    let fits: Vec<Vec3> = (0..points.len())
        .into_par_iter()
        .map(|i| Orientation::Up.apply(Vec3::ZERO, plane_normal(near(i))))
        .collect();
    for (found, fit) in neighbourhoods.iter().zip(fits) {
        if let Some(&own) = found.first() {
            fitted[own as usize] = fit;
        }
    }
    which
        .par_iter()
        .map(|&i| {
            let found = &neighbourhoods[i as usize];
            let own = found.first().map_or(Vec3::Z, |&c| fitted[c as usize]);
            let given = given_normal(i);
            let (normal, plane) = if given != Vec3::ZERO {
                (given, given)
            } else {
                let mean = found.iter().skip(1).map(|&f| fitted[f as usize]);
                (mean.sum::<Vec3>().normalize_or(own), own)
            };
            let near: ArrayVec<Vec3, K> = near(i as usize).collect();
            (
                normal,
                covering(points[i as usize] * scale, plane, &near, rule),
            )
        })
        .collect()
}

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
    let normal = glam::DVec2::new(d.dot(shape.axis), d.dot(shape.minor_axis(n)));
    Clip::Line {
        normal: normal.normalize_or(glam::DVec2::X),
        offset: BOUNDARY_CLIP_OFFSET,
    }
}

/// Queries walked in order, in blocks of this many: each block's first query searches
/// the whole tree, the others within the bound that their predecessor gives. Fixed
/// blocks keep the result independent of how rayon splits the work.
const QUERY_BLOCK: usize = 1024;

/// The k nearest positions' indices (nearest first) of each of `queries`, taken in
/// order. Consecutive queries of a scan's or a generator's order lie near each other:
/// by the triangle inequality the k-th neighbour of p lies within r + |p − q| of p,
/// where r is the k-th neighbour's distance from the previous query q, so each search
/// after the first prunes from its first step.
fn nearest_in_order<'t>(
    tree: &'t ImmutableKdTree<f32, 3>,
    k: NonZero<usize>,
    queries: impl Iterator<Item = Vec3> + 't,
) -> impl Iterator<Item = ArrayVec<u32, K>> + 't {
    let mut scratch = tree.create_scratch::<SquaredEuclidean<f32>>();
    let mut last: Option<(Vec3, f32)> = None;
    queries.map(move |p| {
        // The relative margin absorbs f32 rounding of the distances (unit-scaled model).
        let bound = last.map_or(f32::INFINITY, |(q, r)| (r + p.distance(q)) * (1.0 + 1e-5));
        let mut search = |bound: f32| {
            tree.query(&p.to_array())
                .nearest_n::<SquaredEuclidean<f32>>(k)
                .within(bound * bound)
                .with_scratch(&mut scratch)
                .execute()
        };
        let mut found = search(bound);
        if found.len() < k.get() {
            found = search(f32::INFINITY);
        }
        last = found.last().map(|f| (p, f.distance.sqrt()));
        found.iter().map(|f| f.item).take(K).collect()
    })
}

/// Which way a cloud's estimated normals face, where the data tells: sign consistency
/// lets the tree's inner nodes average their children's normals without cancelling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// An airborne tile (far wider than it is high): +z.
    Up,
    /// A sensor frame: toward the sensor, at this point (relative to the model origin).
    Toward(Vec3),
    /// Nothing known: drawn two-sided as they are.
    Unknown,
}

/// Which way a model's normals were turned when its surfels were estimated: what the
/// renderer must know of the [`Orientation`] (a `.spt` file stores it from version 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalsTurned {
    /// Not turned: a mesh's, given ones, or a cloud's of unknown orientation (drawn
    /// two-sided).
    #[default]
    No,
    /// A terrain's, up: a splat's underside is the ground's, weighed as a mesh's back.
    Up,
    /// A sensor frame's, toward the file's origin, where the sensor stood.
    TowardOrigin,
}

impl NormalsTurned {
    /// How estimated normals facing `orientation` were turned.
    pub fn of(orientation: Orientation) -> NormalsTurned {
        match orientation {
            Orientation::Up => NormalsTurned::Up,
            Orientation::Toward(_) => NormalsTurned::TowardOrigin,
            Orientation::Unknown => NormalsTurned::No,
        }
    }
}

/// A model whose core is less than a quarter as high as it is wide is a terrain.
const TERRAIN_ASPECT: f64 = 0.25;

impl Orientation {
    /// The orientation of a cloud with core box `core`, whole box `bounds` and
    /// `origin`: up for a terrain; toward the file's origin (where a sensor writes its
    /// frame from) when that lies outside the box and within 100 core extents of it.
    pub fn of(core: &crate::io::Bounds, bounds: &crate::io::Bounds, origin: glam::DVec3) -> Self {
        let e = core.extent();
        let width = e.x.max(e.y);
        if width > 0.0 && e.z < TERRAIN_ASPECT * width {
            return Orientation::Up;
        }
        let sensor = -origin;
        let far = sensor.length() > 100.0 * e.max_element();
        if bounds.contains([0.0; 3]) || far || !sensor.is_finite() {
            return Orientation::Unknown;
        }
        Orientation::Toward(sensor.as_vec3())
    }

    /// `normal` flipped, if need be, to face this way from `position`.
    pub fn apply(self, position: Vec3, normal: Vec3) -> Vec3 {
        let facing = match self {
            Orientation::Up => Vec3::Z,
            Orientation::Toward(sensor) => sensor - position,
            Orientation::Unknown => return normal,
        };
        if normal.dot(facing) < 0.0 {
            -normal
        } else {
            normal
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounded_queries_find_the_same_neighbourhoods_as_unbounded_ones() {
        // A wavy sheet on a jittered grid (proptest's seeded generator), queried in its
        // own order and in a shuffled one (far consecutive queries: loose bounds).
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let mut next = || rng.random::<f32>();
        let coords: Vec<[f32; 3]> = (0..4096)
            .map(|i| {
                let (x, y) = ((i % 64) as f32 + next(), (i / 64) as f32 + next());
                [x / 64.0, y / 64.0, 0.05 * (x * 0.3).sin() * (y * 0.2).cos()]
            })
            .collect();
        let tree = ImmutableKdTree::<f32, 3>::new_from_slice(&coords).unwrap();
        let k = NonZero::new(K).unwrap();
        let distances = |p: Vec3, found: &[u32]| -> Vec<f32> {
            found
                .iter()
                .map(|&f| p.distance(Vec3::from(coords[f as usize])))
                .collect()
        };
        let shuffled: Vec<usize> = (0..coords.len()).map(|i| i * 1237 % coords.len()).collect();
        for order in [(0..coords.len()).collect::<Vec<_>>(), shuffled] {
            let queries: Vec<Vec3> = order.iter().map(|&i| Vec3::from(coords[i])).collect();
            for (p, found) in
                queries
                    .iter()
                    .zip(nearest_in_order(&tree, k, queries.iter().copied()))
            {
                let all = tree
                    .query(&p.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                let plain: Vec<u32> = all.iter().map(|f| f.item).collect();
                assert_eq!(distances(*p, &found), distances(*p, &plain), "at {p}");
            }
        }
    }

    #[test]
    fn a_terrain_on_scan_lines_and_height_steps_gets_smoother_normals_than_its_fits() {
        // A slope z = 0.2 x sampled as an airborne scan stores it: lines 0.5 apart in y,
        // jittered samples along them, heights quantised to 0.1 (proptest's seeded
        // generator). A terrain's normals (the mean of the neighbours' fits) must lie
        // nearer the slope's than the fits themselves (an unknown cloud's normals).
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let points: Vec<Vec3> = (0..60 * 40)
            .map(|i| {
                let x = (i % 60) as f32 * 0.3 + rng.random::<f32>() * 0.2;
                let y = (i / 60) as f32 * 0.5 + rng.random::<f32>() * 0.02;
                Vec3::new(x, y, (0.2 * x / 0.1).round() * 0.1)
            })
            .collect();
        let slope = Vec3::new(-0.2, 0.0, 1.0).normalize();
        let mean_error = |orientation: Orientation| {
            let mut surfels: Vec<Surfel> = points
                .iter()
                .map(|&position| Surfel {
                    position,
                    radius: 0.0,
                    normal: Vec3::ZERO,
                    color: super::super::DEFAULT_COLOR,
                    shape: bytemuck::Zeroable::zeroed(),
                    attributes: Default::default(),
                })
                .collect();
            let all: Vec<u32> = (0..points.len() as u32).collect();
            let rule = (RadiusRule::Surrounding, orientation);
            let mut stats = SurfelStats::default();
            neighbour_disks(&points, 0.05, &all, rule, None, &mut surfels, &mut stats);
            let angles = surfels
                .iter()
                .map(|s| s.normal.dot(slope).abs().min(1.0).acos());
            angles.sum::<f32>().to_degrees() / points.len() as f32
        };
        let (terrain, fits) = (
            mean_error(Orientation::Up),
            mean_error(Orientation::Unknown),
        );
        assert!(
            terrain < 0.6 * fits,
            "terrain {terrain:.2}° against fits {fits:.2}°"
        );
    }

    #[test]
    fn a_flat_tile_faces_up_and_a_sensor_frame_faces_its_sensor() {
        use crate::io::Bounds;
        let tile = Bounds {
            min: [500.0, 700.0, 10.0],
            max: [900.0, 1100.0, 40.0],
        };
        let o = Orientation::of(&tile, &tile, tile.center());
        assert_eq!(o, Orientation::Up);
        assert_eq!(o.apply(Vec3::ZERO, -Vec3::Z), Vec3::Z);
        let frame = Bounds {
            min: [-1.0, -1.0, 1.0],
            max: [1.0, 1.0, 3.0],
        };
        let o = Orientation::of(&frame, &frame, frame.center());
        assert_eq!(o, Orientation::Toward(Vec3::new(0.0, 0.0, -2.0)));
        assert_eq!(o.apply(Vec3::ZERO, Vec3::Z), -Vec3::Z);
        let around = Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        };
        assert_eq!(
            Orientation::of(&around, &around, glam::DVec3::ZERO),
            Orientation::Unknown
        );
    }
}
