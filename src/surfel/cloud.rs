//! Surfels of a point cloud from its k nearest neighbours (kiddo's k-d tree).
//!
//! * normal: the smallest principal axis of the neighbourhood (self + [`K`] − 1
//!   neighbours), unless the file gives a non-zero one;
//! * radius: the distance to the [`RADIUS_RANK`]-th nearest *distinct* neighbour (at a
//!   non-zero distance). On a square grid of spacing h that is h√2, so each disk reaches
//!   its diagonal neighbours and neighbouring disks overlap with margin; duplicated
//!   samples do not shrink it. A surfel whose neighbours all coincide with it takes the
//!   median radius of the others ([`fallback_radius`]).

use std::num::NonZero;

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::pca::plane_normal;
use super::{Surfel, SurfelStats};

/// Neighbourhood size, the point itself included.
pub const K: usize = 12;
/// Which distinct neighbour sets the radius (1 = nearest).
pub const RADIUS_RANK: usize = 6;

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
    let disks: Vec<(Vec3, f32)> = match ImmutableKdTree::<f32, 3>::new_from_slice(&coords) {
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
                let normal = if given_n != Vec3::ZERO {
                    given_n
                } else {
                    plane_normal(found.iter().map(|f| point(f.item)))
                };
                let distinct: Vec<f32> = found
                    .iter()
                    .map(|f| point(f.item).distance(p))
                    .filter(|d| *d > 0.0)
                    .collect();
                let radius = distinct
                    .get(RADIUS_RANK.min(distinct.len()).wrapping_sub(1))
                    .copied()
                    .unwrap_or(0.0);
                (normal, radius / scale)
            })
            .collect(),
        // A tree that cannot be built leaves every disk to the fallbacks.
        Err(_) => vec![(Vec3::Z, 0.0); which.len()],
    };
    for (&i, (normal, radius)) in which.iter().zip(disks) {
        let s = &mut surfels[i as usize];
        s.normal = normal;
        s.radius = s.radius.max(radius);
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
