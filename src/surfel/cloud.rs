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

use super::SurfelStats;
use super::pca::plane_normal;

/// Neighbourhood size, the point itself included.
pub const K: usize = 12;
/// Which distinct neighbour sets the radius (1 = nearest).
pub const RADIUS_RANK: usize = 6;

/// Radius for surfels without a measured one: the median of the measured radii, or
/// 1/1024 of the (unit-scaled) model when none was measured.
pub fn fallback_radius(radii: &[f32]) -> f32 {
    let mut measured: Vec<f32> = radii.iter().copied().filter(|r| *r > 0.0 && r.is_finite()).collect();
    if measured.is_empty() {
        return 1.0 / 1024.0;
    }
    let mid = measured.len() / 2;
    *measured.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// Normal and radius from the neighbours of each point listed in `which`, searching
/// among all `points`, written into `normals` and `radii` (arrays over all points).
/// Non-zero `given` normals are kept; a radius already set (from faces) is only grown.
/// Afterwards every listed point whose radius is still 0 gets [`fallback_radius`] of all.
pub fn neighbour_disks(
    points: &[Vec3],
    which: &[u32],
    given: Option<&[Vec3]>,
    normals: &mut [Vec3],
    radii: &mut [f32],
    stats: &mut SurfelStats,
) {
    if which.is_empty() {
        return;
    }
    let coords: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    let k = NonZero::new(K.min(points.len())).unwrap_or(NonZero::<usize>::MIN);
    let disks: Vec<(Vec3, f32)> = match ImmutableKdTree::<f32, 3>::new_from_slice(&coords) {
        Ok(tree) => which
            .par_iter()
            .with_min_len(1024)
            .map(|&i| {
                let p = points[i as usize];
                let found = tree
                    .query(&coords[i as usize])
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                let given_n = given.map_or(Vec3::ZERO, |g| g[i as usize]);
                let normal = if given_n != Vec3::ZERO {
                    given_n
                } else {
                    plane_normal(found.iter().map(|f| points[f.item as usize]))
                };
                let distinct: Vec<f32> = found
                    .iter()
                    .map(|f| points[f.item as usize].distance(p))
                    .filter(|d| *d > 0.0)
                    .collect();
                let radius = distinct
                    .get(RADIUS_RANK.min(distinct.len()).wrapping_sub(1))
                    .copied()
                    .unwrap_or(0.0);
                (normal, radius)
            })
            .collect(),
        // A tree that cannot be built leaves every disk to the fallbacks.
        Err(_) => vec![(Vec3::Z, 0.0); which.len()],
    };
    for (&i, (normal, radius)) in which.iter().zip(disks) {
        normals[i as usize] = normal;
        radii[i as usize] = radii[i as usize].max(radius);
    }
    let missing: Vec<u32> = which.iter().copied().filter(|&i| radii[i as usize] <= 0.0).collect();
    if !missing.is_empty() {
        let r = fallback_radius(radii);
        for i in &missing {
            radii[*i as usize] = r;
        }
        stats.fallback_radii += missing.len() as u64;
    }
}
