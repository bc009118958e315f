//! The CPU's plan of a frame of a scene ([`super::instanced`]): the instances the view
//! may see, each one's placement and its model's ranges at ε
//! ([`crate::tree::instances::lod`]), ε raised where the ranges would overfill the
//! models' room.

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::camera::Camera;
use super::far::FarPlan;
use super::gpu_scene::GpuScene;
use super::placement::Placement;
use super::settings::Settings;
use crate::tree::TreeMeta;
use crate::tree::instances::InstancedScene;
use crate::tree::instances::groups::Group;
use crate::tree::instances::lod::{ModelLod, NearBy, SLOTS};
use crate::tree::select::{ViewCone, error_per_distance};

/// An instance takes its ranges by its distance alone ([`ModelLod::far`]) from this many
/// of its sphere's radii away: its chunks' own distances then differ from the sphere's
/// by at most a factor 1.5, so it hands over few more nodes than its chunks'
/// prefixes would. Nearer, its chunks are searched one by one.
const FAR_RADII: f64 = 4.0;

/// What the frame before drew: the ε it asked and drew, and how full it filled its room
/// (over 1 where the GPU's far instances asked for more survivors than it held).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LastFrame {
    pub asked: f64,
    pub drawn: f64,
    pub fill: f64,
}

/// What the CPU decided for one frame of a scene: per model, the placements of its
/// visible instances and the ranges they hand over.
pub(super) struct Planned {
    pub placements: Vec<Vec<Placement>>,
    /// Per model: ranges and each one's placement index.
    pub ranges: Vec<Vec<(Range<usize>, u32)>>,
    /// Per model: the far groups handed to the GPU whole (`far.rs`).
    pub far: Vec<FarPlan>,
    /// Instances the CPU planned (the GPU counts the far groups' own).
    pub visible: usize,
    pub eps: f64,
    pub coarsened: bool,
    /// The near plane: half the distance from the eye to the nearest visible
    /// instance's sphere, or 10⁻⁴ of its radius when the eye is inside it.
    pub near: f64,
    /// Nodes handed over, and the share of the visible groups planned (less than 1
    /// when the plan stopped: far too many nodes to test).
    tested: usize,
    planned_share: f64,
    /// The ε the settings asked for, and how full the fullest room is (at most 1).
    pub asked: f64,
    pub fill: f64,
}

/// Plans a frame of `scene`: ε from the settings, raised by quarter octaves until
/// every slice's ranges test no more nodes than its survivor list holds; ranges
/// beyond a slice's room are joined across their smallest gaps first (the GPU
/// then tests the nodes between them too, and rejects them).
///
/// `last`: the ε asked and drawn of the frame before, and how full its room was. Where
/// that frame asked the same ε and had to coarsen, the search starts where it drew (a
/// view changes little from frame to frame) instead of at the asked ε, whose plan would
/// overfill again; a quarter octave finer where the room was filled less than half
/// (a step's worth twice over: the survivors grow as 1/ε² or faster, measured up to 1/ε³
/// on the forest, and a frame that overfills is drawn again), so that frames refine
/// as the view allows without swinging between two steps. A fill over 1 is the GPU's:
/// its far instances asked for more survivors than the room held, and the search
/// starts coarser by the square root.
///
/// `on_gpu[m]`: whether model m's far groups go to the GPU whole; `trim`: whether a
/// near instance's prefixes end at their node (else at their block).
pub(super) fn plan(
    (scene, models, lods): (&InstancedScene, &[GpuScene], &[ModelLod]),
    (camera, settings): (&Camera, &Settings),
    (width, height): (u32, u32),
    (last, on_gpu, trim): (Option<LastFrame>, &[bool], bool),
) -> Planned {
    let asked = match settings.lod {
        true => error_per_distance(settings.error_px, camera.fov_y, height),
        false => 0.0,
    };
    let start = match last {
        Some(LastFrame {
            asked: was,
            drawn,
            fill,
        }) if was == asked && fill > 1.0 => {
            on_steps(asked, drawn * fill.sqrt().clamp(QUARTER_OCTAVE, 4.0))
        }
        Some(LastFrame {
            asked: was,
            drawn,
            fill,
        }) if was == asked && drawn > asked => {
            let finer = fill * QUARTER_OCTAVE.powi(4) < 1.0;
            on_steps(asked, if finer { drawn / QUARTER_OCTAVE } else { drawn })
        }
        _ => asked,
    };
    let cone = instance_cone(&scene.meta, camera, (width, height));
    let firsts: Vec<usize> = (0..scene.models.len())
        .map(|m| scene.instances.partition_point(|i| (i.model as usize) < m))
        .collect();
    let lod_eye = settings.lod_eye.unwrap_or(camera.eye);
    let mut eps = start;
    loop {
        let view = View {
            eye: camera.eye,
            lod_eye,
            cone: &cone,
            eps,
            on_gpu,
            trim,
            firsts: &firsts,
        };
        let mut planned = plan_at((scene, models, lods), &view);
        for (g, ranges) in models.iter().zip(&mut planned.ranges) {
            if let Some(room) = g.room {
                merge_to(
                    ranges,
                    room.ranges.saturating_sub(g.planned_slices()).max(1),
                );
            }
        }
        let over = (models.iter().zip(&planned.ranges))
            .map(|(g, r)| overflow(g, r))
            .fold(0.0, f64::max)
            / planned.planned_share.max(1e-3);
        let floor = error_per_distance(1.0, camera.fov_y, height) * 1e-3;
        if over <= 1.0 || eps > 1.0 {
            let near = if planned.near.is_finite() {
                planned.near
            } else {
                1.0
            };
            return Planned {
                coarsened: eps != asked,
                near,
                asked,
                fill: over,
                ..planned
            };
        }
        // The nodes tested fall about as 1/ε² (a cut of a surface seen from afar).
        eps = on_steps(
            asked,
            (eps * over.sqrt().clamp(QUARTER_OCTAVE, 4.0)).max(floor),
        );
    }
}

