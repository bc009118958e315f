//! The mesh reference pass: the model's triangles with the leaf surfels' normals,
//! interpolated, written into the same G-buffer as the splats (weight 1) and shaded by
//! the same pass 3: the ground truth of image errors. WGSL: `shaders/mesh.wgsl`.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::gbuffer::{GBuffer, Writes, color_targets, depth_state};
use super::gpu_scene::MeshBuffers;
use super::shaders::module;
use crate::tree::scene::MeshData;

/// One vertex of the mesh (`struct MeshVertex` in mesh.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct MeshVertex {
    /// Relative to the model's origin.
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// RGBA8, read as unorm.
    pub color: [u8; 4],
}

impl MeshVertex {
    const ATTRIBUTES: [wgpu::VertexAttribute; 3] =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Unorm8x4];

    fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

pub(super) struct MeshPass {
    pipeline: wgpu::RenderPipeline,
}

impl MeshPass {
    pub fn new(device: &wgpu::Device, frame_layout: &wgpu::BindGroupLayout) -> MeshPass {
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[Some(frame_layout)],
            immediate_size: 0,
        });
        let shader = module(device, "mesh");
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mesh"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_mesh"),
                compilation_options: Default::default(),
                buffers: &[Some(MeshVertex::layout())],
            },
            primitive: Default::default(),
            depth_stencil: depth_state(wgpu::CompareFunction::Greater, true),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_mesh"),
                compilation_options: Default::default(),
                targets: &color_targets(None),
            }),
            multiview_mask: None,
            cache: None,
        });
        MeshPass { pipeline }
    }

    /// The mesh's vertex and index buffers.
    pub fn upload(device: &wgpu::Device, m: &MeshData) -> MeshBuffers {
        let vertices: Vec<MeshVertex> = (0..m.positions.len())
            .map(|i| MeshVertex {
                position: m.positions[i].to_array(),
                normal: m.normals[i].to_array(),
                color: m.colors[i],
            })
            .collect();
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        MeshBuffers {
            vertices: buffer(
                "mesh vertices",
                bytemuck::cast_slice(&vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buffer(
                "mesh indices",
                bytemuck::cast_slice(&m.triangles),
                wgpu::BufferUsages::INDEX,
            ),
            index_count: (m.triangles.len() * 3) as u32,
        }
    }

    /// Draws the triangles into the G-buffer (cleared before).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer: &GBuffer,
        frame_bind: &wgpu::BindGroup,
        mesh: &MeshBuffers,
        timestamps: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let mut pass = gbuffer.pass(encoder, "mesh", Writes::All, false, timestamps);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, frame_bind, &[]);
        pass.set_vertex_buffer(0, mesh.vertices.slice(..));
        pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..mesh.index_count, 0, 0..1);
    }
}
