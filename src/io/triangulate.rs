//! Triangle meshes of face-less clouds, made without normals, for reference images: what
//! a cloud's splats are measured against, drawn by the mesh pass.
//!
//! * [`sensor_grid`]: an organised cloud (an RGB-D frame: one row per pixel, row-major,
//!   invalid pixels dropped by the reader) joins neighbouring valid pixels. Each 2×2 block
//!   of pixels gives two triangles split along its shorter diagonal, or one when a
//!   corner is missing; a triangle with an edge longer than [`GRID_MAX_EDGE`] of its
//!   depth (the distance from the sensor, at the file's origin) spans a depth
//!   discontinuity and is dropped.
//! * [`terrain`]: an airborne tile is a height field: Delaunay in x–y, triangles with an
//!   edge (in x–y) longer than [`TERRAIN_MAX_EDGE`] × the median edge dropped (gaps,
//!   water, the hull's slivers). A terrain's splats shade with the same triangles'
//!   normals (`surfel::cloud::tin`).

use glam::Vec3;
use rayon::prelude::*;

use super::Geometry;
use super::delaunay::delaunay_xy;
use super::parallel;

/// Longest edge of a sensor-grid triangle, relative to its depth.
pub const GRID_MAX_EDGE: f64 = 0.05;
/// Longest edge of a terrain triangle, in median edges.
pub const TERRAIN_MAX_EDGE: f64 = 4.0;

/// Triangles of `geometry` as a `width` × `height` sensor grid, the vertex of file row
/// `row` at pixel (row mod width, row / width), none with an edge longer than
/// [`GRID_MAX_EDGE`] of its depth. Fails when the file has more rows than the grid has
/// pixels.
pub fn sensor_grid(geometry: &Geometry, width: u32, height: u32) -> Result<Vec<[u32; 3]>, String> {
    sensor_grid_within(geometry, (width, height), GRID_MAX_EDGE)
}

/// The vertex of each of the first `rows` file rows (`Geometry::rows`: the reader drops
/// rows without a position, so a frame's pixel is the row it came from), `u32::MAX`
/// where the file's row was dropped. Every vertex's row must be below `rows`.
pub fn vertex_at_rows(geometry: &Geometry, rows: usize) -> Vec<u32> {
    let row_of = |i: usize| geometry.rows.as_ref().map_or(i, |r| r[i] as usize);
    let mut vertex_at = vec![u32::MAX; rows];
    for i in 0..geometry.positions.len() {
        vertex_at[row_of(i)] = i as u32;
    }
    vertex_at
}

/// [`sensor_grid`], with no edge longer than `max_edge` of its triangle's depth.
pub fn sensor_grid_within(
    geometry: &Geometry,
    (width, height): (u32, u32),
    max_edge: f64,
) -> Result<Vec<[u32; 3]>, String> {
    let pixels = width as usize * height as usize;
    let n = geometry.positions.len();
    let row_of = |i: usize| geometry.rows.as_ref().map_or(i, |r| r[i] as usize);
    if n == 0 || row_of(n - 1) >= pixels {
        return Err(format!(
            "{n} points do not lie on a {width}×{height} grid (row {} is beyond it)",
            row_of(n.saturating_sub(1))
        ));
    }
    let vertex_at = vertex_at_rows(geometry, pixels);
    let position = |v: u32| geometry.origin + geometry.positions[v as usize].as_dvec3();
    let short_enough = |t: &[u32; 3]| {
        let depth = t.iter().map(|&v| position(v).length()).sum::<f64>() / 3.0;
        (0..3).all(|k| position(t[k]).distance(position(t[(k + 1) % 3])) <= max_edge * depth)
    };
    let mut triangles = Vec::new();
    for y in 0..height as usize - 1 {
        for x in 0..width as usize - 1 {
            let at = |dx: usize, dy: usize| vertex_at[(y + dy) * width as usize + x + dx];
            let [a, b, c, d] = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
            for t in block_triangles([a, b, c, d], |p, q| position(p).distance(position(q))) {
                if short_enough(&t) {
                    triangles.push(t);
                }
            }
        }
    }
    Ok(triangles)
}

