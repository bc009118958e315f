//! What the CPU decides for a frame before the GPU draws it (DESIGN.md §5): ε from the
//! budget in pixels, the eye the level of detail is chosen for, the chunks the view
//! cone can see and, by binary search, each one's prefix: the list ranges to hand over.
//! While a model uploads, ε is raised until its ranges are on the GPU (a coarser cut,
//! never a holed one).

use std::ops::Range;

use glam::DVec3;

use super::camera::Camera;
use super::settings::Settings;
use crate::tree::scene::Scene;
use crate::tree::select::{ViewCone, error_per_distance, tested};

/// What the CPU decided for one recorded frame.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedFrame {
    /// The list ranges handed to the GPU: each visible chunk's prefix, ascending.
    pub ranges: Vec<Range<usize>>,
    /// Nodes in `ranges`: what the GPU tests.
    pub tested: usize,
    /// Compute culling ran: the survivor counts can be read back.
    pub compute: bool,
    /// ε of the selection test, world error per unit of distance.
    pub eps: f64,
    /// ε had to be raised above the settings' because the ranges they ask for are not
    /// all on the GPU yet (while a model uploads): the frame is a coarser cut.
    pub coarsened: bool,
    /// Slices of the list on the GPU when the frame was recorded.
    pub slices: usize,
    /// The eye the level of detail was chosen for, relative to the model's origin.
    pub lod_eye: DVec3,
}

/// The least ε ≥ `eps` whose ranges (seen from `eye`, chunks culled by `cone`) lie
/// within the first `uploaded` nodes, and those ranges. Any ε gives a complete cut of
/// the tree, so a frame drawn while the list uploads is coarser, never holed. The
/// ranges shrink as ε grows, so the least fitting ε is found by doubling, then
/// bisection. (An eye within reach of a chunk not uploaded yet needs part of it at any
/// ε: the ranges are then cut at what is there.)
pub(super) fn fitting_eps(
    scene: &Scene,
    (eye, cone): (DVec3, &ViewCone),
    eps: f64,
    uploaded: usize,
) -> (f64, Vec<Range<usize>>) {
    let nodes = scene.nodes();
    let ranges = |e: f64| scene.index.ranges(nodes, eye, e, Some(cone));
    let end = |r: &[Range<usize>]| r.last().map_or(0, |r| r.end);
    let wanted = ranges(eps);
    if end(&wanted) <= uploaded || uploaded == 0 {
        return (eps, if uploaded == 0 { Vec::new() } else { wanted });
    }
    // Invariant after the doubling: `at_hi` is ranges(hi) (which fits, unless 200
    // doublings did not suffice), and ranges(lo) does not fit.
    let mut lo = eps;
    let mut hi = eps.max(scene.meta().error_scale as f64 * 1e-9);
    let mut at_hi = if hi == eps { wanted } else { ranges(hi) };
    for _ in 0..200 {
        if end(&at_hi) <= uploaded {
            break;
        }
        lo = hi;
        hi *= 2.0;
        at_hi = ranges(hi);
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        let at_mid = ranges(mid);
        if end(&at_mid) <= uploaded {
            (hi, at_hi) = (mid, at_mid);
        } else {
            lo = mid;
        }
    }
    let cut = at_hi
        .into_iter()
        .filter_map(|r| (r.start < uploaded).then(|| r.start..r.end.min(uploaded)))
        .collect();
    (hi, cut)
}

/// Plans a frame of `scene` seen by `camera` over `size` pixels, with `uploaded` nodes
/// on the GPU in `slices` slices. `compute`: whether compute culling will run.
pub(super) fn plan(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    (width, height): (u32, u32),
    (uploaded, slices): (usize, usize),
    compute: bool,
) -> EncodedFrame {
    let eps = error_per_distance(settings.error_px, camera.fov_y, height);
    let wanted_eps = if settings.lod { eps } else { 0.0 };
    let meta = scene.meta();
    let lod_eye = settings.lod_eye.unwrap_or(camera.eye) - DVec3::from(meta.origin);
    let aspect = width as f64 / height.max(1) as f64;
    let cone = camera.view_cone(meta, aspect, settings.radius_scale as f64);
    let (lod_eps, ranges) = fitting_eps(scene, (lod_eye, &cone), wanted_eps, uploaded);
    EncodedFrame {
        tested: tested(&ranges),
        ranges,
        compute,
        eps: lod_eps,
        coarsened: lod_eps != wanted_eps,
        slices,
        lod_eye,
    }
}
