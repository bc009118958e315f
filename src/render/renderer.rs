//! The three-pass deferred EWA splatting renderer (DESIGN.md §6–7; Botsch, Hornung,
//! Zwicker, Kobbelt 2005), and the mesh reference pass into the same G-buffer.
//!
//! ```text
//! CPU: prefix (binary search) ─► per slice of the list: instanced quads, 4 vertices each
//! pass 1 visibility:  depth only, pushed back by a fraction of the radius
//! pass 2 attributes:  depth test against pass 1, additive (colour·w, w), (normal·w, z·w)
//! pass 3 shading:     full-screen, normalize and Blinn-Phong, sRGB out
//! ```
//!
//! The list is uploaded once, in slices no larger than one storage binding (128 MiB on
//! lavapipe), each drawn with its own bind group.

use glam::DVec3;
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use super::camera::Camera;
use super::frame::FrameUniform;
use super::gbuffer::{self, GBuffer};
use super::gpu::Gpu;
use super::pipelines::{OUTPUT, Pipelines};
use super::readback;
use super::scene::Scene;
use super::settings::{Culling, Mode, Settings};
use super::upload::GpuScene;
use crate::tree::select::{error_per_distance, is_drawn};

/// A frame read back: sRGB pixels and which pixels something covered.
#[derive(Debug, Clone)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// RGBA8, sRGB, row-major, top row first.
    pub rgba: Vec<u8>,
    pub covered: Vec<bool>,
    /// View distance of each covered pixel (the blended z; 0 where not covered).
    pub depth: Vec<f32>,
}

#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Nodes handed to the GPU (the CPU prefix).
    pub prefix_len: usize,
    /// Nodes that pass the exact selection test (CPU reference of the GPU test).
    pub selected: usize,
    /// GPU time of the frame (timestamp queries), when the adapter has them.
    pub gpu_ms: Option<f64>,
    /// Splats the GPU drew, counted by the compute culling (None with vertex culling).
    pub gpu_drawn: Option<u64>,
}

pub struct Renderer {
    pub gpu: Gpu,
    pub(super) pipelines: Pipelines,
}

impl Renderer {
    pub fn new(gpu: Gpu) -> Renderer {
        let pipelines = Pipelines::new(&gpu.device);
        Renderer { gpu, pipelines }
    }

