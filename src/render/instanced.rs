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

use glam::DVec3;

use super::camera::Camera;
use super::frame::FrameUniform;
use super::gpu_scene::{GpuScene, Share};
use super::placement::Placement;
use super::plan::EncodedFrame;
use super::renderer::{FrameStats, Image, Renderer};
use super::settings::{Culling, Mode, Settings};
use super::upload::{self, InstancedRoom};
use crate::tree::instances::InstancedScene;
use crate::tree::instances::lod::ModelLod;
use crate::tree::select::{ViewCone, error_per_distance};

/// Survivors a slice holds room for at least: enough for a 1920×1080 frame's splats
/// several layers deep.
const MIN_SURVIVOR_ROOM: usize = 1 << 22;

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
                    ranges: 2 * count + chunks,
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
        if settings.mode == Mode::Mesh {
            anyhow::bail!("mesh mode draws one model's triangles; a scene draws splats");
        }
        let targets = self.targets(size)?;
        let settings = &Settings {
            culling: Culling::Compute,
            ..*settings
        };
        let rasterized = self.rasterized(settings, size)?;
        let started = std::time::Instant::now();
        let planned = self.plan_instances(scene, gpu, camera, settings, size);
        let plan_ms = started.elapsed().as_secs_f64() * 1e3;
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
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.encode_passes(
            &mut encoder,
            &targets,
            &shares,
            settings,
            (true, rasterized, None),
        );
        let tested: usize = shares.iter().map(|s| s.count as usize).sum();
        let frame = EncodedFrame {
            ranges: Vec::new(),
            tested,
            compute: true,
            eps: planned.eps,
            coarsened: planned.coarsened,
            slices: gpu.models.iter().map(|g| g.resident_slices()).sum(),
            wanted_slices: Vec::new(),
            lod_eye: DVec3::ZERO,
            plan_ms,
        };
        let all: Vec<&GpuScene> = gpu.models.iter().collect();
        let (image, counters) = self.read_frame(encoder, &targets, &all, &frame)?;
        let stats = FrameStats {
            tested,
            chunks: scene.models.iter().map(|m| m.index.chunks().len()).sum(),
            chunks_tested: planned.ranges.iter().map(Vec::len).sum(),
            selected: counters.drawn.unwrap_or(0) as usize,
            gpu_ms: counters.gpu_ms,
            passes_ms: counters.passes_ms,
            gpu_drawn: counters.drawn,
            gpu_outline: counters.outline,
            eps: planned.eps,
            coarsened: planned.coarsened,
            plan_ms,
        };
        Ok((image, stats, planned.visible))
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
            let mut planned = plan_at(scene, gpu, (camera.eye, lod_eye, &cone), eps);
            for (g, ranges) in gpu.models.iter().zip(&mut planned.ranges) {
                if let Some(room) = g.room {
                    merge_to(
                        ranges,
                        room.ranges.saturating_sub(g.planned_slices()).max(1),
                    );
                }
            }
            let fits = gpu
                .models
                .iter()
                .zip(&planned.ranges)
                .all(|(g, r)| fits(g, r));
            let floor = error_per_distance(1.0, camera.fov_y, height) * 1e-3;
            if fits || eps > 1.0 {
                return Planned {
                    coarsened: eps != asked,
                    ..planned
                };
            }
            eps = (eps * 2f64.powf(0.25)).max(floor);
        }
    }
}

/// Joins ranges of the same placement across their smallest gaps until at most
/// `target` remain (a placement's ranges are ascending and consecutive in the list).
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
    let mut out: Vec<(Range<usize>, u32)> = Vec::with_capacity(target);
    for (r, p) in ranges.drain(..) {
        match out.last_mut() {
            Some((last, q)) if *q == p && r.start - last.end <= widest => last.end = r.end,
            _ => out.push((r, p)),
        }
    }
    *ranges = out;
}

/// Whether `ranges` (of one model) fit every slice's room.
fn fits(g: &GpuScene, ranges: &[(Range<usize>, u32)]) -> bool {
    let Some(room) = g.room else { return true };
    let (mut tested, mut count) = (
        vec![0usize; g.planned_slices()],
        vec![0usize; g.planned_slices()],
    );
    for (r, _) in ranges {
        for k in g.slices_of(r) {
            let s = g.slice_range(k);
            tested[k] += r.end.min(s.end) - r.start.max(s.start);
            count[k] += 1;
        }
    }
    tested.iter().all(|&t| t <= room.survivors) && count.iter().all(|&c| c <= room.ranges)
}

/// The visible instances' placements and ranges at `eps`: eyes (the camera's, and
/// the one the level of detail is chosen for) and the view cone in world units.
fn plan_at(
    scene: &InstancedScene,
    gpu: &GpuInstances,
    (eye, lod_eye, cone): (DVec3, DVec3, &ViewCone),
    eps: f64,
) -> Planned {
    let models = scene.models.len();
    let mut placements = vec![Vec::new(); models];
    let mut ranges = vec![Vec::new(); models];
    let mut visible = 0;
    let mut near = f64::INFINITY;
    for group in scene.groups.visible(cone, scene.instances.len()) {
        for instance in &scene.instances[group] {
            let (c, r) = scene.groups.sphere_of(instance);
            if !cone.sees_sphere(c, r) {
                continue;
            }
            let gap = (c - eye).length() - r;
            near = near.min(if gap > 0.0 { 0.5 * gap } else { 1e-4 * r });
            let m = instance.model as usize;
            let model = &scene.models[m];
            let meta = model.meta();
            let origin = DVec3::from(meta.origin);
            let to_world = instance.similarity();
            let model_eye = to_world.eye_to_model(lod_eye) - origin;
            let model_cone = shifted(&to_world.cone_to_model(cone), origin);
            let found = gpu.lods[m].ranges(model, model_eye, &model_cone, eps);
            if found.is_empty() {
                continue;
            }
            let index = placements[m].len() as u32;
            placements[m].push(Placement::new(&to_world, origin, eye, meta.error_scale));
            ranges[m].extend(found.iter().map(|r| (r.clone(), index)));
            visible += 1;
        }
    }
    Planned {
        placements,
        ranges,
        visible,
        eps,
        coarsened: false,
        near: if near.is_finite() { near } else { 1.0 },
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
