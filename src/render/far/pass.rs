//! The far instances' pipelines: placing (place.wgsl), then, on the slice of the
//! model's list, settling the dispatches, culling and settling the rasterizer's
//! (cull.wgsl).

use super::records::{FarArgs, FarCounters, FarEntry, FarInstance, FarRange, PlaceParams};
use crate::render::bindings::{Slot, far as far_slots, place as place_slots};
use crate::render::cull::storage;
use crate::render::shaders::module;

/// The pipelines of far instances and their bind group layouts.
pub(in crate::render) struct FarPass {
    pub place_layout: wgpu::BindGroupLayout,
    pub far_layout: wgpu::BindGroupLayout,
    pub args_layout: wgpu::BindGroupLayout,
    place: wgpu::ComputePipeline,
    settle_far: wgpu::ComputePipeline,
    cull_far: wgpu::ComputePipeline,
    settle_raster: wgpu::ComputePipeline,
}

impl FarPass {
    pub(in crate::render) fn new(
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
                    size_of::<crate::render::placement::Placement>(),
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
pub(in crate::render) struct FarDraw<'a> {
    pub place: wgpu::BindGroup,
    pub far: wgpu::BindGroup,
    pub args_bind: &'a wgpu::BindGroup,
    pub cull: &'a wgpu::BindGroup,
    pub args: &'a wgpu::Buffer,
    pub groups: u32,
}