/// The least ε ≥ `eps` of the quarter-octave steps above `asked` (asked · 2^(k/4), k ≥
/// 0; `eps` itself when nothing was asked: leaves only). A coarsened frame draws at one
/// of a few ε, whose tables of far ranges (lod.rs, far.rs) the frames after it find
/// kept.
fn on_steps(asked: f64, eps: f64) -> f64 {
    if asked <= 0.0 {
        return eps;
    }
    let k = ((eps / asked).log2() * 4.0 - 1e-6).ceil().max(0.0);
    asked * (k / 4.0).exp2()
}

/// The view cone instances are culled by: world units, apex at the eye, keeping what
/// lies in front of the eye at all (the near plane is set from what it kept).
pub(super) fn instance_cone(
    meta: &TreeMeta,
    camera: &Camera,
    (width, height): (u32, u32),
) -> ViewCone {
    let aspect = width as f64 / height.max(1) as f64;
    let origin = DVec3::from(meta.origin);
    let wide = shifted(&camera.view_cone(meta, aspect), -origin);
    let axes = [wide.right, wide.up, wide.forward];
    ViewCone::new(camera.eye, axes, wide.tan_half_fov, f64::MIN_POSITIVE)
}

/// 2^¼: the least step of ε.
const QUARTER_OCTAVE: f64 = 1.189_207_115_002_721;

/// Widest gap joined: a block of the prefix search.
const MAX_JOINED_GAP: usize = 64;

/// Joins ranges of the same placement across their smallest gaps (at most
/// [`MAX_JOINED_GAP`] nodes) until at most `target` remain, or as few as such gaps
/// allow (a placement's ranges are ascending and consecutive in the list).
fn merge_to(ranges: &mut Vec<(Range<usize>, u32)>, target: usize) {
    if ranges.len() <= target {
        return;
    }
    let mut gaps: Vec<usize> = ranges
        .windows(2)
        .filter(|w| w[0].1 == w[1].1)
        .map(|w| w[1].0.start - w[0].0.end)
        .collect();
    let joins = (ranges.len() - target).min(gaps.len());
    if joins == 0 {
        return;
    }
    let (_, &mut widest, _) = gaps.select_nth_unstable(joins - 1);
    // Gaps wider than a block of the prefix search are not worth testing: the frame
    // coarsens instead (`overflow` counts the ranges left over the room).
    let widest = widest.min(MAX_JOINED_GAP);
    let mut out: Vec<(Range<usize>, u32)> = Vec::with_capacity(target);
    for (r, p) in ranges.drain(..) {
        match out.last_mut() {
            Some((last, q)) if *q == p && r.start - last.end <= widest => last.end = r.end,
            _ => out.push((r, p)),
        }
    }
    *ranges = out;
}

