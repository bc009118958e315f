//! An organised frame's pixel grid, found from its file's row order (docs/design.md §2).
//!
//! An RGB-D camera (PCL's organised clouds, a depth map written out as points) writes
//! one row per pixel, row-major, with NaN where the pixel saw nothing; the reader drops
//! those rows and keeps each sample's file row ([`Geometry::rows`]). Seen from the
//! sensor, file rows r and r + 1 are then horizontal neighbours and r and r + W
//! vertical ones, one pixel pitch apart, where W is the grid's width. The grid is the
//! frame's own neighbourhood: it joins the samples each pixel saw to those its
//! neighbours saw, which no nearest-neighbour search over a quantised depth can tell
//! apart from the next depth step's.
//!
//! [`frame_triangles`] joins the grid's neighbouring pixels ([`sensor_grid_within`]) but
//! not across a depth edge, or a surface seen nearly edge-on ([`MAX_EDGE_PITCHES`]);
//! the frame's splats are then those of this mesh's vertices (`super::mesh`,
//! [`frame_disks`]), over its short triangles, and its long triangles' own
//! (`super::long_triangles`).
//!
//! [`pixel_grid`] finds W as the row offset of most sampled pixels' nearest ray beyond
//! their right-hand neighbour, and accepts it only where most horizontal and vertical
//! neighbours alike lie about one pitch apart: a cloud written in any other order (a
//! scanned mesh's vertices, a tile sorted in space) has no grid.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::isolated;
use super::long_triangles::{self, Reach};
use super::progress::Progress;
use super::{Surfel, SurfelStats};

use crate::io::Geometry;
use crate::io::triangulate::{sensor_grid_within, vertex_at_rows};

/// A frame's pixel grid and the mesh of its neighbouring pixels ([`frame_triangles`]).
pub struct FrameMesh {
    pub grid: PixelGrid,
    /// The grid's pitch, radians ([`pixel_grid`]).
    pub pitch: f32,
    pub triangles: Vec<[u32; 3]>,
}

/// The triangles of frame `g`'s pixel grid seen from `sensor` (relative to the model
/// origin; the file's origin, from which [`sensor_grid_within`] takes depths), if it
/// lies on one ([`pixel_grid`]), all wound to face the sensor: neighbouring pixels
/// joined, but not by an edge longer than [`MAX_EDGE_PITCHES`] at its depth.
pub fn frame_triangles(g: &Geometry, sensor: Vec3) -> Option<FrameMesh> {
    let (grid, pitch) = pixel_grid(g, sensor)?;
    let max_edge = MAX_EDGE_PITCHES * pitch as f64;
    let triangles = sensor_grid_within(g, (grid.width, grid.height), max_edge).ok()?;
    Some(facing_the_sensor(g, sensor, (grid, pitch), triangles))
}

/// The frame mesh of `triangles` on `grid`, all wound to face `sensor` where most of
/// their area faced away.
fn facing_the_sensor(
    g: &Geometry,
    sensor: Vec3,
    (grid, pitch): (PixelGrid, f32),
    mut triangles: Vec<[u32; 3]>,
) -> FrameMesh {
    if facing_away(&g.positions, &triangles, sensor) {
        triangles.par_iter_mut().for_each(|t| t.swap(1, 2));
    }
    FrameMesh {
        grid,
        pitch,
        triangles,
    }
}

/// Frame `g`'s own triangles (a depth frame meshed on its sensor grid, as depth-camera
/// tools write it), if its vertices lie on a pixel grid seen from `sensor`
/// ([`pixel_grid`]): all wound to face the sensor, where most of their area faced
/// away. Drawn as the frame's cloud is, its splats are the cloud's.
pub fn meshed_frame(g: &Geometry, sensor: Vec3) -> Option<FrameMesh> {
    let grid = pixel_grid(g, sensor)?;
    Some(facing_the_sensor(g, sensor, grid, g.triangles.clone()))
}

