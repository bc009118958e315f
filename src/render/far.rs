//! Far instances placed by the GPU: a frame of a scene hands each model's far groups
//! (those whose every member lies at least `FAR_RADII` of its sphere's radii from the
//! eye, `instance_plan.rs`) to the GPU whole, instead of planning their members one by
//! one on the CPU.
//!
//! ```text
//! CPU, per frame: far groups (member ranges) + the model's table at ε for the slots
//!                 they may reach (filled once per ε and slot, lod.rs)
//! GPU: place       a thread per member: cone test, slot = ⌊16 log₂(d / r)⌋, placement
//!                  appended after the CPU's, with its slot        (place.wgsl)
//!      settle_far  cull_far's dispatch, the survivors left to it  (cull.wgsl)
//!      cull_far    a workgroup per placed instance tests its slot's ranges
//!      settle_raster  the compute rasterizer's dispatch
//! ```
//!
//! The slot is the one `ModelLod::far` takes on the CPU: the eye's distance to the
//! instance's sphere in model units, rounded down to 1/16 octave, so the ranges hold
//! every node the exact test draws (lod.rs). Positions reach the GPU as an f32 and the
//! f16 rest of the f64 value (about 2⁻³⁵ of it), relative to the scene's origin, so an
//! instance 10⁶ units away is placed to about 3·10⁻⁵ units. A frame cannot know before
//! it ends how many survivors its far instances ask for: those beyond the list's room
//! are counted, not stored, and the next frame coarsens ([`FarCounts::asked`]).

use std::ops::Range;
use std::sync::Mutex;

use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use rayon::prelude::*;

use super::bindings::{Slot, far as far_slots, place as place_slots};
use super::cull::storage;
use super::gpu::Gpu;
use super::placement::snorm16;
use super::shaders::module;
use crate::tree::instances::lod::{ModelLod, SLOTS};
use crate::tree::instances::{InstancedScene, groups::GROUP};
use crate::tree::scene::Scene;

/// Mirrors `struct FarInstance` in place.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct FarInstance {
    anchor: [f32; 3],
    scale: f32,
    anchor_rest: [u32; 2],
    rotation: [u32; 2],
}

/// Mirrors `struct FarEntry` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
struct FarEntry {
    first: u32,
    count: u32,
    nodes: u32,
    pad: u32,
}

/// Mirrors `struct FarRange` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
struct FarRange {
    start: u32,
    end: u32,
}

/// Mirrors `struct FarCounters` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub(super) struct FarCounters {
    pub visible: u32,
    pub nodes: u32,
    pub kept: u32,
    pub budget: u32,
    base: u32,
}

impl FarCounters {
    /// Bytes of what is read back: visible, nodes, kept, budget.
    pub const READ_BYTES: u64 = 16;
}

/// Mirrors `struct FarArgs` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub(super) struct FarArgs {
    cull: [u32; 3],
    raster: [u32; 3],
}

impl FarArgs {
    /// Byte offset of `cull_far`'s dispatch arguments.
    const CULL_AT: u64 = std::mem::offset_of!(FarArgs, cull) as u64;
    /// Byte offset of the compute rasterizer's dispatch arguments.
    pub const RASTER_AT: u64 = std::mem::offset_of!(FarArgs, raster) as u64;
}

/// Mirrors `struct PlaceParams` in place.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct PlaceParams {
    eye: [f32; 3],
    radius: f32,
    eye_rest: [f32; 3],
    error_scale: f32,
    centre: [f32; 3],
    near: f32,
    right: [f32; 3],
    tan_x: f32,
    up: [f32; 3],
    tan_y: f32,
    forward: [f32; 3],
    secant_x: f32,
    secant_y: f32,
    pad: [f32; 3],
}

/// What the GPU measured of a frame's far instances, all models together.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FarCounts {
    /// Instances placed, and the nodes their slots hold (tested).
    pub visible: u64,
    pub tested: u64,
    /// Survivors they asked for, and the room left to them.
    pub asked: u64,
    pub room: u64,
}

impl FarCounts {
    /// Adds one model's counters (as read back: visible, nodes, kept, budget).
    pub(super) fn add(&mut self, c: [u32; 4]) {
        self.visible += c[0] as u64;
        self.tested += c[1] as u64;
        self.asked += c[2] as u64;
        self.room += c[3] as u64;
    }
}

/// `v` as an f32 and its f16 rest.
fn split(v: DVec3) -> ([f32; 3], [f32; 3]) {
    let head = v.as_vec3();
    (head.to_array(), (v - head.as_dvec3()).as_vec3().to_array())
}