/// How far `ranges` (of one model) overfill its slices' room: the fullest slice's nodes
/// to test over the survivors it holds, or the ranges over their room, whichever is
/// larger (at most 1: they fit).
fn overflow(g: &GpuScene, ranges: &[(Range<usize>, u32)]) -> f64 {
    let Some(room) = g.room else { return 0.0 };
    let too_many =
        ranges.len() as f64 / room.ranges.saturating_sub(g.planned_slices()).max(1) as f64;
    let mut tested = vec![0usize; g.planned_slices()];
    for (r, _) in ranges {
        for k in g.slices_of(r) {
            let s = g.slice_range(k);
            tested[k] += r.end.min(s.end) - r.start.max(s.start);
        }
    }
    (tested.iter().map(|&t| t as f64 / room.survivors as f64)).fold(too_many, f64::max)
}

/// What the frame's plan reads: the eyes (the camera's, and the one the level of
/// detail is chosen for), the view cone (world units) and ε.
struct View<'a> {
    eye: DVec3,
    lod_eye: DVec3,
    cone: &'a ViewCone,
    eps: f64,
    on_gpu: &'a [bool],
    trim: bool,
    /// Each model's first instance in the scene's list (sorted by model).
    firsts: &'a [usize],
}

/// The visible instances' placements and ranges at `view.eps`: groups in parallel,
/// each batch's placement indices renumbered as the batches are joined.
fn plan_at(
    (scene, models, lods): (&InstancedScene, &[GpuScene], &[ModelLod]),
    view: &View,
) -> Planned {
    let count = scene.models.len();
    let mut far: Vec<FarPlan> = vec![FarPlan::default(); count];
    let mut far_near = f64::INFINITY;
    let mut groups: Vec<Range<usize>> = Vec::new();
    for group in scene.groups.visible(view.cone) {
        let m = group.model as usize;
        match far_slots(group, &lods[m], view) {
            Some((slots, gap)) => {
                let (base, members) = (view.firsts[m], group.members());
                far[m].add(members.start - base..members.end - base, slots);
                far_near = far_near.min(0.5 * gap);
            }
            None => groups.push(group.members()),
        }
    }
    // A plan that tests more than HOPELESS rooms' worth stops: the frame will coarsen
    // by about the ratio, which the groups planned so far tell well enough.
    let room = models
        .iter()
        .filter_map(|g| g.room)
        .map(|r| r.survivors)
        .min();
    let limit = room.map_or(usize::MAX, |r| HOPELESS * r);
    let tested = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let parts: Vec<Planned> = groups
        .par_chunks(16)
        .map(|batch| {
            let mut part = Planned::empty(count, view.eps);
            for group in batch {
                if tested.load(Ordering::Relaxed) > limit {
                    break;
                }
                let before = part.tested;
                plan_group((scene, lods), view, group.clone(), &mut part);
                tested.fetch_add(part.tested - before, Ordering::Relaxed);
                done.fetch_add(1, Ordering::Relaxed);
            }
            part
        })
        .collect();
    let mut all = Planned::empty(count, view.eps);
    for part in parts {
        all.join(part);
    }
    for (all, far) in all.far.iter_mut().zip(far) {
        all.join(far);
    }
    all.near = all.near.min(far_near);
    all.planned_share = done.into_inner() as f64 / groups.len().max(1) as f64;
    all
}

/// Rooms' worth of nodes to test after which a plan stops.
const HOPELESS: usize = 1;

/// Where `group`'s members all lie far enough for the GPU to place them whole (at least
/// [`FAR_RADII`] of their spheres' radii outside them, their model's far groups handed
/// to the GPU, ε > 0): the table slots their distances reach, and the group's distance
/// to the eye (a bound on each member's).
///
/// With g the eye's distance to the group's sphere and s a member's scale, the eye lies
/// at least g / s model units outside the member's sphere, and at most (|c − eye| + R) / s.
fn far_slots(group: &Group, lod: &ModelLod, view: &View) -> Option<(Range<usize>, f64)> {
    let m = group.model as usize;
    if !view.on_gpu.get(m).copied().unwrap_or(false) || view.eps <= 0.0 {
        return None;
    }
    let centre = (group.centre - view.eye).length();
    let gap = centre - group.radius;
    let (s_min, s_max) = (group.scale_min as f64, group.scale_max as f64);
    if gap <= FAR_RADII * lod.radius * s_max {
        return None;
    }
    // A slot's margin either side for the GPU's f32.
    let lo = lod.slot(gap / s_max).saturating_sub(1);
    let hi = (lod.slot((centre + group.radius) / s_min) + 2).min(SLOTS);
    Some((lo..hi, gap))
}

