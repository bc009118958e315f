//! A terrain's vegetation (classes 3, 4 and 5: low, medium and high vegetation; or
//! found by its geometry, [`super::layers`]), drawn apart from its TIN. A TIN joins a
//! crown's samples to the ground around the trunk, and its splats hang a curtain from
//! every crown to the ground (docs/point-clouds.md, "Airborne scans against a known scene"). Left out of
//! the TIN, the ground and roofs under and around a tree keep their own surface, and
//! the vegetation's samples get a cloud's surfels among themselves
//! ([`super::cloud::neighbour_disks`]): sized by the vegetation's own sampling, their
//! estimated normals turned up as the terrain's are.

use glam::Vec3;

use super::cloud::{self, Orientation};
use super::covering::RadiusRule;
use super::layers::pick;
use super::progress::Progress;
use super::{Surfel, SurfelStats};

/// Largest radius of a vegetation splat, in the tile's spacings s (the median edge of
/// the ground's TIN). A lone return (a trunk's, one under a crown) has neighbours metres
/// away and would get a disk as wide as they are far, down to the ground; held to √2 s,
/// the circle that covers a pulse's square of the scan. Simulated scan
/// (`airborne_quality`, 4 views): FLIP 0.101 / 0.100 / 0.091 and surface invented
/// under the crowns 24–32 % / 3–5 % / 4–6 % unheld / at s / at √2 s.
pub const FOOTPRINT_SPACINGS: f32 = std::f32::consts::SQRT_2;

/// The surfels of the vegetation's samples `plants` (indices into all `points`, the
/// first `own` of them the model's own), into `surfels` (one per point of the model): a
/// cloud's among the vegetation alone, their estimated normals turned up, their radii
/// held to [`FOOTPRINT_SPACINGS`] tile `spacing`s.
pub fn plant_disks(
    (points, scale, spacing): (&[Vec3], f32, f32),
    (plants, own): (&[u32], usize),
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) {
    let positions = pick(points, plants);
    let given = given.map(|g| pick(g, plants));
    let mut own_surfels = pick(surfels, plants);
    let which: Vec<u32> = (0..own as u32).collect();
    let rule = (RadiusRule::Surrounding, Orientation::Unknown, progress);
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
        s.radius = s.radius.min(FOOTPRINT_SPACINGS * spacing);
        surfels[plants[k] as usize] = *s;
    }
    stats.vegetation += own as u64;
}
