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
use std::sync::Mutex;

use glam::DVec3;

use super::camera::Camera;
use super::far::{FarCounts, FarModel};
use super::frame::FrameUniform;
use super::gpu_scene::{GpuScene, InstancedRoom, Share};
use super::instance_plan::{LastFrame, instance_cone, plan};
use super::placement::Placement;
use super::plan::EncodedFrame;
use super::renderer::{FrameStats, Image, Renderer};
use super::settings::{Culling, Mode, Settings};
use super::targets::FrameTargets;
use super::upload;
use crate::tree::instances::InstancedScene;
use crate::tree::instances::lod::ModelLod;

/// Survivors a slice holds room for at least: a 1920×1080 frame's pixels eight times
/// over (128 MiB: a node and a placement index each). A forest seen across at ε = 1 px
/// asks for more (every leaf within a hundred metres is a pixel): such frames coarsen.
const MIN_SURVIVOR_ROOM: usize = 1 << 24;

/// Instances a frame may hand over chunk by chunk (near ones) before their ranges are
/// joined: the test ranges' room is two per instance (of at most
/// [`CPU_PLANNED`], where the GPU places the far ones) and this many per chunk.
const NEAR_INSTANCES: usize = 16;

/// Instances of a model whose far ones the GPU places that the test ranges' room
/// holds two ranges for.
const CPU_PLANNED: usize = 4096;

/// Times `render_instanced` draws a frame again, coarser, when the GPU's far instances
/// asked for more survivors than the room held.
const REDRAWS: usize = 6;

/// The models of a scene on the GPU, and their levels of detail.
pub struct GpuInstances {
    pub models: Vec<GpuScene>,
    lods: Vec<ModelLod>,
    /// Per model: its far instances on the GPU, where its list is one slice.
    far: Vec<Option<FarModel>>,
    /// The ε asked and drawn of the last frame planned, and how full its room was
    /// (`instance_plan::plan`).
    last: Mutex<Option<LastFrame>>,
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
    /// A placement and the rest: room for two test ranges, or the GPU's record of a
    /// far instance (all models' instances together, rounded up).
    pub per_instance: u64,
}

impl GpuInstances {
    /// Takes what the GPU measured of the far instances of a frame drawn at ε = `eps`:
    /// how full they filled the room left to them, which the next frame's ε follows
    /// (`instance_plan::plan`: coarser where they asked for more survivors than it
    /// held, and some were not drawn; finer only where a quarter octave finer would
    /// fit). Returns whether they overfilled it.
    pub fn observe(&self, far: FarCounts, eps: f64) -> bool {
        let (fill, over) = (far.fill, far.fill > 1.0);
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(last) = last.as_mut()
            && (over || last.drawn == eps)
        {
            last.fill = last.fill.max(fill);
        }
        over
    }