/// Each vertex's normal for the mesh pass: the file's where it gives one, else
/// normalize(Σ (b − a) × (c − a)) over its triangles (area-weighted face normals,
/// wound as `triangles` are), zero for a vertex of none.
pub fn vertex_normals(
    points: &[Vec3],
    triangles: &[[u32; 3]],
    given: Option<&[Vec3]>,
) -> Vec<Vec3> {
    let mut sums = vec![DVec3::ZERO; points.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| points[v as usize].as_dvec3());
        let cross = (b - a).cross(c - a);
        t.iter().for_each(|&v| sums[v as usize] += cross);
    }
    let given = |v: usize| given.map_or(Vec3::ZERO, |g| g[v]);
    (sums.iter().enumerate())
        .map(|(v, s)| match given(v) {
            Vec3::ZERO => s.normalize_or_zero().as_vec3(),
            n => n,
        })
        .collect()
}

/// The splats of frame `g`'s mesh seen from `sensor` ([`long_triangles::disks`]): a
/// triangle is long beyond [`long_triangles::LONG_PITCHES`] pixel footprints at its
/// depth, and a vertex on long triangles only keeps a circle of its pixel's
/// half-diagonal. Returns the redundant isolated vertices and the long triangles' own
/// splats.
pub fn frame_disks(
    g: &Geometry,
    (mesh, sensor, scale): (&FrameMesh, Vec3, f32),
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> (Vec<u32>, Vec<Surfel>) {
    let points = &g.positions;
    let is_long = is_long_in(points, sensor, mesh.pitch);
    let lone_radius = |p: Vec3| PIXEL_HALF_DIAGONAL * mesh.pitch * (p - sensor).length();
    let all = surfels.len();
    let split = long_triangles::disks(
        (points, scale),
        &mesh.triangles,
        (is_long, lone_radius),
        given,
        (surfels, all),
        stats,
        progress,
    );
    let redundant = isolated::redundant(points, scale, &split.isolated, surfels);
    stats.redundant_vertices = redundant.len() as u64;
    let looks = (g.colors.as_deref(), g.attributes.as_deref());
    let (long, normals) = (&split.long, &split.normals);
    let splats = long_triangles::splats(points, scale, long, normals, (looks, Reach::CORNERS));
    stats.triangle_splats = splats.len() as u64;
    (redundant, splats)
}

/// Whether a triangle of a frame seen from `sensor` with pixel `pitch` is long: its
/// longest edge over [`long_triangles::LONG_PITCHES`] pixel footprints (pitch × depth)
/// at the mean depth of its corners.
fn is_long_in(points: &[Vec3], sensor: Vec3, pitch: f32) -> impl Fn(&[u32; 3]) -> bool + Sync {
    move |t| {
        let depth = t
            .iter()
            .map(|&v| (points[v as usize] - sensor).length())
            .sum::<f32>()
            / 3.0;
        long_triangles::longest_edge(points, t) > long_triangles::LONG_PITCHES * pitch * depth
    }
}

/// A pixel's half-diagonal, in pitches.
const PIXEL_HALF_DIAGONAL: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Whether `triangles` face away from `sensor`, by area. One grid's triangles all wind
/// the same way on the image, so they all face the sensor or all face away (but those
/// seen edge-on, whose sign the sum outweighs).
fn facing_away(points: &[Vec3], triangles: &[[u32; 3]], sensor: Vec3) -> bool {
    let at = |v: u32| points[v as usize].as_dvec3();
    let toward: f64 = triangles
        .par_iter()
        .map(|&[a, b, c]| {
            let n = (at(b) - at(a)).cross(at(c) - at(a));
            n.dot(sensor.as_dvec3() - at(a)).signum() * n.length()
        })
        .sum();
    toward < 0.0
}

/// A frame's pixel grid: file row r is pixel (r mod `width`, r / `width`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct PixelGrid {
    pub width: u32,
    /// Rows up to the last that holds a sample: a frame whose last rows saw nothing
    /// (dropped by the reader, and not counted here) is taller; `spt info` tells its
    /// height from the file's row count.
    pub height: u32,
}

