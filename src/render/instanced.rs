//! Drawing a scene of instances ([`InstancedScene`]): each model's list on the GPU once
//! ([`GpuInstances`]), and per frame, for each instance the view may see, its
//! placement and its model's ranges ([`crate::tree::instances::lod`]); the survivors
//! of all models then go through the same passes as one model's.
//!
//! ```text
//! CPU: groups ─► visible instances ─► placement (f64 → eye-relative f32) + ranges
//!      (test range k carries its instance's placement index)
//! GPU: cull (survivor = node, placement) ─► splat passes (node at its placement) ─► shading
//! ```
//!
//! Each model's slices hold room for a frame's survivors and ranges
//! ([`InstancedRoom`]); a frame whose ranges would test more nodes than a slice's
//! survivor list holds is planned again at a coarser ε (as a streamed model is: a
//! coarser cut, never a holed one).

use std::ops::Range;

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use glam::DVec3;

use super::camera::Camera;
use super::frame::FrameUniform;
use super::gpu_scene::{GpuScene, InstancedRoom, Share};
use super::placement::Placement;
use super::plan::EncodedFrame;
use super::renderer::{FrameStats, Image, Renderer};
use super::settings::{Culling, Mode, Settings};
use super::targets::FrameTargets;
use super::upload;
use crate::tree::instances::InstancedScene;
use crate::tree::instances::lod::{ModelLod, NearBy};
use crate::tree::select::{ViewCone, error_per_distance};

/// An instance takes its ranges by its distance alone ([`ModelLod::far`]) from this many
/// of its sphere's radii away: its chunks' own distances then differ from the sphere's
/// by at most a factor 1.5, so it hands over few more nodes than its chunks'
/// prefixes would. Nearer, its chunks are searched one by one.
const FAR_RADII: f64 = 4.0;

/// Survivors a slice holds room for at least: a 1920×1080 frame's pixels eight times
/// over (128 MiB: a node and a placement index each). A forest seen across at ε = 1 px
/// asks for more (every leaf within a hundred metres is a pixel): such frames coarsen.
const MIN_SURVIVOR_ROOM: usize = 1 << 24;

/// Instances a frame may hand over chunk by chunk (near ones) before their ranges are
/// joined: the test ranges' room is two per instance and this many per chunk.
const NEAR_INSTANCES: usize = 16;

/// The models of a scene on the GPU, and their levels of detail.
pub struct GpuInstances {
    pub models: Vec<GpuScene>,
    lods: Vec<ModelLod>,
}

/// A scene's GPU memory: its models' lists, their survivor room, and what each
/// instance adds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneMemory {
    /// Every slice's buffers but the survivor room and the instances' share.
    pub models: u64,
    /// Survivor lists (a node index and a placement index each), beyond one index a
    /// node.
    pub survivor_room: u64,
    /// A placement and room for two test ranges.
    pub per_instance: u64,
}

impl GpuInstances {
    /// Bytes of every buffer, by what it is for (the room of `upload_instanced`).
    pub fn memory(&self) -> SceneMemory {
        let per_instance =
            (size_of::<Placement>() + 2 * size_of::<super::cull::TestRange>()) as u64;
        let (mut all, mut survivor_room, mut instances) = (0, 0, 0);
        for g in &self.models {
            let count = g.placements.size() / size_of::<Placement>() as u64;
            all += g.resident_bytes() + g.placements.size();
            instances += count * per_instance;
            if let Some(room) = g.room {
                let slices = g.resident_slices() as u64;
                survivor_room += slices * (8 * room.survivors as u64) - 4 * g.total as u64;
            }
        }
        SceneMemory {
            models: all.saturating_sub(survivor_room + instances),
            survivor_room,
            per_instance,
        }
    }
}

/// A frame of a scene as recorded: the frame's plan (the GPU's counters read as a
/// model's), the instances drawn, and the test ranges.
#[derive(Debug, Clone)]
pub struct InstancedFrame {
    pub frame: EncodedFrame,
    pub visible: usize,
    pub ranges: usize,
}

/// What the CPU decided for one frame of a scene: per model, the placements of its
/// visible instances and the ranges they hand over.
struct Planned {
    placements: Vec<Vec<Placement>>,
    /// Per model: ranges and each one's placement index.
    ranges: Vec<Vec<(Range<usize>, u32)>>,
    visible: usize,
    eps: f64,
    coarsened: bool,
    /// The near plane: half the distance from the eye to the nearest visible
    /// instance's sphere, or 10⁻⁴ of its radius when the eye is inside it.
    near: f64,
    /// Nodes handed over, and the share of the visible groups planned (less than 1
    /// when the plan stopped: far too many nodes to test).
    tested: usize,
    planned_share: f64,
}

