//! A terrain's vegetation, where its file classifies it (ASPRS 3, 4 and 5: low, medium
//! and high vegetation), drawn apart from its TIN. A TIN joins a crown's samples to the
//! ground around the trunk, and its splats hang a curtain from every crown to the
//! ground (docs/point-clouds.md, "Airborne scans against a known scene"). Left out of
//! the TIN, the ground and roofs under and around a tree keep their own surface, and
//! the vegetation's samples get a cloud's surfels among themselves
//! ([`super::cloud::neighbour_disks`]): sized by the vegetation's own sampling, their
//! estimated normals turned up as the terrain's are.

use glam::Vec3;

use super::cloud::{self, Orientation};
use super::covering::RadiusRule;
use super::{Surfel, SurfelStats};
use crate::io::PointAttributes;

/// Whether a sample is vegetation by its class.
pub fn is_vegetation(a: &PointAttributes) -> bool {
    matches!(a.class, 3..=5)
}

/// A model's samples in two sets, each its own samples first, then its halo's (in the
/// model's order), with how many are its own.
pub struct Split {
    pub rest: (Vec<u32>, usize),
    pub plants: (Vec<u32>, usize),
}

impl Split {
    /// The split of samples with `attributes` whose first `own` are the model's own;
    /// `None` when none of its own is vegetation.
    pub fn of(attributes: &[PointAttributes], own: usize) -> Option<Split> {
        let (mut rest, mut plants) = ((Vec::new(), 0), (Vec::new(), 0));
        for (i, a) in attributes.iter().enumerate() {
            let set: &mut (Vec<u32>, usize) = if is_vegetation(a) {
                &mut plants
            } else {
                &mut rest
            };
            set.0.push(i as u32);
            set.1 += (i < own) as usize;
        }
        (plants.1 > 0).then_some(Split { rest, plants })
    }
}

/// `values` at `indices`.
pub fn pick<T: Copy>(values: &[T], indices: &[u32]) -> Vec<T> {
    indices.iter().map(|&i| values[i as usize]).collect()
}

/// The surfels of the vegetation's own samples (`split.plants`, of all `points`), into
/// `surfels` (one per point of the model): a cloud's among the vegetation alone, their
/// estimated normals turned up.
pub fn plant_disks(
    (points, scale): (&[Vec3], f32),
    (plants, own): (&[u32], usize),
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
) {
    let positions = pick(points, plants);
    let given = given.map(|g| pick(g, plants));
    let mut own_surfels = pick(surfels, plants);
    let which: Vec<u32> = (0..own as u32).collect();
    let rule = (RadiusRule::Surrounding, Orientation::Unknown);
    let walls = cloud::neighbour_disks(
        &positions,
        scale,
        &which,
        rule,
        given.as_deref(),
        &mut own_surfels,
        stats,
    );
    debug_assert!(walls.is_empty(), "walls are a terrain's");
    for (k, s) in own_surfels.iter_mut().enumerate().take(own) {
        let estimated = given.as_ref().is_none_or(|g| g[k] == Vec3::ZERO);
        if estimated {
            s.normal = Orientation::Up.apply(s.position, s.normal);
        }
        surfels[plants[k] as usize] = *s;
    }
    stats.vegetation += own as u64;
}