/// Longest edge of a frame's grid triangle, in pixel pitches at its depth. Neighbouring
/// pixels one pitch p apart at depth z that see one surface lie p·z / cos θ apart, θ
/// the angle between the surface's normal and the ray; a longer edge than 17.5 p·z
/// joins pixels that see a surface within 3.3° of edge-on, which the sensor does not
/// resolve, or two surfaces across a depth edge. `cloud_quality
/// ../shared/data/kinect_rgb.ply --grid 640x480` (4 views, medians; its pitch 1.72 mrad,
/// so 17.5 pitches are 3 % of the depth): FLIP 0.1948 at 14 pitches (worst view's holes
/// 1.09 %), 0.1954 at 17.5 (0.27 %), 0.1980 at 21 (0.10 %), 0.2061 at the reference
/// triangulation's own 5 % of the depth (29 pitches; 0.004 %), 0.2264 at 8 %: the
/// reference's long, near edge-on triangles, drawn as splats, are ellipses wider than
/// the pixels that saw them.
pub const MAX_EDGE_PITCHES: f64 = 17.5;

/// Largest ratio of a grid's vertical to its horizontal pitch, or the reverse (a
/// sensor's pixels are about square; kinect_rgb's 1.01). One scan line written sample
/// after sample, whose second neighbours lie 2 pitches away, is no grid of width 2.
const MAX_PITCH_RATIO: f32 = 1.5;

/// The widest grid looked for (a 16 K-pixel-wide sensor).
pub const MAX_WIDTH: usize = 16_384;

/// How many pixels [`pixel_grid`] samples.
const SAMPLE: usize = 256;

/// Least share of the sampled pixels whose horizontal and whose vertical neighbours
/// (where present) must each lie within [`PITCH_TOLERANCE`] of the median pitch.
const MIN_ON_GRID: f64 = 0.75;

/// How far from the median pitch a neighbour on the grid may lie: a factor either way.
const PITCH_TOLERANCE: f32 = 2.0;

/// The pixel grid of a frame `g` seen from `sensor` (relative to the model origin), if
/// its samples lie on one in their file's row order, and its pitch (radians: the larger
/// of the median angles between horizontal and between vertical neighbours).
pub fn pixel_grid(g: &Geometry, sensor: Vec3) -> Option<(PixelGrid, f32)> {
    let n = g.positions.len();
    let row_of = |i: usize| g.rows.as_ref().map_or(i, |r| r[i] as usize);
    let rows = row_of(n.checked_sub(1)?) + 1;
    let vertex_at = vertex_at_rows(g, rows);
    let ray = |r: usize| {
        let v = *vertex_at.get(r)?;
        (v != u32::MAX).then(|| (g.positions[v as usize] - sensor).normalize_or_zero())
    };
    let angle = |a: Vec3, b: Vec3| 2.0 * (0.5 * a.distance(b)).min(1.0).asin();
    let sample: Vec<usize> = (0..n)
        .step_by(n.div_ceil(SAMPLE).max(1))
        .map(row_of)
        .collect();
    let width = likeliest_width(&sample, rows, &ray, &angle)?;
    let spacing = |d: usize| -> Vec<Option<f32>> {
        let same_line = |r: usize| d != 1 || !(r + 1).is_multiple_of(width);
        sample
            .iter()
            .map(|&r| Some(angle(ray(r)?, ray(r + d).filter(|_| same_line(r))?)))
            .collect()
    };
    let (across, down) = (spacing(1), spacing(width));
    let (pitch_across, pitch_down) = (median(&across)?, median(&down)?);
    // Samples along one ray (a pitch of 0) or pitches far apart make no grid.
    let tolerable = pitch_across.min(pitch_down) > 0.0
        && pitch_across.max(pitch_down) <= MAX_PITCH_RATIO * pitch_across.min(pitch_down);
    let on_grid = |angles: &[Option<f32>], pitch: f32| {
        let near = |a: &f32| *a <= PITCH_TOLERANCE * pitch && *a >= pitch / PITCH_TOLERANCE;
        let present: Vec<f32> = angles.iter().flatten().copied().collect();
        present.iter().filter(|a| near(a)).count() as f64 >= MIN_ON_GRID * present.len() as f64
    };
    (tolerable && on_grid(&across, pitch_across) && on_grid(&down, pitch_down)).then(|| {
        let grid = PixelGrid {
            width: width as u32,
            height: rows.div_ceil(width) as u32,
        };
        (grid, pitch_across.max(pitch_down))
    })
}

