//! What one frame size needs on the GPU, made once and kept between frames (the viewer
//! keeps one per window size): the G-buffer, the shaded output, the frame uniform and
//! the bind groups that point at them, and the timestamp queries.

use std::sync::OnceLock;

use super::Gpu;
use super::accumulation::Accumulation;
use super::frame::FrameUniform;
use super::gbuffer::{GBuffer, target};

/// The shaded output: written linear, stored sRGB-encoded.
pub const OUTPUT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Whether a pixel of the output shows a surface (1) or the background (0): an integer
/// format that compute shaders can also write (R8Unorm is no storage format).
pub(super) const COVERED: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The same bytes seen without sRGB decoding (overlays, presentation).
pub const OUTPUT_GAMMA: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The frame's timestamps, indices into its query set, each written once per frame.
pub(super) mod stamp {
    /// The start of the frame's first pass: the cull pass, else the G-buffer's clear.
    pub const START: u32 = 0;
    /// The end of pass 1 (in the points and mesh modes of the raster pipeline, which
    /// have none, of the clear).
    pub const VISIBILITY_END: u32 = 1;
    /// The end of pass 2 (or of the points or mesh pass).
    pub const ATTRIBUTES_END: u32 = 2;
    /// The end of shading.
    pub const END: u32 = 3;
    pub const COUNT: u32 = 4;
}

/// Bytes of the frame's timestamps (u64 each).
pub(super) const STAMP_BYTES: u64 = 8 * stamp::COUNT as u64;

/// Render targets and per-frame buffers for one `size`.
pub struct FrameTargets {
    pub size: (u32, u32),
    pub(super) gbuffer: GBuffer,
    /// The shaded frame: RGBA8, sRGB-encoded. Can also be viewed as plain `Rgba8Unorm`
    /// ([`FrameTargets::overlay_view`]) to draw an overlay in gamma space or to copy the
    /// bytes as they are. Where pass 3 can run in compute ([`Gpu::compute_shading`]) it
    /// is made `Rgba8Unorm`, which compute shaders can write, and viewed as [`OUTPUT`]
    /// to render into.
    pub output: wgpu::Texture,
    /// The output as [`OUTPUT`], for the passes that render into it.
    pub(super) output_view: wgpu::TextureView,
    /// Pass 3's mask of the pixels that show a surface ([`COVERED`]), read back with
    /// the output.
    pub(super) covered: wgpu::Texture,
    pub(super) covered_view: wgpu::TextureView,
    pub(super) frame_buffer: wgpu::Buffer,
    pub(super) frame_bind: wgpu::BindGroup,
    pub(super) gbuffer_bind: wgpu::BindGroup,
    /// Pass 1's depth for pass 2 (bind group 2 of its pipelines).
    pub(super) depth_bind: wgpu::BindGroup,
    /// The frame's timestamps ([`stamp`]) and their resolve buffer.
    pub(super) queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    /// What frames drawn in compute bind, made for the first of them.
    pub(super) compute: OnceLock<ComputeBinds>,
}

/// The compute rasterizer's buffers, pass 3's bind group of what their resolve writes,
/// and, where pass 3 runs in compute, that of its storage targets (the output and the
/// covered mask).
pub(super) struct ComputeBinds {
    pub accumulation: Accumulation,
    pub gbuffer: wgpu::BindGroup,
    pub outputs: Option<wgpu::BindGroup>,
}

