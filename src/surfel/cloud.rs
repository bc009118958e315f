//! Surfels of a point cloud from its k nearest neighbours (kiddo's k-d tree), made to
//! hold on real sampling: scan lines, quantised coordinates, rows of an RGB-D frame
//! sparser than its columns, stray samples.
//!
//! * normal: the smallest principal axis of the neighbourhood (self + [`K`] − 1
//!   neighbours: enough to span several scan lines), unless the file gives a non-zero
//!   one; oriented afterwards where a direction is known ([`Orientation`]);
//! * radius: the neighbourhood's *surrounding distance* r_s, the least distance at which
//!   the (distinct) neighbours, projected on the tangent plane and taken nearest first,
//!   leave no angular gap wider than [`MAX_GAP`] around the point, times
//!   [`SURROUND_GROWTH`]. Every triangle the point makes with two angularly consecutive
//!   surrounding neighbours then has a circumradius ≤ r_s (an angle ≤ 120° between
//!   sides ≤ r_s), so the disks close every gap of the sampling, however anisotropic
//!   (on a square grid of spacing h: r_s = h, radius h√2, as the diagonal neighbours);
//! * a cap: a point that no neighbourhood surrounds (a boundary) or whose nearest
//!   neighbour lies more than [`MAX_SPACINGS`] times the neighbourhood's median spacing
//!   away (a stray sample) closes no gap; its radius is capped at [`MAX_SPACINGS`] times
//!   that spacing and counted ([`SurfelStats::capped_radii`]). The spacing is the median,
//!   over the neighbourhood, of each member's distance to its nearest other member.
//!
//! Duplicated samples do not shrink a radius (only distinct neighbours count). A surfel
//! whose neighbours all coincide with it takes the median radius of the others
//! ([`fallback_radius`]).

use std::num::NonZero;

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::pca::plane_normal;
use super::{Surfel, SurfelStats};

/// Neighbourhood size, the point itself included.
pub const K: usize = 16;
/// Widest angular gap (radians) that the surrounding neighbours may leave: 120°.
pub const MAX_GAP: f32 = 2.0 * std::f32::consts::FRAC_PI_3;
/// Radius over the surrounding distance.
pub const SURROUND_GROWTH: f32 = std::f32::consts::SQRT_2;
/// Which distinct neighbour sets the radius of a point no neighbourhood surrounds.
pub const RADIUS_RANK: usize = 6;
/// Largest radius of a point that closes no gap, in neighbourhood spacings.
pub const MAX_SPACINGS: f32 = 4.0;

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

/// The distinct positions among `points`, unit-scaled. Searching among distinct
/// positions keeps each query O(log n) however many samples coincide (10⁵ copies of
/// one point would otherwise make the search quadratic), and coinciding samples add
/// nothing to a neighbourhood's shape.
fn distinct_positions(points: &[Vec3], scale: f32) -> Vec<[f32; 3]> {
    // Scaled coordinates stay within ±2⁶⁰ (`super::unit_scale`): squared distances fit f32.
    let mut coords: Vec<[f32; 3]> = points.par_iter().map(|p| (*p * scale).to_array()).collect();
    let key = |c: &[f32; 3]| c.map(|x| if x == 0.0 { 0 } else { x.to_bits() });
    coords.par_sort_unstable_by_key(key);
    coords.dedup_by_key(|c| key(c));
    coords
}

