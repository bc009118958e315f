//! Pass 3, shading: a full-screen triangle reads the G-buffer's sums, normalizes them
//! (colour = Σcw/Σw, normal = normalize(Σnw)), and shades each pixel (Blinn-Phong with
//! a movable light, two-sided); background where nothing contributed. Written linear
//! into the sRGB output. WGSL: `shaders/shade.wgsl`.

use super::bindings::{Slot, shade};
use super::fullscreen::{fragment_texture, fullscreen_pipeline};
use super::gbuffer::{GBuffer, store};
use super::shaders::module;
use super::targets::{COVERED, FrameTargets, OUTPUT, stamp};

pub(super) struct ShadingPass {
    /// Bind group 1: the colour and normal sums, the coverage and the depth, as textures.
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

impl ShadingPass {
    pub fn new(device: &wgpu::Device, frame_layout: &wgpu::BindGroupLayout) -> ShadingPass {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer"),
            entries: &[
                fragment_texture(shade::COLOR_SUM.binding),
                fragment_texture(shade::NORMAL_SUM.binding),
                fragment_texture(shade::COVERAGE.binding),
                // The depth, as an unfilterable float texture (see shade.wgsl).
                fragment_texture(shade::DEPTH.binding),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shade"),
            bind_group_layouts: &[Some(frame_layout), Some(&layout)],
            immediate_size: 0,
        });
        let shader = module(device, "shade");
        let targets = [OUTPUT, COVERED];
        let pipeline = fullscreen_pipeline(device, &pipeline_layout, &shader, "fs_shade", &targets);
        ShadingPass { layout, pipeline }
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
    /// its output and its covered mask; writes the frame's end timestamp.
    pub fn encode(
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