/// Three f16 packed two a word (WGSL's `unpack2x16float` inverts it).
fn pack_f16(v: [f32; 3]) -> [u32; 2] {
    let h = v.map(|x| half::f16::from_f32(x).to_bits() as u32);
    [h[0] | (h[1] << 16), h[2]]
}

/// The pipelines of far instances and their bind group layouts.
pub(super) struct FarPass {
    pub place_layout: wgpu::BindGroupLayout,
    pub far_layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    place: wgpu::ComputePipeline,
    settle_far: wgpu::ComputePipeline,
    cull_far: wgpu::ComputePipeline,
    settle_raster: wgpu::ComputePipeline,
}

impl FarPass {
    pub fn new(
        device: &wgpu::Device,
        frame_layout: &wgpu::BindGroupLayout,
        cull_layout: &wgpu::BindGroupLayout,
    ) -> FarPass {
        let entry =
            |slot: Slot, read_only: bool, size: usize| storage(slot, read_only, size as u64);
        let counters = size_of::<FarCounters>();
        let place_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("place"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: place_slots::PARAMS.binding,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<PlaceParams>() as u64),
                    },
                    count: None,
                },
                entry(place_slots::INSTANCES, true, size_of::<FarInstance>()),
                entry(place_slots::GROUPS, true, 8),
                entry(place_slots::ENTRIES, true, size_of::<FarEntry>()),
                entry(
                    place_slots::PLACED,
                    false,
                    size_of::<super::placement::Placement>(),
                ),
                entry(place_slots::COUNTERS, false, counters),
            ],
        });
        let far_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("far"),
            entries: &[
                entry(far_slots::ENTRIES, true, size_of::<FarEntry>()),
                entry(far_slots::RANGES, true, size_of::<FarRange>()),
                entry(far_slots::COUNTERS, false, counters),
            ],
        });
        let pipeline = |name: &str, layouts: &[Option<&wgpu::BindGroupLayout>], entry: &str| {
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: layouts,
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module(device, name),
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let args_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("far args"),
            entries: &[entry(far_slots::ARGS, false, size_of::<FarArgs>())],
        });
        let culling = [Some(frame_layout), Some(cull_layout), Some(&far_layout)];
        let settling = [culling[0], culling[1], culling[2], Some(&args_layout)];
        FarPass {
            place: pipeline("place", &[Some(frame_layout), Some(&place_layout)], "place"),
            settle_far: pipeline("cull", &settling, "settle_far"),
            cull_far: pipeline("cull", &culling, "cull_far"),
            settle_raster: pipeline("cull", &settling, "settle_raster"),
            place_layout,
            far_layout,
            args_layout,
        }
    }

    /// Records each model's far instances: placing, culling, and the dispatch the
    /// compute rasterizer reads (after the CPU's ranges are culled: `settle_far` reads
    /// what they kept).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame_bind: &wgpu::BindGroup,
        draws: &[FarDraw],
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("far instances"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, frame_bind, &[]);
        for draw in draws {
            pass.set_pipeline(&self.place);
            pass.set_bind_group(1, &draw.place, &[]);
            pass.dispatch_workgroups(draw.groups, 1, 1);
            pass.set_bind_group(1, draw.cull, &[]);
            pass.set_bind_group(2, &draw.far, &[]);
            pass.set_bind_group(3, draw.args_bind, &[]);
            pass.set_pipeline(&self.settle_far);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_pipeline(&self.cull_far);
            pass.dispatch_workgroups_indirect(draw.args, FarArgs::CULL_AT);
            pass.set_pipeline(&self.settle_raster);
            pass.dispatch_workgroups(1, 1, 1);
        }
    }
}

/// One model's far instances in a frame, as [`FarPass::encode`] records them.
pub(super) struct FarDraw<'a> {
    place: wgpu::BindGroup,
    far: wgpu::BindGroup,
    args_bind: &'a wgpu::BindGroup,
    cull: &'a wgpu::BindGroup,
    args: &'a wgpu::Buffer,
    groups: u32,
}

/// What a frame's plan hands the GPU of one model: its far groups' members
/// (model-local instance ranges) and the table slots they may reach.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct FarPlan {
    pub groups: Vec<[u32; 2]>,
    pub slots: Option<Range<usize>>,
}

impl FarPlan {
    /// Adds a group of at most [`GROUP`] members (model-local instance indices) whose
    /// rounded distances lie in `slots`.
    pub fn add(&mut self, members: Range<usize>, slots: Range<usize>) {
        self.groups.push([members.start as u32, members.end as u32]);
        self.reach(slots);
    }