impl Renderer {
    /// Uploads each model of `scene` once, with room for its instances.
    pub fn upload_instanced(&self, scene: &InstancedScene) -> GpuInstances {
        let models = scene
            .models
            .iter()
            .enumerate()
            .map(|(m, model)| {
                let count = scene.count_of(m).max(1);
                let nodes = model.nodes().len();
                let chunks = model.index.chunks().len();
                let most = (self.gpu.max_binding_bytes() / 4) as usize;
                let room = InstancedRoom {
                    survivors: (2 * nodes).max(MIN_SURVIVOR_ROOM).min(most),
                    ranges: 2 * count + NEAR_INSTANCES * chunks,
                };
                let has_attributes = model.meta().has_attributes;
                let mut gpu = upload::empty_gpu_scene(
                    &self.gpu,
                    nodes,
                    None,
                    has_attributes,
                    Some((count, room)),
                );
                let home = gpu.home();
                for k in 0..gpu.planned_slices() {
                    let range = gpu.slice_range(k);
                    gpu.insert(self.upload_slice(model, &home, k, range));
                }
                gpu
            })
            .collect();
        let lods = scene.models.iter().map(ModelLod::new).collect();
        GpuInstances { models, lods }
    }

    /// Renders one frame of `scene` and reads it back, with its statistics (`selected`:
    /// the GPU's count) and the instances it drew.
    pub fn render_instanced(
        &self,
        scene: &InstancedScene,
        gpu: &GpuInstances,
        camera: &Camera,
        settings: &Settings,
        size: (u32, u32),
    ) -> anyhow::Result<(Image, FrameStats, usize)> {
        let targets = self.targets(size)?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let drawn =
            self.encode_instanced(&mut encoder, &targets, (scene, gpu), camera, settings)?;
        let all: Vec<&GpuScene> = gpu.models.iter().collect();
        let frame = &drawn.frame;
        let (image, counters) = self.read_frame(encoder, &targets, &all, frame)?;
        let stats = FrameStats {
            tested: frame.tested,
            chunks: scene.models.iter().map(|m| m.index.chunks().len()).sum(),
            chunks_tested: drawn.ranges,
            selected: counters.drawn.unwrap_or(0) as usize,
            gpu_ms: counters.gpu_ms,
            passes_ms: counters.passes_ms,
            gpu_drawn: counters.drawn,
            gpu_outline: counters.outline,
            eps: frame.eps,
            coarsened: frame.coarsened,
            plan_ms: frame.plan_ms,
        };
        Ok((image, stats, drawn.visible))
    }

    /// Records one frame of `scene` into `encoder`, drawing into `targets.output`; the
    /// uniform, placements and compaction records are written through the queue (they
    /// take effect at the next submit). Compute culling always runs (the survivors
    /// carry their placements).
    pub fn encode_instanced(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        (scene, gpu): (&InstancedScene, &GpuInstances),
        camera: &Camera,
        settings: &Settings,
    ) -> anyhow::Result<InstancedFrame> {
        if settings.mode == Mode::Mesh {
            anyhow::bail!("mesh mode draws one model's triangles; a scene draws splats");
        }
        let size = targets.size;
        let settings = &Settings {
            culling: Culling::Compute,
            ..*settings
        };
        let rasterized = self.rasterized(settings, size)?;
        let started = std::time::Instant::now();
        let planned = self.plan_instances(scene, gpu, camera, settings, size);
        let mut uniform = FrameUniform::new(&scene.meta, camera, settings, size, planned.eps);
        // The scene's box may span a country: the near plane comes from the instances
        // in view instead (half the distance to the nearest one's sphere).
        let aspect = size.0 as f64 / size.1.max(1) as f64;
        uniform.near = planned.near as f32;
        uniform.proj = camera.projection(aspect, planned.near).to_cols_array_2d();
        let queue = &self.gpu.queue;
        queue.write_buffer(&targets.frame_buffer, 0, bytemuck::bytes_of(&uniform));
        let mut shares = Vec::new();
        for (m, g) in gpu.models.iter().enumerate() {
            let placements = &planned.placements[m];
            if !placements.is_empty() {
                queue.write_buffer(&g.placements, 0, bytemuck::cast_slice(placements));
            }
            shares.extend(placed_shares(g, &planned.ranges[m]));
        }
        let plan_ms = started.elapsed().as_secs_f64() * 1e3;
        self.encode_passes(
            encoder,
            targets,
            &shares,
            settings,
            (true, rasterized, None),
        );
        let frame = EncodedFrame {
            ranges: Vec::new(),
            tested: shares.iter().map(|s| s.count as usize).sum(),
            compute: true,
            eps: planned.eps,
            coarsened: planned.coarsened,
            slices: gpu.models.iter().map(|g| g.resident_slices()).sum(),
            wanted_slices: Vec::new(),
            lod_eye: DVec3::ZERO,
            plan_ms,
        };
        Ok(InstancedFrame {
            frame,
            visible: planned.visible,
            ranges: planned.ranges.iter().map(Vec::len).sum(),
        })
    }

