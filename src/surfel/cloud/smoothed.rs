//! Normals smoothed over a cloud's neighbourhoods where one neighbourhood's fit is not
//! to be trusted: a terrain's scan lines and height steps, a sensor frame's depth steps
//! ([`super::super::levels`]).

use arrayvec::ArrayVec;
use glam::Vec3;
use rayon::prelude::*;

use super::super::covering::{Covering, RadiusRule, covering};
use super::super::levels;
use super::super::pca::plane_normal;
use super::search::Search;
use super::{K, Orientation};

/// The clouds whose fitted normals [`smoothed_disks`] replaces by their neighbours'.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Smoothing {
    /// A terrain: every fit, by the mean of its neighbours' (all turned up).
    Terrain,
    /// A sensor frame whose depth is quantised along this axis ([`levels`]): a fit of
    /// a neighbourhood on one step, by the mean of its neighbours' fits that span
    /// steps (all turned toward the sensor, here in unit-scaled coordinates).
    Steps { axis: usize, sensor: Vec3 },
}

impl Smoothing {
    /// How a cloud turned by `orientation` smooths its fits: a terrain always, a
    /// sensor frame where its depth is quantised ([`levels::quantised_axis`], in the
    /// search's unit-scaled coordinates), any other cloud not at all.
    pub fn of(search: &Search, scale: f32, orientation: Orientation) -> Option<Smoothing> {
        match orientation {
            Orientation::Up => Some(Smoothing::Terrain),
            Orientation::Toward(sensor) => {
                let sensor = sensor * scale;
                let axis = levels::quantised_axis(&search.coords, sensor)?;
                Some(Smoothing::Steps { axis, sensor })
            }
            Orientation::Unknown => None,
        }
    }

    /// The fit of a neighbourhood `found` (of positions in `coords`, its own first),
    /// turned.
    fn fit(self, coords: &[[f32; 3]], found: &[u32]) -> Vec3 {
        let n = plane_normal(found.iter().map(|&f| Vec3::from(coords[f as usize])));
        match self {
            Smoothing::Terrain => Orientation::Up.apply(Vec3::ZERO, n),
            Smoothing::Steps { sensor, .. } => {
                let own = found
                    .first()
                    .map_or(Vec3::ZERO, |&f| Vec3::from(coords[f as usize]));
                Orientation::Toward(sensor).apply(own, n)
            }
        }
    }

    /// Whether the fit of `found` counts in the neighbours' means: not on one step.
    fn spans_steps(self, coords: &[[f32; 3]], found: &[u32]) -> bool {
        match self {
            Smoothing::Terrain => true,
            Smoothing::Steps { axis, .. } => !levels::one_level(coords, axis, found),
        }
    }
}

/// Disks whose normals are smoothed over the neighbourhood ([`Smoothing`],
/// [`fitted_normals`]), with the plane each was measured in: a sample's normal is the
/// mean of its neighbours' fitted normals (each the plane of its own neighbourhood,
/// turned), on a terrain always, on a quantised frame where its own neighbourhood lies
/// on one step; its covering is measured in the plane of its own fit, where its
/// sampling's gaps lie.
///
/// A quantised frame's step treads (`kinect_rgb`, issue 13, `cloud_quality --grid
/// 640x480`, 4 views, medians): FLIP 0.2983 → 0.2966, holes 0.082 % → 0.023 % (worst
/// view 0.126 % → 0.067 %), and the bright dashes across its floor on view 0 (treads
/// seen from behind, lit from above) are gone. Replacing every fit of the frame by the
/// mean of those that span steps gave 0.3493: its reference shades the steps' ridges.
///
/// An airborne scan's lines and quantised steps turn one neighbourhood's plane at
/// random, and at 1–2 pixels a splat such planes read as dark blotches across the
/// roofs and streets, where the 2.5D triangulation of the same samples shades with
/// vertex normals averaged over each one-ring. Averaged once over the neighbourhood
/// (issue 13, `cloud_quality --terrain`, 4 views, medians): FLIP 0.2572 → 0.2280, SSIM
/// 0.172 → 0.242, holes 0.167 % → 0.221 % (worst view 0.483 % → 0.468 %). On the
/// RGB-D frame the same mean of all fits (turned toward the sensor) raised FLIP
/// (0.2983 → 0.3299) and opened holes (up to 2.8 % on a view). Each sample's
/// neighbourhood is kept between the two steps (K indices, 100 bytes a sample) rather
/// than searched twice (+35 % of the surfels' time on the tile, for 27 MB less at its
/// peak).
pub(super) fn smoothed_disks(
    search: &Search,
    (points, scale): (&[Vec3], f32),
    which: &[u32],
    (rule, smoothing): (RadiusRule, Smoothing),
    given_normal: &(dyn Fn(u32) -> Vec3 + Sync),
) -> Vec<(Vec3, Vec3, Covering)> {
    // Every sample's neighbourhood, halo included, in the samples' own order (which
    // keeps `nearest_in_order`'s bounds tight); its nearest is its own position.
    let neighbourhoods: Vec<ArrayVec<u32, K>> = search
        .neighbourhoods(points, &|p| *p * scale)
        .map(|(_, found)| found)
        .collect();
    let near = |i: usize| neighbourhoods[i].iter().map(|&f| search.point(f));
    let fitted = fitted_normals(&search.coords, &neighbourhoods, smoothing);
    which
        .par_iter()
        .map(|&i| {
            let found = &neighbourhoods[i as usize];
            let own = found.first().map_or(Fitted::NONE, |&c| fitted[c as usize]);
            let smoothed = match smoothing {
                // The mean over this sample's own neighbourhood.
                Smoothing::Terrain => counted_sum(&found[1..], &fitted).normalize_or(own.fit),
                Smoothing::Steps { .. } => own.normal,
            };
            let given = given_normal(i);
            let (normal, plane) = if given != Vec3::ZERO {
                (given, given)
            } else {
                (smoothed, own.fit)
            };
            let near: ArrayVec<Vec3, K> = near(i as usize).collect();
            let covering = covering(points[i as usize] * scale, plane, &near, rule);
            (normal, plane, covering)
        })
        .collect()
}

