//! One model's far instances on the GPU, and its table of ranges at the frame's ε.

use std::ops::Range;
use std::sync::Mutex;

use glam::DVec3;
use rayon::prelude::*;

use super::pass::{FarDraw, FarPass};
use super::plan::FarPlan;
use super::records::{
    FarArgs, FarCounters, FarEntry, FarInstance, FarRange, PlaceParams, pack_f16, split,
};
use crate::render::bindings::{Slot, far as far_slots, place as place_slots};
use crate::render::gpu::Gpu;
use crate::render::placement::snorm16;
use crate::tree::instances::InstancedScene;
use crate::tree::instances::groups::GROUP;
use crate::tree::instances::lod::{ModelLod, SLOTS};
use crate::tree::scene::Scene;

/// A model's table at one ε on the CPU and the GPU: the ranges of each slot filled so
/// far, and the bind groups that read the GPU's copy.
struct FarTable {
    eps: f64,
    filled: Vec<bool>,
    ranges: Vec<FarRange>,
    ranges_buffer: wgpu::Buffer,
    far: wgpu::BindGroup,
}

/// One model's far instances on the GPU: its instances (f32 anchor and rest, scale,
/// rotation; 32 bytes each), the frame's far groups, its table and counters.
pub(in crate::render) struct FarModel {
    instances: wgpu::Buffer,
    entries: wgpu::Buffer,
    pub counters: wgpu::Buffer,
    /// The indirect dispatches ([`FarArgs`]): the compute rasterizer reads its own.
    pub args: wgpu::Buffer,
    args_bind: wgpu::BindGroup,
    params: wgpu::Buffer,
    placements: wgpu::Buffer,
    /// The frame's far groups (grown as frames hand over more) and the placing's bind
    /// group, which reads them.
    groups: Mutex<(wgpu::Buffer, wgpu::BindGroup)>,
    table: Mutex<FarTable>,
}

/// GPU bytes per instance of [`FarModel`]: its record.
pub const BYTES_PER_INSTANCE: u64 = size_of::<FarInstance>() as u64;