/// The row offset d (2 ≤ d ≤ [`MAX_WIDTH`]) of the ray nearest each sampled row's,
/// taken by the most sampled rows: the grid's width, where there is one. `None` when
/// fewer than half the rows that found one agree.
fn likeliest_width(
    sample: &[usize],
    rows: usize,
    ray: &dyn Fn(usize) -> Option<Vec3>,
    angle: &dyn Fn(Vec3, Vec3) -> f32,
) -> Option<usize> {
    let mut votes = std::collections::BTreeMap::<usize, usize>::new();
    for &r in sample {
        let Some(here) = ray(r) else { continue };
        let nearest = (2..=MAX_WIDTH.min(rows.saturating_sub(r + 1)))
            .filter_map(|d| Some((angle(here, ray(r + d)?), d)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, d)) = nearest {
            *votes.entry(d).or_default() += 1;
        }
    }
    let cast: usize = votes.values().sum();
    let (width, count) = votes
        .into_iter()
        .max_by_key(|&(d, c)| (c, std::cmp::Reverse(d)))?;
    (2 * count >= cast && cast > 0).then_some(width)
}

/// The median of the present values.
fn median(values: &[Option<f32>]) -> Option<f32> {
    let mut v: Vec<f32> = values.iter().flatten().copied().collect();
    v.sort_unstable_by(f32::total_cmp);
    v.get(v.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pitch of the test frames' pixels, radians.
    const PITCH: f64 = 0.002;

    /// A `width` × `height` frame seen from the file's origin, row-major: pixel (x, y)
    /// sees depth `depth(x, y)` (NaN: nothing) along its ray.
    fn frame(width: usize, height: usize, depth: impl Fn(usize, usize) -> f64) -> Vec<[f64; 3]> {
        let mut points = Vec::new();
        for y in 0..height {
            for x in 0..width {
                let u = (x as f64 - width as f64 / 2.0) * PITCH;
                let v = (y as f64 - height as f64 / 2.0) * PITCH;
                let z = depth(x, y);
                points.push([u * z, v * z, z]);
            }
        }
        points
    }

    fn geometry(points: &[[f64; 3]]) -> (Geometry, Vec3) {
        let g = Geometry::from_points(points).unwrap().0;
        let sensor = (-g.origin).as_vec3();
        (g, sensor)
    }

    /// A floor-like slope, every 7th pixel and the last 5 rows without depth.
    fn sloped(x: usize, y: usize) -> f64 {
        if (x + 3 * y).is_multiple_of(7) || y >= 43 {
            f64::NAN
        } else {
            2.0 + 0.004 * y as f64 + 0.001 * x as f64
        }
    }

    #[test]
    fn a_frame_written_row_by_row_lies_on_its_grid() {
        let (g, sensor) = geometry(&frame(64, 48, sloped));
        let (grid, _) = pixel_grid(&g, sensor).expect("a grid");
        assert_eq!((grid.width, grid.height), (64, 43));
    }

    #[test]
    fn the_same_samples_in_another_order_lie_on_no_grid() {
        let points = frame(64, 48, sloped);
        let n = points.len();
        // 1009 is prime to n = 3072: a permutation.
        let shuffled: Vec<[f64; 3]> = (0..n).map(|i| points[i * 1009 % n]).collect();
        let (g, sensor) = geometry(&shuffled);
        assert_eq!(pixel_grid(&g, sensor), None);
    }

    #[test]
    fn samples_along_one_ray_or_one_line_lie_on_no_grid() {
        // Every pixel on the optical axis, at its own depth.
        let on_axis: Vec<[f64; 3]> = (0..3072)
            .map(|i| [0.0, 0.0, 1.0 + i as f64 * 1e-3])
            .collect();
        let (g, sensor) = geometry(&on_axis);
        assert_eq!(pixel_grid(&g, sensor), None);
        // One scan line, written pixel after pixel.
        let (g, sensor) = geometry(&frame(3072, 1, |_, _| 2.0));
        assert_eq!(pixel_grid(&g, sensor), None);
    }

    #[test]
    fn a_depth_edge_is_not_joined_and_every_triangle_faces_the_sensor() {
        let near = |x: usize| x < 32;
        let (g, sensor) = geometry(&frame(64, 48, |x, _| if near(x) { 1.0 } else { 2.0 }));
        let triangles = frame_triangles(&g, sensor).expect("a grid").triangles;
        let at = |v: u32| g.positions[v as usize];
        let depth = |v: u32| (at(v) - sensor).length();
        assert_eq!(triangles.len(), 2 * 2 * 31 * 47);
        for &[a, b, c] in &triangles {
            let sides = [a, b, c].map(|v| depth(v) < 1.5);
            assert!(
                sides.iter().all(|s| *s == sides[0]),
                "{a} {b} {c} join the edge"
            );
            let n = (at(b) - at(a)).cross(at(c) - at(a));
            assert!(n.dot(sensor - at(a)) > 0.0, "{a} {b} {c} faces away");
        }
    }

    #[test]
    fn a_frame_s_splats_do_not_bridge_its_depth_edge() {
        let points = frame(64, 48, |x, _| if x < 32 { 1.0 } else { 2.0 });
        let g = Geometry::from_points(&points).unwrap().0;
        let leaves = crate::surfel::leaf_surfels(&g);
        assert_eq!(leaves.stats.pixel_grid.map(|p| p.width), Some(64));
        let sensor = (-g.origin).as_vec3();
        for s in &leaves.surfels {
            let depth = (s.position - sensor).length() as f64;
            // A pixel's neighbours lie one pitch away, its diagonal ones √2.
            assert!(
                (s.radius as f64) < 2.0 * PITCH * depth,
                "radius {} at depth {depth}",
                s.radius
            );
        }
    }

    #[test]
    fn a_depth_step_s_riser_is_drawn_by_its_own_splats_and_no_vertex_s_reaches_along_it() {
        // A floor whose depth is quantised: every 4 rows it steps 4 cm back, 10 pixel
        // footprints at its depth (over long_triangles::LONG_PITCHES). A vertex's
        // ellipse that covered its riser triangles would reach 5 footprints.
        let points = frame(64, 48, |_, y| 2.0 + 0.04 * (y / 4) as f64);
        let g = Geometry::from_points(&points).unwrap().0;
        let leaves = crate::surfel::leaf_surfels(&g);
        let sensor = (-g.origin).as_vec3();
        let mesh = frame_triangles(&g, sensor).unwrap();
        let is_long = is_long_in(&g.positions, sensor, mesh.pitch);
        let long: Vec<&[u32; 3]> = mesh.triangles.iter().filter(|t| is_long(t)).collect();
        // 11 risers of 63 pixel pairs, two triangles each.
        assert_eq!(long.len(), 11 * 63 * 2);
        assert_eq!(leaves.stats.triangle_splats, long.len() as u64);
        assert_eq!(leaves.surfels.len(), points.len() + long.len());
        for s in &leaves.surfels[..points.len()] {
            let depth = (s.position - sensor).length() as f64;
            assert!(
                (s.radius as f64) < 2.5 * PITCH * depth,
                "a vertex's radius {} at depth {depth}",
                s.radius
            );
        }
        let at = |v: u32| g.positions[v as usize];
        for t in &long {
            let [a, b, c] = t.map(at);
            for p in [
                (a + b + c) / 3.0,
                (a + b) / 2.0,
                (b + c) / 2.0,
                (c + a) / 2.0,
            ] {
                let p = p + ((a + b + c) / 3.0 - p) * 0.01;
                assert!(
                    leaves.surfels.iter().any(|s| s.covers(p)),
                    "{p} on a riser left uncovered"
                );
            }
        }
    }
}