/// A distinct position's fitted normal (turned), the normal [`fitted_normals`] gave
/// it, and whether that counts in its neighbours' means.
#[derive(Debug, Clone, Copy)]
struct Fitted {
    fit: Vec3,
    normal: Vec3,
    counts: bool,
}

impl Fitted {
    const NONE: Fitted = Fitted {
        fit: Vec3::Z,
        normal: Vec3::Z,
        counts: false,
    };
}

/// The sum of the normals of the positions `near` that count.
fn counted_sum(near: &[u32], fitted: &[Fitted]) -> Vec3 {
    let counted = near
        .iter()
        .map(|&f| fitted[f as usize])
        .filter(|f| f.counts);
    counted.map(|f| f.normal).sum()
}

/// Rounds of [`fitted_normals`] on a quantised frame: a tread wider than this many
/// neighbourhoods keeps its middle's fits.
const STEP_ROUNDS: usize = 4;

/// Each distinct position's fit, from the samples' `neighbourhoods` (each its own
/// position first; a position's samples share one but for ties). On a terrain every
/// fit counts in the means. On a quantised frame a fit that spans steps counts; one on
/// a single step takes the mean of its neighbours' that count, and then counts
/// itself, in each of [`STEP_ROUNDS`] rounds: a tread's middle lies further than one
/// neighbourhood from any step.
fn fitted_normals(
    coords: &[[f32; 3]],
    neighbourhoods: &[ArrayVec<u32, K>],
    smoothing: Smoothing,
) -> Vec<Fitted> {
    // Each distinct position's neighbourhood: its last sample's.
    let mut hood = vec![None; coords.len()];
    for found in neighbourhoods {
        if let Some(&own) = found.first() {
            hood[own as usize] = Some(found);
        }
    }
    let mut fitted: Vec<Fitted> = hood
        .par_iter()
        .map(|found| match found {
            Some(f) => {
                let fit = smoothing.fit(coords, f);
                let counts = smoothing.spans_steps(coords, f);
                Fitted {
                    fit,
                    normal: fit,
                    counts,
                }
            }
            None => Fitted::NONE,
        })
        .collect();
    let rounds = match smoothing {
        Smoothing::Terrain => 0,
        Smoothing::Steps { .. } => STEP_ROUNDS,
    };
    for _ in 0..rounds {
        let next: Vec<Fitted> = (0..coords.len())
            .into_par_iter()
            .map(|c| {
                let own = fitted[c];
                if own.counts {
                    return own;
                }
                let near = hood[c].map_or(&[][..], |f| &f[1..]);
                let sum = counted_sum(near, &fitted);
                if sum == Vec3::ZERO {
                    return own;
                }
                let normal = sum.normalize_or(own.fit);
                Fitted {
                    normal,
                    counts: true,
                    ..own
                }
            })
            .collect();
        fitted = next;
    }
    fitted
}