impl FarModel {
    /// The far instances of model `m` of `scene`, placed into `placements`.
    pub fn new(
        gpu: &Gpu,
        pass: &FarPass,
        (scene, m): (&InstancedScene, usize),
        placements: &wgpu::Buffer,
    ) -> FarModel {
        let device = &gpu.device;
        let first = scene.instances.partition_point(|i| (i.model as usize) < m);
        let end = scene.instances.partition_point(|i| (i.model as usize) <= m);
        let origin = DVec3::from(scene.meta.origin);
        let model_origin = DVec3::from(scene.models[m].meta().origin);
        let records: Vec<FarInstance> = scene.instances[first..end]
            .iter()
            .map(|i| {
                let s = i.similarity();
                let (anchor, rest) = split(s.apply(model_origin) - origin);
                let q = s.rotation;
                FarInstance {
                    anchor,
                    scale: i.scale,
                    anchor_rest: pack_f16(rest),
                    rotation: [
                        snorm16(q.x) | (snorm16(q.y) << 16),
                        snorm16(q.z) | (snorm16(q.w) << 16),
                    ],
                }
            })
            .collect();
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let buffer = |label: &str, size: usize, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16) as u64,
                usage,
                mapped_at_creation: false,
            })
        };
        let count = records.len().max(1);
        let instances = buffer("far instances", count * size_of::<FarInstance>(), storage);
        gpu.queue
            .write_buffer(&instances, 0, bytemuck::cast_slice(&records));
        let groups = buffer("far groups", count.div_ceil(GROUP) * 8, storage);
        let entries = buffer("far entries", SLOTS * size_of::<FarEntry>(), storage);
        let counters = buffer(
            "far counters",
            size_of::<FarCounters>(),
            storage | wgpu::BufferUsages::COPY_SRC,
        );
        let args = buffer(
            "far dispatches",
            size_of::<FarArgs>(),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        );
        let args_layout = ("far dispatches", &pass.args_layout);
        let args_bind = bind_group(device, args_layout, [far_slots::ARGS], [&args]);
        let params = buffer(
            "place params",
            size_of::<PlaceParams>(),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let ranges_buffer = buffer("far ranges", 1 << 16, storage);
        let far = far_bind(device, pass, [&entries, &ranges_buffer, &counters]);
        let place = place_bind(
            device,
            pass,
            [
                &params, &instances, &groups, &entries, placements, &counters,
            ],
        );
        FarModel {
            instances,
            entries,
            counters,
            args,
            args_bind,
            params,
            placements: placements.clone(),
            groups: Mutex::new((groups, place)),
            table: Mutex::new(FarTable {
                eps: f64::NAN,
                filled: vec![false; SLOTS],
                ranges: Vec::new(),
                ranges_buffer,
                far,
            }),
        }
    }

    /// Writes the frame's far groups (growing their buffer where they outgrow it) and
    /// returns the placing's bind group.
    fn write_groups(&self, gpu: &Gpu, pass: &FarPass, groups: &[[u32; 2]]) -> wgpu::BindGroup {
        let mut held = self.groups.lock().unwrap_or_else(|e| e.into_inner());
        let bytes = std::mem::size_of_val(groups) as u64;
        if bytes > held.0.size() {
            let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("far groups"),
                size: bytes.next_power_of_two(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let buffers = [
                &self.params,
                &self.instances,
                &buffer,
                &self.entries,
                &self.placements,
                &self.counters,
            ];
            let place = place_bind(&gpu.device, pass, buffers);
            *held = (buffer, place);
        }
        gpu.queue
            .write_buffer(&held.0, 0, bytemuck::cast_slice(groups));
        held.1.clone()
    }

    /// Zeroes its counters for a frame that places none of its instances.
    pub fn reset(&self, queue: &wgpu::Queue) {
        let zero = FarCounters::default();
        queue.write_buffer(&self.counters, 0, bytemuck::bytes_of(&zero));
    }

    /// Bytes of its buffers (the table's ranges as they stand).
    pub fn bytes(&self) -> u64 {
        let table = self.table.lock().unwrap_or_else(|e| e.into_inner());
        let groups = self.groups.lock().unwrap_or_else(|e| e.into_inner());
        [
            &self.instances,
            &groups.0,
            &self.entries,
            &self.counters,
            &self.args,
            &table.ranges_buffer,
        ]
        .iter()
        .map(|b| b.size())
        .sum()
    }

    /// Writes a frame's far instances of this model (`plan`, at `eps`, their
    /// placements from `base` on) and returns what [`FarPass::encode`] records;
    /// fills the table's slots the plan may reach first.
    #[allow(clippy::too_many_arguments)]
    pub fn prepare<'a>(
        &'a self,
        (gpu, pass): (&Gpu, &FarPass),
        (model, lod): (&Scene, &ModelLod),
        plan: &FarPlan,
        (eye, cone, scene_origin): (DVec3, &crate::tree::select::ViewCone, DVec3),
        (eps, base): (f64, u32),
        cull: &'a wgpu::BindGroup,
    ) -> FarDraw<'a> {
        let queue = &gpu.queue;
        let far = match &plan.slots {
            Some(slots) => self.fill(gpu, pass, (model, lod), eps, slots.clone()),
            None => self
                .table
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .far
                .clone(),
        };
        let place = self.write_groups(gpu, pass, &plan.groups);
        let meta = model.meta();
        let (eye, eye_rest) = split(eye - scene_origin);
        let params = PlaceParams {
            eye,
            radius: lod.radius as f32,
            eye_rest,
            error_scale: meta.error_scale,
            centre: lod.centre().as_vec3().to_array(),
            near: cone.near as f32,
            right: cone.right.as_vec3().to_array(),
            tan_x: cone.tan_half_fov[0] as f32,
            up: cone.up.as_vec3().to_array(),
            tan_y: cone.tan_half_fov[1] as f32,
            forward: cone.forward.as_vec3().to_array(),
            secant_x: cone.secants[0] as f32,
            secant_y: cone.secants[1] as f32,
            pad: [0.0; 3],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let counters = FarCounters {
            base,
            ..FarCounters::default()
        };
        queue.write_buffer(&self.counters, 0, bytemuck::bytes_of(&counters));
        FarDraw {
            place,
            far,
            args_bind: &self.args_bind,
            cull,
            args: &self.args,
            groups: plan.groups.len() as u32,
        }
    }

    /// Fills the table's `slots` at `eps` (all of it anew when ε changed), uploads
    /// what changed, and returns the bind group that reads it.
    fn fill(
        &self,
        gpu: &Gpu,
        pass: &FarPass,
        (model, lod): (&Scene, &ModelLod),
        eps: f64,
        slots: Range<usize>,
    ) -> wgpu::BindGroup {
        let queue = &gpu.queue;
        let mut table = self.table.lock().unwrap_or_else(|e| e.into_inner());
        if table.eps != eps {
            table.eps = eps;
            table.filled.fill(false);
            table.ranges.clear();
            let zeros = vec![FarEntry::default(); SLOTS];
            queue.write_buffer(&self.entries, 0, bytemuck::cast_slice(&zeros));
        }
        let missing: Vec<usize> = slots.filter(|&s| !table.filled[s]).collect();
        if missing.is_empty() {
            return table.far.clone();
        }
        let found: Vec<_> = missing
            .par_iter()
            .map(|&s| lod.far_kept(model, s, eps))
            .collect();
        let from = table.ranges.len();
        for (&slot, ranges) in missing.iter().zip(&found) {
            let first = table.ranges.len() as u32;
            let mut end = 0u32;
            for r in ranges.iter() {
                end += r.len() as u32;
                table.ranges.push(FarRange {
                    start: r.start as u32,
                    end,
                });
            }
            let entry = FarEntry {
                first,
                count: ranges.len() as u32,
                nodes: end,
                pad: 0,
            };
            let at = (slot * size_of::<FarEntry>()) as u64;
            queue.write_buffer(&self.entries, at, bytemuck::bytes_of(&entry));
            table.filled[slot] = true;
        }
        let needed = (table.ranges.len() * size_of::<FarRange>()) as u64;
        if needed > table.ranges_buffer.size() {
            table.ranges_buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("far ranges"),
                size: needed.next_power_of_two(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let buffers = [&self.entries, &table.ranges_buffer, &self.counters];
            table.far = far_bind(&gpu.device, pass, buffers);
            queue.write_buffer(&table.ranges_buffer, 0, bytemuck::cast_slice(&table.ranges));
        } else if table.ranges.len() > from {
            let at = (from * size_of::<FarRange>()) as u64;
            let new = bytemuck::cast_slice(&table.ranges[from..]);
            queue.write_buffer(&table.ranges_buffer, at, new);
        }
        table.far.clone()
    }
}

