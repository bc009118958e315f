//! The G-buffer that passes 1–2 write and pass 3 reads, for one frame size: the colour
//! sum (colour·w, w), the normal sum (normal·w, z·w), both Rgba16Float, and the
//! reversed-Z depth of pass 1.

use super::pipelines::{DEPTH, GBUFFER};

/// A 2D render target of `format`.
pub(super) fn target(
    device: &wgpu::Device,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    label: &str,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

pub(super) struct GBuffer {
    pub color_sum: wgpu::Texture,
    pub normal_sum: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub normal_view: wgpu::TextureView,
    pub depth_view: wgpu::TextureView,
}

impl GBuffer {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> GBuffer {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let color_sum = target(device, size, GBUFFER, "colour sum", usage);
        let normal_sum = target(device, size, GBUFFER, "normal sum", usage);
        let depth = target(
            device,
            size,
            DEPTH,
            "depth",
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        GBuffer {
            color_view: color_sum.create_view(&Default::default()),
            normal_view: normal_sum.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            color_sum,
            normal_sum,
        }
    }
}