/// Normal and radius from the neighbours of each point listed in `which`, searching
/// among all `points` (unit-scaled by `scale` for the search), written into `surfels`.
/// Non-zero `given` normals are kept; a radius already set (from faces) is only grown.
/// Afterwards every listed surfel whose radius is still 0 gets [`fallback_radius`].
pub fn neighbour_disks(
    points: &[Vec3],
    scale: f32,
    which: &[u32],
    rule: RadiusRule,
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
) {
    if which.is_empty() {
        return;
    }
    let coords = distinct_positions(points, scale);
    let point = |i: u32| Vec3::from(coords[i as usize]);
    let k = NonZero::new(K.min(coords.len())).unwrap_or(NonZero::<usize>::MIN);
    let disks: Vec<(Vec3, f32, bool)> = match ImmutableKdTree::<f32, 3>::new_from_slice(&coords) {
        Ok(tree) => which
            .par_iter()
            .with_min_len(1024)
            .map(|&i| {
                let p = points[i as usize] * scale;
                let found = tree
                    .query(&p.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                let given_n = given.map_or(Vec3::ZERO, |g| g[i as usize]);
                let near: Vec<Vec3> = found.iter().map(|f| point(f.item)).collect();
                let normal = if given_n != Vec3::ZERO {
                    given_n
                } else {
                    plane_normal(near.iter().copied())
                };
                let (radius, capped) = disk_radius(p, normal, &near, rule);
                (normal, radius / scale, capped)
            })
            .collect(),
        // A tree that cannot be built leaves every disk to the fallbacks.
        Err(_) => vec![(Vec3::Z, 0.0, false); which.len()],
    };
    for (&i, (normal, radius, capped)) in which.iter().zip(disks) {
        let s = &mut surfels[i as usize];
        s.normal = normal;
        s.radius = s.radius.max(radius);
        stats.capped_radii += capped as u64;
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
}

/// How a neighbour disk's radius is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RadiusRule {
    /// A cloud's: the surrounding distance, or a capped ranked distance (module doc).
    Surrounding,
    /// A mesh's isolated vertices, which lie among the mesh's own vertices: the distance
    /// to the [`RADIUS_RANK`]-th distinct neighbour.
    Ranked,
}

/// The radius of the disk at `p` of unit `normal` among its neighbours `near` (sorted
/// nearest first, `p` and its duplicates included) by `rule`, and whether it was capped
/// (see the module doc). 0 when every neighbour coincides with `p`.
fn disk_radius(p: Vec3, normal: Vec3, near: &[Vec3], rule: RadiusRule) -> (f32, bool) {
    let (t1, t2) = normal.any_orthonormal_pair();
    let distinct: Vec<(f32, f32)> = near
        .iter()
        .map(|q| (q.distance(p), *q - p))
        .filter(|(d, _)| *d > 0.0)
        .map(|(d, o)| (d, o.dot(t2).atan2(o.dot(t1))))
        .collect();
    let Some(&(nearest, _)) = distinct.first() else {
        return (0.0, false);
    };
    let ranked = distinct[RADIUS_RANK.min(distinct.len()) - 1].0;
    if rule == RadiusRule::Ranked {
        return (ranked, false);
    }
    let spacing = median_spacing(near);
    let stray = nearest > MAX_SPACINGS * spacing;
    let surrounding = (!stray).then(|| surrounding_distance(&distinct)).flatten();
    match surrounding {
        Some(r) => (SURROUND_GROWTH * r, false),
        None => {
            let cap = MAX_SPACINGS * spacing;
            (ranked.min(cap), ranked > cap)
        }
    }
}

/// The least distance of `neighbours` ((distance, angle in the tangent plane), nearest
/// first) within which they leave no angular gap wider than [`MAX_GAP`]; `None` when
/// even all of them do.
fn surrounding_distance(neighbours: &[(f32, f32)]) -> Option<f32> {
    let mut angles: Vec<f32> = Vec::with_capacity(neighbours.len());
    for &(d, angle) in neighbours {
        let at = angles.partition_point(|a| *a < angle);
        angles.insert(at, angle);
        if angles.len() >= 3 && widest_gap(&angles) <= MAX_GAP {
            return Some(d);
        }
    }
    None
}

/// The widest gap between consecutive sorted angles (radians in (−π, π]), around the
/// circle.
fn widest_gap(sorted: &[f32]) -> f32 {
    let wrap = sorted[0] + std::f32::consts::TAU - sorted[sorted.len() - 1];
    sorted.windows(2).map(|w| w[1] - w[0]).fold(wrap, f32::max)
}

/// The median, over `points`, of each one's distance to its nearest other distinct
/// member: the sampling's spacing there, which a stray sample beside it does not change.
fn median_spacing(points: &[Vec3]) -> f32 {
    let mut nearest: Vec<f32> = points
        .iter()
        .map(|a| {
            points
                .iter()
                .map(|b| a.distance(*b))
                .filter(|d| *d > 0.0)
                .fold(f32::INFINITY, f32::min)
        })
        .filter(|d| d.is_finite())
        .collect();
    if nearest.is_empty() {
        return 0.0;
    }
    let mid = nearest.len() / 2;
    *nearest.select_nth_unstable_by(mid, f32::total_cmp).1
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
    fn a_square_grid_point_is_surrounded_by_its_four_neighbours() {
        let near: Vec<Vec3> = [
            (0, 0),
            (1, 0),
            (0, 1),
            (-1, 0),
            (0, -1),
            (1, 1),
            (-1, 1),
            (1, -1),
            (-1, -1),
        ]
        .iter()
        .map(|&(x, y)| Vec3::new(x as f32, y as f32, 0.0))
        .collect();
        let (r, capped) = disk_radius(Vec3::ZERO, Vec3::Z, &near, RadiusRule::Surrounding);
        assert!(
            (r - std::f32::consts::SQRT_2).abs() < 1e-6 && !capped,
            "{r}"
        );
    }

    #[test]
    fn rows_sparser_than_columns_get_a_radius_that_reaches_the_next_row() {
        // Columns 1 apart, rows 4 apart: the nearest neighbours all lie on the point's
        // own row until the next rows come in at distance 4.
        let mut near = Vec::new();
        for row in -1..=1 {
            for col in -6..=6 {
                near.push(Vec3::new(col as f32, 4.0 * row as f32, 0.0));
            }
        }
        near.sort_by(|a, b| a.length().total_cmp(&b.length()));
        let (r, capped) = disk_radius(Vec3::ZERO, Vec3::Z, &near[..K], RadiusRule::Surrounding);
        assert!(r >= 4.0 && !capped, "{r}");
    }

    #[test]
    fn a_stray_sample_is_capped_at_four_spacings() {
        let mut near = vec![Vec3::ZERO];
        for x in 0..4 {
            for y in 0..4 {
                near.push(Vec3::new(100.0 + x as f32, y as f32, 0.0));
            }
        }
        let (r, capped) = disk_radius(Vec3::ZERO, Vec3::Z, &near, RadiusRule::Surrounding);
        assert!(capped && r <= 4.0, "{r}");
    }

    #[test]
    fn a_boundary_point_keeps_a_radius_of_its_neighbours_spacing() {
        // A half-plane: every neighbour lies at x ≥ 0.
        let mut near = Vec::new();
        for x in 0..4 {
            for y in -2..=2 {
                near.push(Vec3::new(x as f32, y as f32, 0.0));
            }
        }
        near.sort_by(|a, b| a.length().total_cmp(&b.length()));
        let (r, _) = disk_radius(Vec3::ZERO, Vec3::Z, &near[..K], RadiusRule::Surrounding);
        assert!(r > 1.0 && r <= 4.0, "{r}");
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
