//! The GPU programs of the renderer: bind group layouts, shader modules (composed from
//! `shaders/` by [`super::shaders`]) and pipelines, made once per device.

use super::shaders::module;

pub(super) const GBUFFER: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub(super) const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The shaded output: written linear, stored sRGB-encoded.
pub(super) const OUTPUT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// The same bytes seen without sRGB decoding (overlays, presentation).
pub const OUTPUT_GAMMA: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// A full-screen pass: `vs_fullscreen` (shaders/fullscreen.wgsl, which `module` must
/// import) and the fragment stage `fragment` writing one target of `format`.
pub fn fullscreen_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fragment: &str,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fragment),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn depth_state(compare: wgpu::CompareFunction, write: bool) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

fn gbuffer_targets(blend: Option<wgpu::BlendState>) -> [Option<wgpu::ColorTargetState>; 2] {
    let t = wgpu::ColorTargetState {
        format: GBUFFER,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    };
    [Some(t.clone()), Some(t)]
}

const ADD: wgpu::BlendState = wgpu::BlendState {
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

/// The three splat pipelines of one culling strategy.
pub(super) struct SplatPipelines {
    pub visibility: wgpu::RenderPipeline,
    pub attributes: wgpu::RenderPipeline,
    pub points: wgpu::RenderPipeline,
}

/// Every layout and pipeline the renderer uses.
pub(super) struct Pipelines {
    pub frame_layout: wgpu::BindGroupLayout,
    pub nodes_layout: wgpu::BindGroupLayout,
    pub compacted_layout: wgpu::BindGroupLayout,
    pub cull_layout: wgpu::BindGroupLayout,
    pub gbuffer_layout: wgpu::BindGroupLayout,
    pub direct: SplatPipelines,
    pub compacted: SplatPipelines,
    pub cull: wgpu::ComputePipeline,
    pub mesh: wgpu::RenderPipeline,
    pub shade: wgpu::RenderPipeline,
}

impl Pipelines {
    pub fn new(device: &wgpu::Device) -> Pipelines {
        let entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        };
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[entry(
                0,
                wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            )],
        });
        let nodes_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("nodes"),
            entries: &[entry(
                0,
                wgpu::ShaderStages::VERTEX,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            )],
        });
        let storage = |read_only| wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let compacted_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("compacted nodes"),
            entries: &[
                entry(0, wgpu::ShaderStages::VERTEX, storage(true)),
                entry(1, wgpu::ShaderStages::VERTEX, storage(true)),
            ],
        });
        let cull_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull"),
            entries: &[
                entry(0, wgpu::ShaderStages::COMPUTE, storage(true)),
                entry(1, wgpu::ShaderStages::COMPUTE, storage(false)),
                entry(2, wgpu::ShaderStages::COMPUTE, storage(false)),
            ],
        });
        let texture = wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        let gbuffer_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer"),
            entries: &[
                entry(0, wgpu::ShaderStages::FRAGMENT, texture),
                entry(1, wgpu::ShaderStages::FRAGMENT, texture),
            ],
        });
        let layout = |second: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&frame_layout), Some(second)],
                immediate_size: 0,
            })
        };
        let splat_layout = layout(&nodes_layout);
        let compacted_splat_layout = layout(&compacted_layout);
        let cull_pipeline_layout = layout(&cull_layout);
        let shade_layout = layout(&gbuffer_layout);
        let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });
        let splat = module(device, "splat");
        let mesh_module = module(device, "mesh");
        let shade_module = module(device, "shade");
        let strip = wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleStrip,
            ..Default::default()
        };
        let splat_pipeline =
            |vs: &str, fs: &str, targets: &[Option<wgpu::ColorTargetState>], depth| {
                let layout = if vs == "vs_splat" {
                    &splat_layout
                } else {
                    &compacted_splat_layout
                };
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(fs),
                    layout: Some(layout),
                    vertex: wgpu::VertexState {
                        module: &splat,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: strip,
                    depth_stencil: depth,
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &splat,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
        let pipelines = |vs: &str| SplatPipelines {
            visibility: splat_pipeline(
                vs,
                "fs_visibility",
                &[],
                depth_state(wgpu::CompareFunction::Greater, true),
            ),
            attributes: splat_pipeline(
                vs,
                "fs_attributes",
                &gbuffer_targets(Some(ADD)),
                depth_state(wgpu::CompareFunction::GreaterEqual, false),
            ),
            points: splat_pipeline(
                vs,
                "fs_points",
                &gbuffer_targets(None),
                depth_state(wgpu::CompareFunction::Greater, true),
            ),
        };
        let direct = pipelines("vs_splat");
        let compacted = pipelines("vs_splat_compacted");
        let cull_module = module(device, "cull");
        let cull = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("cull"),
            layout: Some(&cull_pipeline_layout),
            module: &cull_module,
            entry_point: Some("cull"),
            compilation_options: Default::default(),
            cache: None,
        });
        let mesh_attributes = [
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 0,
            },
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 12,
                shader_location: 1,
            },
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Unorm8x4,
                offset: 24,
                shader_location: 2,
            },
        ];
        let mesh = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mesh"),
            layout: Some(&mesh_layout),
            vertex: wgpu::VertexState {
                module: &mesh_module,
                entry_point: Some("vs_mesh"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 28,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &mesh_attributes,
                })],
            },
            primitive: Default::default(),
            depth_stencil: depth_state(wgpu::CompareFunction::Greater, true),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &mesh_module,
                entry_point: Some("fs_mesh"),
                compilation_options: Default::default(),
                targets: &gbuffer_targets(None),
            }),
            multiview_mask: None,
            cache: None,
        });
        let shade = fullscreen_pipeline(device, &shade_layout, &shade_module, "fs_shade", OUTPUT);
        Pipelines {
            frame_layout,
            nodes_layout,
            compacted_layout,
            cull_layout,
            gbuffer_layout,
            direct,
            compacted,
            cull,
            mesh,
            shade,
        }
    }
}