impl FrameTargets {
    /// Targets of `size` around `gbuffer` (of the same size) and its bind groups for
    /// shading and for pass 2 (its depth); the frame uniform bound as `frame_layout`
    /// says; with timestamp queries, the output's gamma view and storage targets for
    /// pass 3 where `gpu` has them.
    pub(super) fn new(
        gpu: &Gpu,
        size: (u32, u32),
        frame_layout: &wgpu::BindGroupLayout,
        (gbuffer, [gbuffer_bind, depth_bind]): (GBuffer, [wgpu::BindGroup; 2]),
    ) -> FrameTargets {
        let device = &gpu.device;
        let (storage, format, view_formats): (_, _, &[_]) = match gpu {
            g if g.compute_shading => (
                wgpu::TextureUsages::STORAGE_BINDING,
                OUTPUT_GAMMA,
                &[OUTPUT],
            ),
            g if g.view_formats => (wgpu::TextureUsages::empty(), OUTPUT, &[OUTPUT_GAMMA]),
            _ => (wgpu::TextureUsages::empty(), OUTPUT, &[]),
        };
        let output = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("output"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING
                | storage,
            view_formats,
        });
        let read_back =
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | storage;
        let covered = target(device, size, COVERED, "covered", read_back);
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: super::bindings::FRAME.binding,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        let queries = gpu.timestamps.then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("passes"),
                ty: wgpu::QueryType::Timestamp,
                count: stamp::COUNT,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: STAMP_BYTES,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        FrameTargets {
            size,
            output_view: view_as(&output, OUTPUT),
            output,
            covered_view: covered.create_view(&Default::default()),
            covered,
            gbuffer,
            frame_buffer,
            frame_bind,
            gbuffer_bind,
            depth_bind,
            queries,
            compute: OnceLock::new(),
        }
    }

    /// A pass's timestamp writes: [`stamp`] indices at its beginning and its end (none
    /// where neither is given).
    pub(super) fn timestamps(
        &self,
        begin: Option<u32>,
        end: Option<u32>,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let any = begin.is_some() || end.is_some();
        self.queries
            .as_ref()
            .filter(|_| any)
            .map(|(q, _)| wgpu::RenderPassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: begin,
                end_of_pass_write_index: end,
            })
    }

    /// A compute pass's timestamp writes, as [`FrameTargets::timestamps`].
    pub(super) fn compute_timestamps(
        &self,
        begin: Option<u32>,
        end: Option<u32>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let any = begin.is_some() || end.is_some();
        self.queries
            .as_ref()
            .filter(|_| any)
            .map(|(q, _)| wgpu::ComputePassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: begin,
                end_of_pass_write_index: end,
            })
    }

    /// The output seen as `format`: [`OUTPUT_GAMMA`] (its bytes as they are, already
    /// sRGB-encoded, so that an overlay blends in gamma space as egui expects, and a copy
    /// moves the bytes unchanged) where the adapter can reinterpret views, else
    /// [`OUTPUT`] itself ([`super::Gpu::overlay_format`]).
    pub fn overlay_view(&self, format: wgpu::TextureFormat) -> wgpu::TextureView {
        view_as(&self.output, format)
    }
}

/// `texture` seen as `format`, with the texture's usages that the format allows (an
/// sRGB view is no storage binding).
fn view_as(texture: &wgpu::Texture, format: wgpu::TextureFormat) -> wgpu::TextureView {
    let mut usage = texture.usage();
    if format.is_srgb() {
        usage.remove(wgpu::TextureUsages::STORAGE_BINDING);
    }
    texture.create_view(&wgpu::TextureViewDescriptor {
        format: Some(format),
        usage: Some(usage),
        ..Default::default()
    })
}

/// Checks that a `width`×`height` frame fits the adapter's limits (texture side, and a
/// read-back buffer of the widest G-buffer format).
pub(super) fn check_size(limits: &wgpu::Limits, (width, height): (u32, u32)) -> anyhow::Result<()> {
    if width.max(height) > limits.max_texture_dimension_2d
        || (width as u64).div_ceil(32) * 256 * height as u64 > limits.max_buffer_size
    {
        anyhow::bail!(
            "{width}×{height} is larger than this adapter renders (at most {} pixels a side, {} MB a read-back buffer)",
            limits.max_texture_dimension_2d,
            limits.max_buffer_size >> 20
        );
    }
    Ok(())
}