    /// Plans a frame of `scene`: ε from the settings, raised by quarter octaves until
    /// every slice's ranges test no more nodes than its survivor list holds; ranges
    /// beyond a slice's room are joined across their smallest gaps first (the GPU
    /// then tests the nodes between them too, and rejects them).
    fn plan_instances(
        &self,
        scene: &InstancedScene,
        gpu: &GpuInstances,
        camera: &Camera,
        settings: &Settings,
        (width, height): (u32, u32),
    ) -> Planned {
        let asked = match settings.lod {
            true => error_per_distance(settings.error_px, camera.fov_y, height),
            false => 0.0,
        };
        let aspect = width as f64 / height.max(1) as f64;
        let origin = DVec3::from(scene.meta.origin);
        let wide = shifted(&camera.view_cone(&scene.meta, aspect), -origin);
        let (right, up, forward) = (wide.right, wide.up, wide.forward);
        // Culling keeps what lies in front of the eye at all; the near plane is set
        // from what it kept.
        let cone = ViewCone::new(
            camera.eye,
            [right, up, forward],
            wide.tan_half_fov,
            f64::MIN_POSITIVE,
        );
        let lod_eye = settings.lod_eye.unwrap_or(camera.eye);
        let mut eps = asked;
        loop {
            let view = View {
                eye: camera.eye,
                lod_eye,
                cone: &cone,
                eps,
            };
            let mut planned = plan_at(scene, gpu, &view);
            for (g, ranges) in gpu.models.iter().zip(&mut planned.ranges) {
                if let Some(room) = g.room {
                    merge_to(
                        ranges,
                        room.ranges.saturating_sub(g.planned_slices()).max(1),
                    );
                }
            }
            let over = (gpu.models.iter().zip(&planned.ranges))
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
                    ..planned
                };
            }
            // The nodes tested fall about as 1/ε² (a cut of a surface seen from afar).
            eps = (eps * over.sqrt().clamp(2f64.powf(0.25), 4.0)).max(floor);
        }
    }
}

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
}

/// The visible instances' placements and ranges at `view.eps`: groups in parallel,
/// each batch's placement indices renumbered as the batches are joined.
fn plan_at(scene: &InstancedScene, gpu: &GpuInstances, view: &View) -> Planned {
    let groups: Vec<Range<usize>> = scene
        .groups
        .visible(view.cone, scene.instances.len())
        .collect();
    let models = scene.models.len();
    // A plan that tests more than HOPELESS rooms' worth stops: the frame will coarsen
    // by about the ratio, which the groups planned so far tell well enough.
    let room = gpu
        .models
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
            let mut part = Planned::empty(models, view.eps);
            for group in batch {
                if tested.load(Ordering::Relaxed) > limit {
                    break;
                }
                let before = part.tested;
                plan_group(scene, gpu, view, group.clone(), &mut part);
                tested.fetch_add(part.tested - before, Ordering::Relaxed);
                done.fetch_add(1, Ordering::Relaxed);
            }
            part
        })
        .collect();
    let mut all = Planned::empty(models, view.eps);
    for part in parts {
        all.join(part);
    }
    all.planned_share = done.into_inner() as f64 / groups.len().max(1) as f64;
    all
}

/// Rooms' worth of nodes to test after which a plan stops.
const HOPELESS: usize = 1;

/// Adds the instances of `group` that `view` sees to `out`.
fn plan_group(
    scene: &InstancedScene,
    gpu: &GpuInstances,
    view: &View,
    group: Range<usize>,
    out: &mut Planned,
) {
    let mut near_by: Vec<NearBy> = (0..scene.models.len()).map(|_| NearBy::default()).collect();
    for instance in &scene.instances[group] {
        let m = instance.model as usize;
        let (model, lod) = (&scene.models[m], &gpu.lods[m]);
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
        let found = match d > FAR_RADII * lod.radius && view.eps > 0.0 {
            true => lod.far(model, d, view.eps, &mut near_by[m]),
            false => {
                let eye = to_world.eye_to_model(view.lod_eye) - origin;
                let cone = shifted(&to_world.cone_to_model(view.cone), origin);
                lod.near(model, eye, &cone, view.eps).into()
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
            visible: 0,
            eps,
            coarsened: false,
            near: f64::INFINITY,
            tested: 0,
            planned_share: 1.0,
        }
    }

    /// Appends `part`, its placement indices moved past this one's.
    fn join(&mut self, part: Planned) {
        for (m, (placements, ranges)) in part.placements.into_iter().zip(part.ranges).enumerate() {
            let offset = self.placements[m].len() as u32;
            self.placements[m].extend(placements);
            self.ranges[m].extend(ranges.into_iter().map(|(r, p)| (r, p + offset)));
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

/// Each resident slice of `g` with its part of `ranges` (list indices, each with its
/// placement), relative to the slice.
fn placed_shares<'a>(g: &'a GpuScene, ranges: &[(Range<usize>, u32)]) -> Vec<Share<'a>> {
    let mut shares: Vec<Share> = g
        .resident()
        .map(|slice| Share {
            slice,
            ranges: Vec::new(),
            placements: Vec::new(),
            count: 0,
        })
        .collect();
    for (r, placement) in ranges {
        for share in &mut shares {
            let (first, end) = (
                share.slice.first,
                share.slice.first + share.slice.count as usize,
            );
            let part = r.start.max(first)..r.end.min(end);
            if part.is_empty() {
                continue;
            }
            share.count += part.len() as u32;
            share
                .ranges
                .push((part.start - first) as u32..(part.end - first) as u32);
            share.placements.push(*placement);
        }
    }
    shares
}
