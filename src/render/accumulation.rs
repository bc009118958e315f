//! The compute rasterizer's per-pixel buffers for one frame size (`shaders/accumulate.wgsl`
//! says what each holds): pass 1's depth, the fixed-point sums and their carries, the
//! coverage bits and the points' winners, with the float depth texture the resolve
//! writes for pass 3. [`super::raster`] draws into them; a frame's targets make them
//! for the first frame drawn in compute.

use super::bindings::{Slot, accumulate, resolve as out};
use super::gbuffer::{GBuffer, target};
use super::shaders::SUM_CHANNELS;

/// Pass 1's depth as the resolve writes it for pass 3 (reversed Z; 0: none).
pub(super) const FLOAT_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// Bytes of the fixed-point sums' low (or high) words for a `size` frame.
pub(super) fn sums_bytes((width, height): (u32, u32)) -> u64 {
    SUM_CHANNELS as u64 * width as u64 * height as u64 * 4
}

/// The compute rasterizer's per-pixel buffers for one frame size, and the bind groups
/// of the passes that read and write them; made by a frame's targets when a frame is
/// first drawn in compute.
pub(super) struct Accumulation {
    /// Group 2 of the raster passes and the resolve.
    pub bind: wgpu::BindGroup,
    /// Group 1 of the resolve: the G-buffer's sums and coverage, and `depth`.
    pub resolve_bind: wgpu::BindGroup,
    /// Pass 1's depth as the resolve writes it, for pass 3.
    pub depth_view: wgpu::TextureView,
}

impl Accumulation {
    /// The buffers of a `size` frame, bound as `layouts` say (group 2 of the raster
    /// passes and the resolve, group 1 of the resolve: `gbuffer`'s sums and coverage,
    /// and pass 1's depth as a float texture made here).
    pub fn new(
        device: &wgpu::Device,
        layouts: [&wgpu::BindGroupLayout; 2],
        gbuffer: &GBuffer,
        size: (u32, u32),
    ) -> Accumulation {
        let [accumulation_layout, resolve_layout] = layouts;
        let pixels = size.0 as u64 * size.1 as u64 * 4;
        let buffer = |label, bytes| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let buffers = [
            buffer("visible", pixels),
            buffer("sums", sums_bytes(size)),
            buffer("carries", sums_bytes(size)),
            buffer("covered", pixels),
            buffer("nearest point", pixels),
        ];
        let entries: Vec<_> = accumulate::ALL
            .iter()
            .zip(&buffers)
            .map(|(slot, b)| wgpu::BindGroupEntry {
                binding: slot.binding,
                resource: b.as_entire_binding(),
            })
            .collect();
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("accumulation"),
            layout: accumulation_layout,
            entries: &entries,
        });
        let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING;
        let depth = target(device, size, FLOAT_DEPTH, "visible depth", usage);
        let depth_view = depth.create_view(&Default::default());
        let view = |slot: Slot, view| wgpu::BindGroupEntry {
            binding: slot.binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        let resolve_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resolved gbuffer"),
            layout: resolve_layout,
            entries: &[
                view(out::COLOR_OUT, &gbuffer.color_view),
                view(out::NORMAL_OUT, &gbuffer.normal_view),
                view(out::COVERAGE_OUT, &gbuffer.coverage_view),
                view(out::DEPTH_OUT, &depth_view),
            ],
        });
        Accumulation {
            bind,
            resolve_bind,
            depth_view,
        }
    }
}