fn bind(slot: Slot, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding: slot.binding,
        resource: buffer.as_entire_binding(),
    }
}

/// A bind group of `layout` binding each of `buffers` at its slot.
fn bind_group<const N: usize>(
    device: &wgpu::Device,
    (label, layout): (&str, &wgpu::BindGroupLayout),
    slots: [Slot; N],
    buffers: [&wgpu::Buffer; N],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = (slots.into_iter().zip(buffers))
        .map(|(slot, buffer)| bind(slot, buffer))
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// The placing's bind group: params, instances, far groups, entries, placements,
/// counters.
fn place_bind(
    device: &wgpu::Device,
    pass: &FarPass,
    buffers: [&wgpu::Buffer; 6],
) -> wgpu::BindGroup {
    let slots = [
        place_slots::PARAMS,
        place_slots::INSTANCES,
        place_slots::GROUPS,
        place_slots::ENTRIES,
        place_slots::PLACED,
        place_slots::COUNTERS,
    ];
    bind_group(device, ("place", &pass.place_layout), slots, buffers)
}

/// The bind group of `cull_far`'s group 2: entries, ranges, counters.
fn far_bind(device: &wgpu::Device, pass: &FarPass, buffers: [&wgpu::Buffer; 3]) -> wgpu::BindGroup {
    let slots = [far_slots::ENTRIES, far_slots::RANGES, far_slots::COUNTERS];
    bind_group(device, ("far", &pass.far_layout), slots, buffers)
}