/// Adds the instances of `group` that `view` sees to `out`.
fn plan_group(
    (scene, lods): (&InstancedScene, &[ModelLod]),
    view: &View,
    group: Range<usize>,
    out: &mut Planned,
) {
    let mut near_by: Vec<NearBy> = (0..scene.models.len()).map(|_| NearBy::default()).collect();
    for (k, instance) in group.clone().zip(&scene.instances[group]) {
        let m = instance.model as usize;
        let (model, lod) = (&scene.models[m], &lods[m]);
        let meta = model.meta();
        let origin = DVec3::from(meta.origin);
        let to_world = instance.similarity();
        let centre = to_world.apply(origin + lod.centre());
        let radius = lod.radius * to_world.scale;
        if !view.cone.sees_sphere(centre, radius) {
            continue;
        }
        let gap = (centre - view.eye).length() - radius;
        let d = lod.gap((centre - view.lod_eye).length(), to_world.scale);
        let far = d > FAR_RADII * lod.radius && view.eps > 0.0;
        if far && view.on_gpu[m] {
            // The GPU places it (its cone test again, its slot from d).
            let slot = lod.slot(d);
            let slots = slot.saturating_sub(1)..(slot + 2).min(SLOTS);
            out.far[m].add_member(k - view.firsts[m], slots);
            out.near = out.near.min(0.5 * gap);
            continue;
        }
        let found = match far {
            true => lod.far(model, d, view.eps, &mut near_by[m]),
            false => {
                let eye = to_world.eye_to_model(view.lod_eye) - origin;
                let cone = shifted(&to_world.cone_to_model(view.cone), origin);
                lod.near(model, (eye, &cone), view.eps, view.trim).into()
            }
        };
        if found.is_empty() {
            continue;
        }
        out.near = out
            .near
            .min(if gap > 0.0 { 0.5 * gap } else { 1e-4 * radius });
        let index = out.placements[m].len() as u32;
        out.placements[m].push(Placement::new(
            &to_world,
            origin,
            view.eye,
            meta.error_scale,
        ));
        out.ranges[m].extend(found.iter().map(|r| (r.clone(), index)));
        out.tested += found.iter().map(|r| r.len()).sum::<usize>();
        out.visible += 1;
    }
}

impl Planned {
    fn empty(models: usize, eps: f64) -> Planned {
        Planned {
            placements: vec![Vec::new(); models],
            ranges: vec![Vec::new(); models],
            far: vec![FarPlan::default(); models],
            visible: 0,
            eps,
            coarsened: false,
            near: f64::INFINITY,
            tested: 0,
            planned_share: 1.0,
            asked: eps,
            fill: 0.0,
        }
    }

    /// Appends `part`, its placement indices moved past this one's.
    fn join(&mut self, part: Planned) {
        for (m, (placements, ranges)) in part.placements.into_iter().zip(part.ranges).enumerate() {
            let offset = self.placements[m].len() as u32;
            self.placements[m].extend(placements);
            self.ranges[m].extend(ranges.into_iter().map(|(r, p)| (r, p + offset)));
        }
        for (far, part) in self.far.iter_mut().zip(part.far) {
            far.join(part);
        }
        self.visible += part.visible;
        self.tested += part.tested;
        self.near = self.near.min(part.near);
    }
}

/// `cone` with its apex moved by −`origin` (into coordinates relative to a model's
/// origin).
fn shifted(cone: &ViewCone, origin: DVec3) -> ViewCone {
    ViewCone::new(
        cone.eye - origin,
        [cone.right, cone.up, cone.forward],
        cone.tan_half_fov,
        cone.near,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_coarsened_eps_lands_on_a_quarter_octave_above_the_asked() {
        let asked = 1e-3;
        assert_eq!(on_steps(asked, asked), asked);
        assert_eq!(
            on_steps(0.0, 0.25),
            0.25,
            "leaves only keeps what it is given"
        );
        for eps in [1.01e-3, 1.3e-3, 2.0e-3, 7.7e-3] {
            let stepped = on_steps(asked, eps);
            let k = (stepped / asked).log2() * 4.0;
            assert!((k - k.round()).abs() < 1e-9, "{eps}: {k} quarter octaves");
            assert!(
                stepped >= eps && stepped < eps * QUARTER_OCTAVE,
                "{eps} → {stepped}"
            );
        }
        // Twice the asked ε is 4 steps, not 5.
        assert!((on_steps(asked, 2.0 * asked) - 2.0 * asked).abs() < 1e-15);
    }
}
