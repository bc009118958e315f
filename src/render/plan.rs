//! What the CPU decides for a frame before the GPU draws it (docs/design.md §5): ε from the
//! budget in pixels, the eye the level of detail is chosen for, the chunks the view
//! cone can see and, by binary search, each one's prefix: the list ranges to hand over.
//! While a model uploads, or where a GPU memory budget keeps only part of it there, ε
//! is raised until its ranges are on the GPU (a coarser cut, never a holed one), and
//! the frame says which slices the asked ε wanted, for the streaming to fetch.

use std::ops::Range;
use std::sync::atomic::Ordering;

use glam::DVec3;

use super::camera::Camera;
use super::gpu_scene::GpuScene;
use super::settings::Settings;
use crate::tree::scene::Scene;
use crate::tree::select::{Fit, Prefixes, ViewCone, error_per_distance, tested};

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
    /// Models whose far instances the GPU placed (their counters follow the slices').
    pub far_models: usize,
    /// The slices the ranges at the asked ε lie in, ascending (all resident unless
    /// `coarsened`).
    pub wanted_slices: Vec<usize>,
    /// The eye the level of detail was chosen for, relative to the model's origin.
    pub lod_eye: DVec3,
    /// What planning the frame took the CPU, ms.
    pub plan_ms: f64,
}

/// The least ε ≥ `eps` whose ranges (seen from `eye`, chunks culled by `cone`) lie in
/// the slices `gpu` holds, those ranges, and what the asked `eps` wants (ranges whose
/// slices are those of its prefixes). Any ε gives a complete cut of the tree, so a frame
/// drawn while slices are missing is coarser, never holed. (An eye within reach of a
/// chunk not on the GPU needs part of it at any ε: the ranges are then cut to what is
/// there.) `trim`: end each drawn prefix at its node, not its block.
///
/// Where the last frame's asked ε fitted (every slice resident, say), the prefixes at
/// `eps` come first, and are all there is to find if they fit. Otherwise ε and the
/// wanted slices come first, from block tests alone
/// ([`crate::tree::select::PrefixIndex::fit`]), and prefixes are searched once, at the
/// ε drawn: at a coarse ε most chunks end at their first block.
pub(super) fn fitting_eps(
    scene: &Scene,
    (eye, cone): (DVec3, &ViewCone),
    eps: f64,
    gpu: &GpuScene,
    trim: bool,
) -> (f64, Vec<Range<usize>>, Vec<Range<usize>>) {
    // The fit reads no node (a streamed file's nodes are on disk): the drawn ranges are
    // trimmed only where their nodes are on the GPU, and so in memory.
    let index = &scene.index;
    let drawn = |prefixes: &Prefixes| match trim {
        true => gpu.clip(&index.refined(prefixes, scene.nodes(), |r| gpu.covers(&r))),
        false => gpu.clip(&prefixes.bounds()),
    };
    let all = gpu.resident_slices() == gpu.planned_slices();
    if all || gpu.asked_fitted.load(Ordering::Relaxed) {
        let asked = index.prefixes(eye, eps, Some(cone));
        let wanted = asked.bounds();
        let fits = wanted.iter().all(|r| gpu.covers(r));
        gpu.asked_fitted.store(fits, Ordering::Relaxed);
        if fits {
            return (eps, drawn(&asked), wanted);
        }
    }
    let loaded = |start, count| gpu.resident_run(start, count);
    let Fit { eps: fit, wanted } = index.fit(eye, eps, Some(cone), gpu.slice_nodes, loaded);
    gpu.asked_fitted.store(fit == eps, Ordering::Relaxed);
    if gpu.resident_slices() == 0 {
        return (eps, Vec::new(), wanted);
    }
    (fit, drawn(&index.prefixes(eye, fit, Some(cone))), wanted)
}

/// Plans a frame of `scene` seen by `camera` over `size` pixels, with what `gpu` holds
/// of its list. `compute`: whether compute culling will run; `trim`: whether each
/// prefix ends at its node ([`crate::render::PrefixCut`]).
pub(super) fn plan(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    (width, height): (u32, u32),
    gpu: &GpuScene,
    (compute, trim): (bool, bool),
) -> EncodedFrame {
    let started = std::time::Instant::now();
    let eps = error_per_distance(settings.error_px, camera.fov_y, height);
    let wanted_eps = if settings.lod { eps } else { 0.0 };
    let meta = scene.meta();
    let lod_eye = settings.lod_eye.unwrap_or(camera.eye) - DVec3::from(meta.origin);
    let aspect = width as f64 / height.max(1) as f64;
    let cone = camera.view_cone(meta, aspect);
    let (lod_eps, ranges, wanted) = fitting_eps(scene, (lod_eye, &cone), wanted_eps, gpu, trim);
    let mut wanted_slices: Vec<usize> = wanted.iter().flat_map(|r| gpu.slices_of(r)).collect();
    wanted_slices.dedup();
    EncodedFrame {
        far_models: 0,
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