    /// Adds member `k` (a far instance of a group planned on the CPU), joined to the
    /// last group where it follows it and that holds fewer than [`GROUP`].
    pub fn add_member(&mut self, k: usize, slots: Range<usize>) {
        let k = k as u32;
        match self.groups.last_mut() {
            Some([start, end]) if *end == k && ((k - *start) as usize) < GROUP => *end += 1,
            _ => self.groups.push([k, k + 1]),
        }
        self.reach(slots);
    }

    /// Appends `other`'s groups.
    pub fn join(&mut self, other: FarPlan) {
        self.groups.extend(other.groups);
        if let Some(slots) = other.slots {
            self.reach(slots);
        }
    }

    fn reach(&mut self, slots: Range<usize>) {
        self.slots = Some(match self.slots.take() {
            Some(s) => s.start.min(slots.start)..s.end.max(slots.end),
            None => slots,
        });
    }
}

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
pub(super) struct FarModel {
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
        let args_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("far dispatches"),
            layout: &pass.args_layout,
            entries: &[bind(far_slots::ARGS, &args)],
        });
        let params = buffer(
            "place params",
            size_of::<PlaceParams>(),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let ranges_buffer = buffer("far ranges", 1 << 16, storage);
        let far = far_bind(device, pass, [&entries, &ranges_buffer, &counters]);
        let mut model = FarModel {
            instances,
            entries,
            counters,
            args,
            args_bind,
            params,
            placements: placements.clone(),
            groups: Mutex::new((groups.clone(), far.clone())),
            table: Mutex::new(FarTable {
                eps: f64::NAN,
                filled: vec![false; SLOTS],
                ranges: Vec::new(),
                ranges_buffer,
                far,
            }),
        };
        let place = model.place_bind(device, pass, &groups);
        model.groups = Mutex::new((groups, place));
        model
    }

    /// The placing's bind group, reading the far groups from `groups`.
    fn place_bind(&self, device: &wgpu::Device, pass: &FarPass, groups: &wgpu::Buffer) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("place"),
            layout: &pass.place_layout,
            entries: &[
                bind(place_slots::PARAMS, &self.params),
                bind(place_slots::INSTANCES, &self.instances),
                bind(place_slots::GROUPS, groups),
                bind(place_slots::ENTRIES, &self.entries),
                bind(place_slots::PLACED, &self.placements),
                bind(place_slots::COUNTERS, &self.counters),
            ],
        })
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
            let place = self.place_bind(&gpu.device, pass, &buffer);
            *held = (buffer, place);
        }
        gpu.queue.write_buffer(&held.0, 0, bytemuck::cast_slice(groups));
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

/// The bind group of `cull_far`'s group 2: entries, ranges, counters.
fn far_bind(device: &wgpu::Device, pass: &FarPass, buffers: [&wgpu::Buffer; 3]) -> wgpu::BindGroup {
    let slots = [far_slots::ENTRIES, far_slots::RANGES, far_slots::COUNTERS];
    let entries: Vec<wgpu::BindGroupEntry> = (slots.into_iter().zip(buffers))
        .map(|(slot, buffer)| bind(slot, buffer))
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("far"),
        layout: &pass.far_layout,
        entries: &entries,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::shaders::assert_wgsl_size;

    #[test]
    fn far_records_have_the_sizes_of_the_wgsl_structs() {
        assert_wgsl_size::<FarInstance>("place", "FarInstance");
        assert_wgsl_size::<PlaceParams>("place", "PlaceParams");
        assert_wgsl_size::<FarEntry>("far", "FarEntry");
        assert_wgsl_size::<FarRange>("far", "FarRange");
        assert_wgsl_size::<FarCounters>("far", "FarCounters");
        assert_wgsl_size::<FarArgs>("far", "FarArgs");
    }

    #[test]
    fn an_anchor_and_its_f16_rest_hold_a_position_a_million_units_away() {
        let v = DVec3::new(1e6 + 0.123_456_7, -2.5e5 - 0.000_31, 7.25);
        let (head, rest) = split(v);
        let [a, b] = pack_f16(rest);
        let unpack = |w: u32| half::f16::from_bits(w as u16).to_f32() as f64;
        let back = DVec3::from(head.map(f64::from))
            + DVec3::new(unpack(a & 0xffff), unpack(a >> 16), unpack(b & 0xffff));
        let error = (back - v).abs().max_element();
        assert!(error < 1e-4, "placed {error} units off");
        // The f32 alone is 0.03 units off here.
        assert!((DVec3::from(head.map(f64::from)) - v).abs().max_element() > 1e-3);
    }
}
