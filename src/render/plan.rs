//! What the CPU decides for a frame before the GPU draws it (DESIGN.md §5): ε from the
//! budget in pixels, the eye the level of detail is chosen for, and the prefix of the
//! list to hand over, found by binary search. While a model uploads, ε is raised until
//! its prefix is on the GPU (a coarser cut, never a holed one).

use glam::DVec3;

use super::camera::Camera;
use super::settings::Settings;
use crate::tree::scene::Scene;
use crate::tree::select::error_per_distance;

/// What the CPU decided for one recorded frame.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedFrame {
    /// Nodes handed to the GPU (the CPU prefix).
    pub prefix_len: usize,
    /// Compute culling ran: the survivor counts can be read back.
    pub compute: bool,
    /// ε of the selection test, world error per unit of distance.
    pub eps: f64,
    /// ε had to be raised above the settings' because the prefix they ask for is not
    /// all on the GPU yet (while a model uploads): the frame is a coarser cut.
    pub coarsened: bool,
    /// Slices of the list on the GPU when the frame was recorded.
    pub slices: usize,
    /// The eye the level of detail was chosen for, relative to the model's origin.
    pub lod_eye: DVec3,
}

/// The least ε ≥ `eps` whose prefix (seen from `eye`) lies within the first `uploaded`
/// nodes, and that prefix. Any ε gives a complete cut of the tree, so a frame drawn
/// while the list uploads is coarser, never holed. The prefix shrinks as ε grows, so
/// the least fitting ε is found by doubling, then bisection.
pub(super) fn fitting_eps(scene: &Scene, eye: DVec3, eps: f64, uploaded: usize) -> (f64, usize) {
    let nodes = scene.nodes();
    let prefix = |e: f64| scene.index.prefix_len(nodes, eye, e);
    let wanted = prefix(eps);
    if wanted <= uploaded {
        return (eps, wanted);
    }
    if uploaded == 0 {
        return (eps, 0);
    }
    let mut lo = eps;
    let mut hi = eps.max(scene.meta().error_scale as f64 * 1e-9);
    for _ in 0..200 {
        if prefix(hi) <= uploaded {
            break;
        }
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if prefix(mid) <= uploaded {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (hi, prefix(hi).min(uploaded))
}

/// Plans a frame of `scene` seen by `camera` over `height` pixels, with `uploaded`
/// nodes on the GPU in `slices` slices. `compute`: whether compute culling will run.
pub(super) fn plan(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    height: u32,
    (uploaded, slices): (usize, usize),
    compute: bool,
) -> EncodedFrame {
    let eps = error_per_distance(settings.error_px, camera.fov_y, height);
    let wanted_eps = if settings.lod { eps } else { 0.0 };
    let lod_eye = settings.lod_eye.unwrap_or(camera.eye) - DVec3::from(scene.meta().origin);
    let (lod_eps, prefix_len) = fitting_eps(scene, lod_eye, wanted_eps, uploaded);
    EncodedFrame {
        prefix_len,
        compute,
        eps: lod_eps,
        coarsened: lod_eps != wanted_eps,
        slices,
        lod_eye,
    }
}