    /// Bytes of every buffer, by what it is for (the room of `upload_instanced`).
    pub fn memory(&self) -> SceneMemory {
        let ranges = 2 * size_of::<super::cull::TestRange>() as u64;
        let (mut all, mut survivor_room, mut instances, mut total) = (0, 0, 0, 0);
        for (g, far) in self.models.iter().zip(&self.far) {
            let count = g.placements.size() / size_of::<Placement>() as u64;
            all += g.resident_bytes() + g.placements.size();
            all += far.as_ref().map_or(0, FarModel::bytes);
            let rest = match far {
                Some(_) => super::far::BYTES_PER_INSTANCE,
                None => ranges,
            };
            instances += count * (size_of::<Placement>() as u64 + rest);
            total += count;
            if let Some(room) = g.room {
                let slices = g.resident_slices() as u64;
                survivor_room += slices * (8 * room.survivors as u64) - 4 * g.total as u64;
            }
        }
        SceneMemory {
            models: all.saturating_sub(survivor_room + instances),
            survivor_room,
            per_instance: instances.div_ceil(total.max(1)),
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

impl Renderer {
    /// Uploads each model of `scene` once, with room for its instances.
    pub fn upload_instanced(&self, scene: &InstancedScene) -> GpuInstances {
        let mut models = scene
            .models
            .iter()
            .enumerate()
            .map(|(m, model)| {
                let count = scene.count_of(m).max(1);
                let nodes = model.nodes().len();
                let chunks = model.index.chunks().len();
                let most = (self.gpu.max_binding_bytes() / 4) as usize;
                let planned = match upload::planned_slices(&self.gpu, nodes) {
                    1 => count.min(CPU_PLANNED),
                    _ => count,
                };
                let room = InstancedRoom {
                    survivors: (2 * nodes).max(MIN_SURVIVOR_ROOM).min(most),
                    ranges: 2 * planned + NEAR_INSTANCES * chunks,
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
            .collect::<Vec<GpuScene>>();
        let far: Vec<Option<FarModel>> = (models.iter_mut().enumerate())
            .map(|(m, g)| {
                let one_slice = g.planned_slices() == 1 && scene.count_of(m) > 0;
                let far = one_slice
                    .then(|| FarModel::new(&self.gpu, self.far_pass(), (scene, m), &g.placements));
                g.far_counters = far.as_ref().map(|f| f.counters.clone());
                far
            })
            .collect();
        let lods = scene.models.iter().map(ModelLod::new).collect();
        GpuInstances {
            models,
            lods,
            far,
            last: Mutex::new(None),
        }
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
        let all: Vec<&GpuScene> = gpu.models.iter().collect();
        let mut redraws = 0;
        loop {
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            let drawn =
                self.encode_instanced(&mut encoder, &targets, (scene, gpu), camera, settings)?;
            let mut frame = drawn.frame;
            let (image, counters) = self.read_frame(encoder, &targets, &all, &frame)?;
            let far = counters.far.unwrap_or_default();
            if gpu.observe(far, frame.eps) && redraws < REDRAWS {
                redraws += 1;
                continue;
            }
            frame.tested += far.tested as usize;
            let chunks = scene.models.iter().map(|m| m.index.chunks().len()).sum();
            let selected = counters.drawn.unwrap_or(0) as usize;
            let stats = FrameStats::of(&frame, &counters, (chunks, drawn.ranges), selected);
            return Ok((image, stats, drawn.visible + far.visible as usize));
        }
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
        // The GPU places far instances for the camera's own eye, at ε > 0.
        let far_on_gpu = settings.far_on_gpu && settings.lod && settings.lod_eye.is_none();
        let on_gpu: Vec<bool> = (gpu.far.iter())
            .map(|f| far_on_gpu && f.is_some())
            .collect();
        let planned = self.plan_scene((scene, gpu), (camera, settings), size, &on_gpu);
        let mut uniform = FrameUniform::new(&scene.meta, camera, settings, size, planned.eps);
        // The scene's box may span a country: the near plane comes from the instances
        // in view instead (half the distance to the nearest one's sphere).
        let aspect = size.0 as f64 / size.1.max(1) as f64;
        uniform.near = planned.near as f32;
        uniform.proj = camera.projection(aspect, planned.near).to_cols_array_2d();
        let queue = &self.gpu.queue;
        queue.write_buffer(&targets.frame_buffer, 0, bytemuck::bytes_of(&uniform));
        let mut shares = Vec::new();
        let mut draws = Vec::new();
        let cone = instance_cone(&scene.meta, camera, size);
        let origin = DVec3::from(scene.meta.origin);
        for (m, g) in gpu.models.iter().enumerate() {
            let placements = &planned.placements[m];
            if !placements.is_empty() {
                queue.write_buffer(&g.placements, 0, bytemuck::cast_slice(placements));
            }
            let mut model_shares = placed_shares(g, &planned.ranges[m]);
            if let Some(far) = &gpu.far[m] {
                let plan = planned.far.get(m).filter(|p| !p.groups.is_empty());
                if let (Some(plan), Some(share)) = (plan, model_shares.first_mut()) {
                    let draw = far.prepare(
                        (&self.gpu, self.far_pass()),
                        (&scene.models[m], &gpu.lods[m]),
                        plan,
                        (camera.eye, &cone, origin),
                        (planned.eps, placements.len() as u32),
                        &share.slice.cull,
                    );
                    share.far = Some(&far.args);
                    draws.push(draw);
                } else {
                    far.reset(queue);
                }
            }
            shares.extend(model_shares);
        }
        let plan_ms = started.elapsed().as_secs_f64() * 1e3;
        self.encode_passes(
            encoder,
            targets,
            (&shares, &draws),
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
            far_models: gpu.far.iter().flatten().count(),
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

    /// The CPU's plan of a frame of `scene` ([`plan`], on [`Renderer::planning`]'s
    /// thread), from what the frame before it drew; kept for the frame after.
    fn plan_scene(
        &self,
        (scene, gpu): (&InstancedScene, &GpuInstances),
        (camera, settings): (&Camera, &Settings),
        size: (u32, u32),
        on_gpu: &[bool],
    ) -> super::instance_plan::Planned {
        let trim = self.prefix_cut(settings.prefix_cut) == super::settings::PrefixCut::Node;
        let mut last = gpu.last.lock().unwrap_or_else(|e| e.into_inner());
        let was = *last;
        let planned = self.planning(|| {
            plan(
                (scene, &gpu.models, &gpu.lods),
                (camera, settings),
                size,
                (was, on_gpu, trim),
            )
        });
        *last = Some(LastFrame {
            asked: planned.asked,
            drawn: planned.eps,
            fill: planned.fill,
        });
        planned
    }
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
            far: None,
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
