//! The splat passes (DESIGN.md §7): pass 1, visibility (depth only, pushed back), and
//! pass 2, attributes (additive (colour·w, w) and (normal·w, z·w) into the G-buffer),
//! or plain points (no blending) instead of both. One instanced quad of 4 vertices per
//! node: every node of the prefix, culled in the vertex stage ("direct"), or the
//! survivors that `cull.rs` compacted, drawn indirectly ("compacted"). WGSL:
//! `shaders/splat.wgsl`. The splat passes read each drawn node's record (32 bytes) and
//! shape (16 bytes, [`SplatShape`]); the cull pass reads only the record.

use super::gbuffer::{ADD, color_targets, depth_state};
use super::gpu_scene::Share;
use super::shaders::module;
use crate::tree::NodeRecord;
use crate::tree::record::{PointAttributes, SplatShape};

/// The three splat pipelines of one culling strategy.
pub(super) struct SplatPipelines {
    pub visibility: wgpu::RenderPipeline,
    pub attributes: wgpu::RenderPipeline,
    pub points: wgpu::RenderPipeline,
}

/// Layouts of bind group 1 and the pipelines of both culling strategies.
pub(super) struct SplatPasses {
    /// The slice's nodes (binding 0) and shapes (2), for vertex culling.
    pub nodes_layout: wgpu::BindGroupLayout,
    /// The slice's nodes (0), survivors (1) and shapes (2), for compute culling.
    pub compacted_layout: wgpu::BindGroupLayout,
    pub direct: SplatPipelines,
    pub compacted: SplatPipelines,
}

/// A read-only storage buffer of bind group 1 for the vertex stage.
fn vertex_storage(binding: u32, min_size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(min_size),
        },
        count: None,
    }
}

/// The pipelines of vertex entry point `vs` (bind group 1 laid out by `nodes`).
fn pipelines(
    device: &wgpu::Device,
    shader: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    vs: &str,
) -> SplatPipelines {
    let pipeline = |fs: &str, targets: &[Option<wgpu::ColorTargetState>], depth| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fs),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some(vs),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                ..Default::default()
            },
            depth_stencil: depth,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: shader,
                entry_point: Some(fs),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    use wgpu::CompareFunction::{Greater, GreaterEqual};
    SplatPipelines {
        visibility: pipeline("fs_visibility", &[], depth_state(Greater, true)),
        attributes: pipeline(
            "fs_attributes",
            &color_targets(Some(ADD)),
            depth_state(GreaterEqual, false),
        ),
        points: pipeline(
            "fs_points",
            &color_targets(None),
            depth_state(Greater, true),
        ),
    }
}

impl SplatPasses {
    pub fn new(device: &wgpu::Device, frame_layout: &wgpu::BindGroupLayout) -> SplatPasses {
        let node = std::mem::size_of::<NodeRecord>() as u64;
        let shape = std::mem::size_of::<SplatShape>() as u64;
        let attribute = std::mem::size_of::<PointAttributes>() as u64;
        let bind_layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let nodes_layout = bind_layout(
            "nodes",
            &[
                vertex_storage(0, node),
                vertex_storage(2, shape),
                vertex_storage(3, attribute),
            ],
        );
        let compacted_layout = bind_layout(
            "compacted nodes",
            &[
                vertex_storage(0, node),
                vertex_storage(1, 4),
                vertex_storage(2, shape),
                vertex_storage(3, attribute),
            ],
        );
        let pipeline_layout = |second: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(frame_layout), Some(second)],
                immediate_size: 0,
            })
        };
        let shader = module(device, "splat");
        SplatPasses {
            direct: pipelines(device, &shader, &pipeline_layout(&nodes_layout), "vs_splat"),
            compacted: pipelines(
                device,
                &shader,
                &pipeline_layout(&compacted_layout),
                "vs_splat_compacted",
            ),
            nodes_layout,
            compacted_layout,
        }
    }

    /// Draws each slice's share of the frame's ranges with `pipeline`: the compacted
    /// survivors (indirect) after compute culling, else every node of each range (its
    /// instances are its nodes' slice indices).
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass,
        pipeline: &wgpu::RenderPipeline,
        frame_bind: &wgpu::BindGroup,
        shares: &[Share],
        compacted: bool,
    ) {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, frame_bind, &[]);
        for share in shares.iter().filter(|s| s.count > 0) {
            if compacted {
                pass.set_bind_group(1, &share.slice.compacted, &[]);
                pass.draw_indirect(&share.slice.compaction, 0);
            } else {
                pass.set_bind_group(1, &share.slice.direct, &[]);
                for r in &share.ranges {
                    pass.draw(0..4, r.clone());
                }
            }
        }
    }

    /// The pipelines of a culling strategy.
    pub fn of(&self, compacted: bool) -> &SplatPipelines {
        if compacted {
            &self.compacted
        } else {
            &self.direct
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_shape_record_matches_its_wgsl_struct() {
        super::super::shaders::assert_wgsl_size::<super::SplatShape>("splat", "SplatShape");
    }
}