/// The triangles of one 2×2 block of pixels `[top-left, top-right, bottom-left,
/// bottom-right]` (`u32::MAX`: no point there), consistently wound.
fn block_triangles([a, b, c, d]: [u32; 4], distance: impl Fn(u32, u32) -> f64) -> Vec<[u32; 3]> {
    let missing = |v: u32| v == u32::MAX;
    match [a, b, c, d].iter().filter(|v| missing(**v)).count() {
        0 if distance(a, d) <= distance(b, c) => vec![[a, d, b], [a, c, d]],
        0 => vec![[a, c, b], [b, c, d]],
        1 if missing(a) => vec![[b, c, d]],
        1 if missing(b) => vec![[a, c, d]],
        1 if missing(c) => vec![[a, d, b]],
        1 => vec![[a, c, b]],
        _ => Vec::new(),
    }
}

/// Triangles of `geometry` as a height field over x–y (its 2.5D Delaunay triangulation),
/// long triangles dropped.
pub fn terrain(geometry: &Geometry) -> Vec<[u32; 3]> {
    height_field(&geometry.positions)
}

/// [`terrain`] of bare `positions`.
pub fn height_field(positions: &[Vec3]) -> Vec<[u32; 3]> {
    height_field_keeping(positions, |_, _| false)
}

/// [`height_field`], but a long triangle is kept where `keep_long` holds for its
/// centroid and the median edge (the ground under a bridge deck or a crown, left out
/// of the triangulation).
pub fn height_field_keeping(
    positions: &[Vec3],
    keep_long: impl Fn(Vec3, f64) -> bool + Sync,
) -> Vec<[u32; 3]> {
    drop_long(positions, &delaunay_xy(positions), keep_long)
}

/// `triangles` of `positions` without those with an edge (in x–y) longer than
/// [`TERRAIN_MAX_EDGE`] × the median edge, but where `keep_long` holds for the
/// triangle's centroid and the median edge.
pub fn drop_long(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    keep_long: impl Fn(Vec3, f64) -> bool + Sync,
) -> Vec<[u32; 3]> {
    let kept = short_or_kept(positions, triangles, keep_long);
    parallel::filtered(triangles, |k| kept[k])
}

/// Whether [`drop_long`] keeps each of `triangles`.
///
/// Edges are compared by their squared x–y lengths: the median length is the root of
/// the median square (√ is monotone and correctly rounded), and an edge is within the
/// bound exactly when its square is at most [`largest_square_within`] the bound.
pub fn short_or_kept(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    keep_long: impl Fn(Vec3, f64) -> bool + Sync,
) -> Vec<bool> {
    let squares = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        [(a, b), (b, c), (c, a)].map(|(p, q)| {
            let (dx, dy) = ((p.x - q.x) as f64, (p.y - q.y) as f64);
            dx * dx + dy * dy
        })
    };
    // Each triangle's longest square, NaN if any is (which no bound holds), kept
    // beside the squares, whose order the median's selection scrambles.
    let longest = |s: [f64; 3]| match s.iter().any(|x| x.is_nan()) {
        true => f64::NAN,
        false => s[0].max(s[1]).max(s[2]),
    };
    let mut edges = vec![[0.0; 3]; triangles.len()];
    let mut longest_square = vec![0.0; triangles.len()];
    (edges.par_iter_mut().zip(&mut longest_square).zip(triangles)).for_each(|((e, l), t)| {
        *e = squares(t);
        *l = longest(*e);
    });
    let flat = edges.as_flattened_mut();
    if flat.is_empty() {
        return Vec::new();
    }
    let mid = flat.len() / 2;
    let median = flat.select_nth_unstable_by(mid, f64::total_cmp).1.sqrt();
    drop(edges);
    let within = largest_square_within(TERRAIN_MAX_EDGE * median);
    (triangles.par_iter().zip(longest_square))
        .map(|(t, longest)| {
            let centroid = || t.iter().map(|&v| positions[v as usize]).sum::<Vec3>() / 3.0;
            longest <= within || keep_long(centroid(), median)
        })
        .collect()
}