    /// Renders one frame and reads it back.
    pub fn render(
        &self,
        scene: &Scene,
        gpu_scene: &GpuScene,
        camera: &Camera,
        settings: &Settings,
        width: u32,
        height: u32,
    ) -> anyhow::Result<(Image, FrameStats)> {
        let device = &self.gpu.device;
        let limits = device.limits();
        if width.max(height) > limits.max_texture_dimension_2d
            || (width as u64).div_ceil(32) * 256 * height as u64 > limits.max_buffer_size
        {
            anyhow::bail!(
                "{width}×{height} is larger than this adapter renders (at most {} pixels a side, {} MB a read-back buffer)",
                limits.max_texture_dimension_2d,
                limits.max_buffer_size >> 20
            );
        }
        let meta = scene.meta();
        let origin = DVec3::from(meta.origin);
        let eye_rel = camera.eye - origin;
        if settings.mode == Mode::Mesh && gpu_scene.mesh.is_none() {
            anyhow::bail!("mesh mode needs a model with faces, read from its PLY file");
        }
        let eps = error_per_distance(settings.error_px, camera.fov_y, height);
        let uniform = FrameUniform::new(meta, camera, settings, width, height);
        let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame"),
            contents: bytemuck::bytes_of(&uniform),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let frame_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &self.pipelines.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });

        // CPU prefix, and the exact test over it for the statistics.
        let nodes = scene.nodes();
        let lod_eps = if settings.lod { eps } else { 0.0 };
        let prefix_len = scene.index.prefix_len(nodes, eye_rel, lod_eps);
        let selected = nodes[..prefix_len]
            .par_iter()
            .filter(|r| is_drawn(r, meta.error_scale, eye_rel, lod_eps))
            .count();

        let gbuffer = GBuffer::new(device, (width, height));
        let output = gbuffer::target(
            device,
            (width, height),
            OUTPUT,
            "output",
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let output_view = output.create_view(&Default::default());
        let queries = self.gpu.timestamps.then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("passes"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            })
        });

        let mut encoder = device.create_command_encoder(&Default::default());
        // Each slice's share of the prefix.
        let mut left = prefix_len as u32;
        let shares: Vec<u32> = gpu_scene
            .slices
            .iter()
            .map(|slice| {
                let n = left.min(slice.count);
                left -= n;
                n
            })
            .collect();
        let compute = settings.culling == Culling::Compute && settings.mode != Mode::Mesh;
        if compute {
            for (slice, &n) in gpu_scene.slices.iter().zip(&shares) {
                self.gpu.queue.write_buffer(
                    &slice.compaction,
                    0,
                    bytemuck::cast_slice(&[4u32, 0, 0, 0, n]),
                );
            }
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cull"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipelines.cull);
            pass.set_bind_group(0, &frame_bind, &[]);
            for (slice, &n) in gpu_scene
                .slices
                .iter()
                .zip(&shares)
                .filter(|(_, n)| **n > 0)
            {
                pass.set_bind_group(1, &slice.cull, &[]);
                pass.dispatch_workgroups(n.div_ceil(256), 1, 1);
            }
        }
        let clear_attachments = |encoder: &mut wgpu::CommandEncoder, first: bool| {
            let ops = |load| wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            };
            let color = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: ops(wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)),
                })
            };
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("clear"),
                color_attachments: &[color(&gbuffer.color_view), color(&gbuffer.normal_view)],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &gbuffer.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: queries.as_ref().filter(|_| first).map(|q| {
                    wgpu::RenderPassTimestampWrites {
                        query_set: q,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: None,
                    }
                }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
        };
        clear_attachments(&mut encoder, true);
        let load = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        let gbuffer_pass = |encoder: &mut wgpu::CommandEncoder, with_colors: bool, label| {
            let color = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: load,
                })
            };
            let colors = [color(&gbuffer.color_view), color(&gbuffer.normal_view)];
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: if with_colors { &colors } else { &[] },
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &gbuffer.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &frame_bind, &[]);
            // The pass ends (is dropped) before the encoder is finished.
            pass.forget_lifetime()
        };
        let pipelines = if compute {
            &self.pipelines.compacted
        } else {
            &self.pipelines.direct
        };
        let draw_prefix = |pass: &mut wgpu::RenderPass, pipeline| {
            pass.set_pipeline(pipeline);
            for (slice, &n) in gpu_scene
                .slices
                .iter()
                .zip(&shares)
                .filter(|(_, n)| **n > 0)
            {
                if compute {
                    pass.set_bind_group(1, &slice.compacted, &[]);
                    pass.draw_indirect(&slice.compaction, 0);
                } else {
                    pass.set_bind_group(1, &slice.direct, &[]);
                    pass.draw(0..4, 0..n);
                }
            }
        };
        match settings.mode {
            Mode::Mesh => {
                let (vb, ib, count) = gpu_scene.mesh.as_ref().expect("checked above");
                let mut pass = gbuffer_pass(&mut encoder, true, "mesh");
                pass.set_pipeline(&self.pipelines.mesh);
                pass.set_vertex_buffer(0, vb.slice(..));
                pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..*count, 0, 0..1);
            }
            Mode::Points => {
                let mut pass = gbuffer_pass(&mut encoder, true, "points");
                draw_prefix(&mut pass, &pipelines.points);
            }
            _ => {
                {
                    let mut pass = gbuffer_pass(&mut encoder, false, "visibility");
                    draw_prefix(&mut pass, &pipelines.visibility);
                }
                let mut pass = gbuffer_pass(&mut encoder, true, "attributes");
                draw_prefix(&mut pass, &pipelines.attributes);
            }
        }
        let gbuffer_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer"),
            layout: &self.pipelines.gbuffer_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&gbuffer.color_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                },
            ],
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shade"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &output_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: queries.as_ref().map(|q| wgpu::RenderPassTimestampWrites {
                    query_set: q,
                    beginning_of_pass_write_index: None,
                    end_of_pass_write_index: Some(1),
                }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipelines.shade);
            pass.set_bind_group(0, &frame_bind, &[]);
            pass.set_bind_group(1, &gbuffer_bind, &[]);
            pass.draw(0..3, 0..1);
        }
        // Read back: the output, the weight channel of the colour sum (coverage), the
        // timestamps, and the survivor counts of compute culling.
        let out_buffer = readback::copy_texture(device, &mut encoder, &output, 4);
        let weight_buffer = readback::copy_texture(device, &mut encoder, &gbuffer.color_sum, 8);
        let normal_buffer = readback::copy_texture(device, &mut encoder, &gbuffer.normal_sum, 8);
        let query_buffer = queries.as_ref().map(|q| {
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(q, 0..2, &resolve, 0);
            readback::copy_ranges(
                device,
                &mut encoder,
                "timestamps read",
                &[(&resolve, 0, 16)],
            )
        });
        let counts = compute.then(|| {
            let ranges: Vec<_> = gpu_scene
                .slices
                .iter()
                .map(|s| (&s.compaction, 4, 4))
                .collect();
            readback::copy_ranges(device, &mut encoder, "survivor counts", &ranges)
        });
        self.gpu.queue.submit([encoder.finish()]);
        let rgba = readback::unpad_rgba8(&readback::read(device, &out_buffer)?, width, height);
        // A pixel counts as covered once it is at least half opaque.
        let coverage_threshold = if uniform.blend[1] > 0.0 {
            0.5 * uniform.blend[1]
        } else {
            0.0
        };
        let weights = readback::read(device, &weight_buffer)?;
        let covered = readback::coverage(&weights, width, height, coverage_threshold);
        let depth = readback::depth(
            &weights,
            &readback::read(device, &normal_buffer)?,
            width,
            height,
        );
        let gpu_ms = match &query_buffer {
            Some(b) => {
                let t: Vec<u64> = bytemuck::cast_slice(&readback::read(device, b)?).to_vec();
                let period_ns = self.gpu.queue.get_timestamp_period() as f64;
                Some(t[1].saturating_sub(t[0]) as f64 * period_ns / 1e6)
            }
            None => None,
        };
        let gpu_drawn = match &counts {
            Some(b) => Some(
                bytemuck::cast_slice::<u8, u32>(&readback::read(device, b)?)
                    .iter()
                    .map(|&c| c as u64)
                    .sum(),
            ),
            None => None,
        };
        Ok((
            Image {
                width,
                height,
                rgba,
                covered,
                depth,
            },
            FrameStats {
                prefix_len,
                selected,
                gpu_ms,
                gpu_drawn,
            },
        ))
    }
}
