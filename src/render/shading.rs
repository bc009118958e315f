//! Pass 3, shading: each pixel reads the G-buffer's sums, normalizes them (colour =
//! Σcw/Σw, normal = normalize(Σnw)), and is shaded (Blinn-Phong with a movable light,
//! two-sided); background where nothing contributed. WGSL: `shaders/shade.wgsl`.
//!
//! Two ways, one WGSL function per pixel: a full-screen triangle through the raster
//! pipeline, written linear into the sRGB output; or, after the compute rasterizer,
//! one compute thread per pixel, encoding sRGB itself and storing through the output's
//! `Rgba8Unorm` view. A GPU such as the H100 runs fragment shaders on only the few of
//! its processors that have a raster engine, compute shaders on all of them.

use std::sync::OnceLock;

use super::bindings::{Slot, shade};
use super::fullscreen::{fragment_texture, fullscreen_pipeline};
use super::gbuffer::{GBuffer, store};
use super::raster::storage_texture;
use super::shaders::{PIXEL_TILE, module};
use super::targets::{COVERED, FrameTargets, OUTPUT, OUTPUT_GAMMA, stamp};

pub(super) struct ShadingPass {
    device: wgpu::Device,
    /// Bind group 1: the colour and normal sums, the coverage and the depth, as textures.
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    /// Bind group 2 of the compute version: the output and the covered mask, as
    /// storage textures.
    outputs_layout: wgpu::BindGroupLayout,
    compute_layout: wgpu::PipelineLayout,
    /// The compute version, made for the first frame that needs it.
    compute: OnceLock<wgpu::ComputePipeline>,
}

impl ShadingPass {
    pub fn new(device: &wgpu::Device, frame_layout: &wgpu::BindGroupLayout) -> ShadingPass {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer"),
            entries: &[
                shaded_texture(shade::COLOR_SUM),
                shaded_texture(shade::NORMAL_SUM),
                shaded_texture(shade::COVERAGE),
                // The depth, as an unfilterable float texture (see shade.wgsl).
                shaded_texture(shade::DEPTH),
            ],
        });
        let outputs_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shaded"),
            entries: &[
                storage_texture(shade::SHADED_OUT, OUTPUT_GAMMA),
                storage_texture(shade::COVERED_OUT, COVERED),
            ],
        });
        let compute_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shade compute"),
            bind_group_layouts: &[Some(frame_layout), Some(&layout), Some(&outputs_layout)],
            immediate_size: 0,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shade"),
            bind_group_layouts: &[Some(frame_layout), Some(&layout)],
            immediate_size: 0,
        });
        let shader = module(device, "shade");
        let targets = [OUTPUT, COVERED];
        let pipeline = fullscreen_pipeline(device, &pipeline_layout, &shader, "fs_shade", &targets);
        ShadingPass {
            device: device.clone(),
            layout,
            pipeline,
            outputs_layout,
            compute_layout,
            compute: OnceLock::new(),
        }
    }

    /// The bind group of `targets`' output and covered mask as the compute version
    /// writes them; none where they are no storage textures (`Gpu::compute_shading`).
    pub fn bind_outputs(&self, targets: &FrameTargets) -> Option<wgpu::BindGroup> {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        if !targets.output.usage().contains(storage) || !targets.covered.usage().contains(storage) {
            return None;
        }
        let output = targets.output.create_view(&wgpu::TextureViewDescriptor {
            format: Some(OUTPUT_GAMMA),
            ..Default::default()
        });
        let entry = |slot: Slot, view| wgpu::BindGroupEntry {
            binding: slot.binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        Some(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shaded"),
            layout: &self.outputs_layout,
            entries: &[
                entry(shade::SHADED_OUT, &output),
                entry(shade::COVERED_OUT, &targets.covered_view),
            ],
        }))
    }

    /// The bind group of `gbuffer`'s sums for this pass, with pass 1's depth as
    /// `depth` (the G-buffer's own, or the compute rasterizer's float copy).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        gbuffer: &GBuffer,
        depth: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let view = |slot: Slot, view| wgpu::BindGroupEntry {
            binding: slot.binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer"),
            layout: &self.layout,
            entries: &[
                view(shade::COLOR_SUM, &gbuffer.color_view),
                view(shade::NORMAL_SUM, &gbuffer.normal_view),
                view(shade::COVERAGE, &gbuffer.coverage_view),
                view(shade::DEPTH, depth),
            ],
        })
    }

    /// Shades `targets`' G-buffer (bound as `gbuffer`, see [`ShadingPass::bind`]) into
    /// its output and its covered mask, in compute where `outputs` binds them as
    /// storage ([`ShadingPass::bind_outputs`]); writes the frame's end timestamp.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        gbuffer: &wgpu::BindGroup,
        outputs: Option<&wgpu::BindGroup>,
    ) {
        match outputs {
            Some(outputs) => self.encode_compute(encoder, targets, gbuffer, outputs),
            None => self.encode_fragment(encoder, targets, gbuffer),
        }
    }

    fn encode_compute(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        gbuffer: &wgpu::BindGroup,
        outputs: &wgpu::BindGroup,
    ) {
        let pipeline = self.compute.get_or_init(|| {
            let desc = wgpu::ComputePipelineDescriptor {
                label: Some("cs_shade"),
                layout: Some(&self.compute_layout),
                module: &module(&self.device, "shade"),
                entry_point: Some("cs_shade"),
                compilation_options: Default::default(),
                cache: None,
            };
            self.device.create_compute_pipeline(&desc)
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shade"),
            timestamp_writes: targets.compute_timestamps(None, Some(stamp::END)),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &targets.frame_bind, &[]);
        pass.set_bind_group(1, gbuffer, &[]);
        pass.set_bind_group(2, outputs, &[]);
        let (w, h) = targets.size;
        pass.dispatch_workgroups(w.div_ceil(PIXEL_TILE), h.div_ceil(PIXEL_TILE), 1);
    }

    fn encode_fragment(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        gbuffer: &wgpu::BindGroup,
    ) {
        let attach = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: store(wgpu::LoadOp::Clear(wgpu::Color::BLACK)),
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shade"),
            color_attachments: &[attach(&targets.output_view), attach(&targets.covered_view)],
            depth_stencil_attachment: None,
            timestamp_writes: targets.timestamps(None, Some(stamp::END)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &targets.frame_bind, &[]);
        pass.set_bind_group(1, gbuffer, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// Binding `slot` of group 1: a G-buffer texture that both versions read texel by texel.
fn shaded_texture(slot: Slot) -> wgpu::BindGroupLayoutEntry {
    let mut entry = fragment_texture(slot.binding);
    entry.visibility |= wgpu::ShaderStages::COMPUTE;
    entry
}
