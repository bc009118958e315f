//! The G-buffer that passes 1–2 (and the mesh, and plain points) write and pass 3 reads,
//! for one frame size: the colour sum (colour·w, w), the normal sum (normal·w, z·w),
//! both Rgba16Float, the coverage of four samples per pixel (Rgba8Unorm, blended by
//! max: the union of what the splats cover) and the reversed-Z depth of pass 1 (which
//! pass 3 also reads: where a surface meets the pixel centres); and how
//! a pass attaches to it (its render pass, colour targets and depth state).

/// Format of both attribute sums.
pub(super) const GBUFFER: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Coverage of the four samples of a pixel.
pub(super) const COVERAGE: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Reversed-Z depth (1 at the near plane, 0 at infinity).
pub(super) const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

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

/// What a pass over the G-buffer writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Writes {
    /// The depth alone (pass 1).
    Depth,
    /// The colour targets and the depth (the clear, the points and mesh passes).
    All,
    /// The colour targets; the depth is tested, read-only, so that the pass may also
    /// read it as a texture (pass 2).
    Attributes,
}

pub(super) struct GBuffer {
    pub color_sum: wgpu::Texture,
    pub normal_sum: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub normal_view: wgpu::TextureView,
    pub coverage_view: wgpu::TextureView,
    pub depth_view: wgpu::TextureView,
}

impl GBuffer {
    /// The G-buffer of a `size` frame; with `storage`, its sums and coverage can also
    /// be written by compute shaders (the compute rasterizer's resolve).
    pub fn new(device: &wgpu::Device, size: (u32, u32), storage: bool) -> GBuffer {
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        if storage {
            usage |= wgpu::TextureUsages::STORAGE_BINDING;
        }
        let color_sum = target(device, size, GBUFFER, "colour sum", usage);
        let normal_sum = target(device, size, GBUFFER, "normal sum", usage);
        let coverage = target(device, size, COVERAGE, "coverage", usage);
        let depth = target(
            device,
            size,
            DEPTH,
            "depth",
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        GBuffer {
            color_view: color_sum.create_view(&Default::default()),
            normal_view: normal_sum.create_view(&Default::default()),
            coverage_view: coverage.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            color_sum,
            normal_sum,
        }
    }

    /// A render pass over the G-buffer: the targets that `writes` names, cleared or
    /// loaded, with `timestamps` written at its start.
    pub fn pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        writes: Writes,
        clear: bool,
        timestamps: Option<wgpu::RenderPassTimestampWrites>,
    ) -> wgpu::RenderPass<'e> {
        let color = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: store(if clear {
                    wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
                } else {
                    wgpu::LoadOp::Load
                }),
            })
        };
        let colors = [
            color(&self.color_view),
            color(&self.normal_view),
            color(&self.coverage_view),
        ];
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: if writes == Writes::Depth {
                &[]
            } else {
                &colors
            },
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_view,
                // None: read-only.
                depth_ops: (writes != Writes::Attributes).then(|| {
                    store(if clear {
                        wgpu::LoadOp::Clear(0.0)
                    } else {
                        wgpu::LoadOp::Load
                    })
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

/// `load`, then store.
pub(super) fn store<V>(load: wgpu::LoadOp<V>) -> wgpu::Operations<V> {
    wgpu::Operations {
        load,
        store: wgpu::StoreOp::Store,
    }
}

/// The colour targets of a pass that writes the G-buffer: the sums blended by `blend`,
/// and the coverage by max when they blend (else written as is).
pub(super) fn color_targets(
    blend: Option<wgpu::BlendState>,
) -> [Option<wgpu::ColorTargetState>; 3] {
    let t = wgpu::ColorTargetState {
        format: GBUFFER,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    };
    let coverage = wgpu::ColorTargetState {
        format: COVERAGE,
        blend: blend.map(|_| MAX),
        write_mask: wgpu::ColorWrites::ALL,
    };
    [Some(t.clone()), Some(t), Some(coverage)]
}

/// Blending by the larger of source and destination: the union of coverage samples.
pub(super) const MAX: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Max,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Max,
    },
};

/// Depth tested with `compare`, written if `write`.
pub(super) fn depth_state(
    compare: wgpu::CompareFunction,
    write: bool,
) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

/// Additive blending of colour and alpha: the attribute sums of pass 2.
pub(super) const ADD: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};
