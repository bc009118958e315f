//! What the CPU decides for a frame before the GPU draws it (docs/design.md §5): ε from the
//! budget in pixels, the eye the level of detail is chosen for, the chunks the view
//! cone can see and, by binary search, each one's prefix: the list ranges to hand over.
//! While a model uploads, or where a GPU memory budget keeps only part of it there, ε
//! is raised until its ranges are on the GPU (a coarser cut, never a holed one), and
//! the frame says which slices the asked ε wanted, for the streaming to fetch.

use std::ops::Range;

use glam::DVec3;

use super::camera::Camera;
use super::gpu_scene::GpuScene;
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
    /// The slices the ranges at the asked ε lie in, ascending (all resident unless
    /// `coarsened`).
    pub wanted_slices: Vec<usize>,
    /// The eye the level of detail was chosen for, relative to the model's origin.
    pub lod_eye: DVec3,
    /// What planning the frame took the CPU, ms.
    pub plan_ms: f64,
}

/// How close the fitting ε is to the least that fits: within this factor.
const FIT_PRECISION: f64 = 1.02;

/// The least ε ≥ `eps` (to within [`FIT_PRECISION`]) whose ranges (seen from `eye`,
/// chunks culled by `cone`) lie in the slices `gpu` holds, those ranges, and the ranges
/// at `eps`. Any ε gives a complete cut of the tree, so a frame drawn while slices are
/// missing is coarser, never holed. The ranges shrink as ε grows (each chunk's prefix
/// shortens, chunks drop out), so whether they fit is monotone in ε: a bracket
/// [lo, hi] with ranges(lo) not fitting and ranges(hi) fitting is widened from the
/// last frame's fitting ε (`gpu.last_fit`) by steps that square, so that a steady view
/// needs three evaluations, then halved in the logarithm. (An eye within reach of a
/// chunk not on the GPU needs part of it at any ε: the ranges are then cut to what is
/// there.)
pub(super) fn fitting_eps(
    scene: &Scene,
    (eye, cone): (DVec3, &ViewCone),
    eps: f64,
    gpu: &GpuScene,
) -> (f64, Vec<Range<usize>>, Vec<Range<usize>>) {
    // The search reads no node (a streamed file's nodes are on disk): it fits each
    // chunk's prefix rounded up to its block; the drawn ranges are made exact where
    // their nodes are on the GPU, and so in memory, in the same pass as the bounds.
    let ranges = |e: f64| scene.index.ranges_bound(eye, e, Some(cone));
    let both = |e: f64| {
        let nodes = scene.nodes();
        let (bounds, refined) = scene
            .index
            .ranges_refined(nodes, eye, e, Some(cone), |r| gpu.covers(&r));
        (bounds, gpu.clip(&refined))
    };
    let fits = |r: &[Range<usize>]| r.iter().all(|r| gpu.covers(r));
    let (wanted, at_eps) = both(eps);
    if gpu.resident_slices() == 0 {
        return (eps, Vec::new(), wanted);
    }
    if fits(&wanted) {
        gpu.last_fit.set(None);
        return (eps, at_eps, wanted);
    }
    let floor = scene.meta().error_scale as f64 * 1e-9;
    let start = gpu
        .last_fit
        .get()
        .filter(|&e| e > eps)
        .unwrap_or(eps.max(floor));
    let hi = least_fitting(eps, start, |e| fits(&ranges(e)));
    gpu.last_fit.set(Some(hi));
    (hi, both(hi).1, wanted)
}

/// The least ε (to within [`FIT_PRECISION`]) above `eps`, which does not fit, for
/// which `fits`, searched from `start` ([`fitting_eps`]).
fn least_fitting(eps: f64, start: f64, fits: impl Fn(f64) -> bool) -> f64 {
    let (mut lo, mut hi) = (eps, start);
    // Widen the bracket from the start by steps that square (×1.02, ×1.04, ×1.08 …):
    // down while the low end still fits, or up until the high end does.
    let mut step = FIT_PRECISION;
    if fits(hi) {
        while hi / step > eps {
            let below = hi / step;
            if !fits(below) {
                lo = below;
                break;
            }
            hi = below;
            step *= step;
        }
    } else {
        for _ in 0..200 {
            lo = hi;
            hi *= step.min(2.0);
            step *= step;
            if fits(hi) {
                break;
            }
        }
    }
    while hi > lo * FIT_PRECISION {
        let mid = (lo * hi).sqrt();
        if fits(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Plans a frame of `scene` seen by `camera` over `size` pixels, with what `gpu` holds
/// of its list. `compute`: whether compute culling will run.
pub(super) fn plan(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    (width, height): (u32, u32),
    gpu: &GpuScene,
    compute: bool,
) -> EncodedFrame {
    let started = std::time::Instant::now();
    let eps = error_per_distance(settings.error_px, camera.fov_y, height);
    let wanted_eps = if settings.lod { eps } else { 0.0 };
    let meta = scene.meta();
    let lod_eye = settings.lod_eye.unwrap_or(camera.eye) - DVec3::from(meta.origin);
    let aspect = width as f64 / height.max(1) as f64;
    let cone = camera.view_cone(meta, aspect);
    let (lod_eps, ranges, wanted) = fitting_eps(scene, (lod_eye, &cone), wanted_eps, gpu);
    let mut wanted_slices: Vec<usize> = wanted.iter().flat_map(|r| gpu.slices_of(r)).collect();
    wanted_slices.dedup();
    EncodedFrame {
        tested: tested(&ranges),
        ranges,
        compute,
        eps: lod_eps,
        coarsened: lod_eps != wanted_eps,
        slices: gpu.resident().count(),
        wanted_slices,
        lod_eye,
        plan_ms: started.elapsed().as_secs_f64() * 1e3,
    }
}