/// The largest s ≥ 0 whose root is at most `bound`: for every s ≥ 0, √s ≤ `bound`
/// exactly when s ≤ this (√ is monotone). Infinite for an infinite bound, and NaN
/// where every root exceeds the bound (a negative or NaN one).
fn largest_square_within(bound: f64) -> f64 {
    if bound.is_nan() || bound < 0.0 {
        return f64::NAN;
    }
    let mut s = bound * bound;
    while s > 0.0 && s.sqrt() > bound {
        s = s.next_down();
    }
    while s.next_up().sqrt() <= bound && s.is_finite() {
        s = s.next_up();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_is_within_the_bound_exactly_when_its_root_is() {
        // Bounds over every magnitude, subnormal to huge, and their neighbours: the
        // largest square's root is within, the next square's is not.
        let mut bounds = vec![0.0, f64::MIN_POSITIVE, 5e-324, 1.0, 4.0, f64::MAX];
        for e in -300..300 {
            for m in [1.0, 1.1, 1.5, std::f64::consts::SQRT_2, 1.999_999] {
                let b = m * 10f64.powi(e);
                bounds.extend([b, b.next_up(), b.next_down()]);
            }
        }
        for bound in bounds {
            let s = largest_square_within(bound);
            assert!(s >= 0.0 && s.sqrt() <= bound, "{bound}: {s}");
            let next = s.next_up();
            assert!(next.sqrt() > bound || next.is_infinite(), "{bound}: {s}");
        }
        assert_eq!(largest_square_within(f64::INFINITY), f64::INFINITY);
        assert!(largest_square_within(f64::NAN).is_nan());
        assert!(largest_square_within(-1.0).is_nan());
    }

    fn grid_points(width: usize, height: usize, hole: Option<usize>) -> Geometry {
        let mut points = Vec::new();
        for y in 0..height {
            for x in 0..width {
                let z = if Some(y * width + x) == hole {
                    f64::NAN
                } else {
                    2.0
                };
                points.push([x as f64 * 0.01, y as f64 * 0.01, z]);
            }
        }
        Geometry::from_points(&points).unwrap().0
    }

    #[test]
    fn a_full_grid_gives_two_triangles_per_block() {
        let g = grid_points(4, 3, None);
        assert_eq!(sensor_grid(&g, 4, 3).unwrap().len(), 2 * 3 * 2);
    }

    #[test]
    fn a_missing_pixel_leaves_one_triangle_in_each_block_around_it() {
        // Pixel (1, 1) of a 3×3 grid is a corner of all four blocks.
        let g = grid_points(3, 3, Some(4));
        assert_eq!(g.rows.as_ref().unwrap().len(), 8);
        assert_eq!(sensor_grid(&g, 3, 3).unwrap().len(), 4);
    }

    #[test]
    fn a_depth_jump_is_not_bridged() {
        let points = [
            [0.0, 0.0, 1.0],
            [0.01, 0.0, 1.0],
            [0.0, 0.01, 3.0],
            [0.01, 0.01, 3.0],
        ];
        let g = Geometry::from_points(&points).unwrap().0;
        assert!(sensor_grid(&g, 2, 2).unwrap().is_empty());
    }

    #[test]
    fn more_rows_than_pixels_is_an_error() {
        let g = grid_points(4, 3, None);
        assert!(sensor_grid(&g, 3, 3).is_err());
    }

    #[test]
    fn a_terrain_drops_the_long_triangles_across_a_gap() {
        let mut points = Vec::new();
        for y in 0..10 {
            for x in (0..10).chain(30..40) {
                points.push([x as f64, y as f64, 0.0]);
            }
        }
        let g = Geometry::from_points(&points).unwrap().0;
        let triangles = terrain(&g);
        // Two 9×9-cell patches, two triangles a cell; nothing spans the gap.
        assert_eq!(triangles.len(), 2 * 2 * 81);
    }
}
