//! One frame's GPU work, recorded into a caller's encoder: the CPU prefix, the compute
//! culling, passes 1–2 (or the mesh, or plain points) into the G-buffer and pass 3
//! into the output. Nothing is allocated per frame; nothing is read back here.
//!
//! ```text
//! CPU: prefix (binary search) ─► per slice of the list: instanced quads, 4 vertices each
//! cull (compute, optional): survivors of the selection test ─► indirect draw
//! pass 1 visibility:  depth only, pushed back by a fraction of the radius
//! pass 2 attributes:  depth test against pass 1, additive (colour·w, w), (normal·w, z·w)
//! pass 3 shading:     full-screen, normalize and Blinn-Phong, sRGB out
//! ```

use glam::DVec3;

use super::camera::Camera;
use super::frame::{FrameUniform, srgb_to_linear};
use super::renderer::Renderer;
use super::settings::{Culling, Mode, Settings};
use super::shaders::WORKGROUP_SIZE;
use super::targets::{FrameTargets, check_size};
use super::upload::GpuScene;
use crate::tree::scene::Scene;
use crate::tree::select::error_per_distance;

/// What the CPU decided for one recorded frame.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedFrame {
    /// Nodes handed to the GPU (the CPU prefix).
    pub prefix_len: usize,
    /// Compute culling ran: the survivor counts can be read back.
    pub compute: bool,
    /// ε of the selection test, world error per unit of distance.
    pub eps: f64,
    /// ε had to be raised above the settings' because the prefix they ask for is not
    /// all on the GPU yet (while a model uploads): the frame is a coarser cut.
    pub coarsened: bool,
    /// Slices of the list on the GPU when the frame was recorded.
    pub slices: usize,
    /// The eye the level of detail was chosen for, relative to the model's origin.
    pub lod_eye: DVec3,
}

fn load_ops<V>(load: wgpu::LoadOp<V>) -> wgpu::Operations<V> {
    wgpu::Operations {
        load,
        store: wgpu::StoreOp::Store,
    }
}

/// A render pass over the G-buffer: its two colour sums (unless `depth_only`) and the
/// depth, cleared or loaded, with an optional timestamp at its start.
fn gbuffer_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    targets: &FrameTargets,
    label: &str,
    depth_only: bool,
    clear: bool,
    timestamp: Option<u32>,
) -> wgpu::RenderPass<'e> {
    let g = &targets.gbuffer;
    let color = |view| {
        Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: load_ops(if clear {
                wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
            } else {
                wgpu::LoadOp::Load
            }),
        })
    };
    let colors = [color(&g.color_view), color(&g.normal_view)];
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: if depth_only { &[] } else { &colors },
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &g.depth_view,
            depth_ops: Some(load_ops(if clear {
                wgpu::LoadOp::Clear(0.0)
            } else {
                wgpu::LoadOp::Load
            })),
            stencil_ops: None,
        }),
        timestamp_writes: targets
            .queries
            .as_ref()
            .zip(timestamp)
            .map(|((q, _), index)| wgpu::RenderPassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(index),
                end_of_pass_write_index: None,
            }),
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// The least ε ≥ `eps` whose prefix (seen from `eye`) lies within the first `uploaded`
/// nodes, and that prefix. Any ε gives a complete cut of the tree, so a frame drawn
/// while the list uploads is coarser, never holed. The prefix shrinks as ε grows, so
/// the least fitting ε is found by doubling, then bisection.
fn fitting_eps(scene: &Scene, eye: DVec3, eps: f64, uploaded: usize) -> (f64, usize) {
    let nodes = scene.nodes();
    let prefix = |e: f64| scene.index.prefix_len(nodes, eye, e);
    let wanted = prefix(eps);
    if wanted <= uploaded {
        return (eps, wanted);
    }
    if uploaded == 0 {
        return (eps, 0);
    }
    let mut lo = eps;
    let mut hi = eps.max(scene.meta().error_scale as f64 * 1e-9);
    for _ in 0..200 {
        if prefix(hi) <= uploaded {
            break;
        }
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if prefix(mid) <= uploaded {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (hi, prefix(hi).min(uploaded))
}

impl Renderer {
    /// Targets for frames of `size`, checked against the adapter's limits.
    pub fn targets(&self, size: (u32, u32)) -> anyhow::Result<FrameTargets> {
        check_size(&self.gpu.device.limits(), size)?;
        Ok(FrameTargets::new(
            &self.gpu.device,
            &self.pipelines,
            size,
            self.gpu.timestamps,
        ))
    }

    /// Records one frame of `scene` into `encoder`, drawing into `targets.output`. The
    /// frame uniform is written through the queue, so it takes effect at the next submit.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        scene: &Scene,
        gpu_scene: &GpuScene,
        camera: &Camera,
        settings: &Settings,
    ) -> anyhow::Result<EncodedFrame> {
        if settings.mode == Mode::Mesh && gpu_scene.mesh.is_none() {
            anyhow::bail!("mesh mode needs a model with faces, read from its PLY file");
        }
        let meta = scene.meta();
        let (width, height) = targets.size;
        let eps = error_per_distance(settings.error_px, camera.fov_y, height);
        let wanted_eps = if settings.lod { eps } else { 0.0 };
        let lod_eye = settings.lod_eye.unwrap_or(camera.eye) - DVec3::from(meta.origin);
        let (lod_eps, prefix_len) =
            fitting_eps(scene, lod_eye, wanted_eps, gpu_scene.uploaded_nodes());
        let uniform = FrameUniform::new(meta, camera, settings, (width, height), lod_eps);
        self.gpu
            .queue
            .write_buffer(&targets.frame_buffer, 0, bytemuck::bytes_of(&uniform));
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
        let drawn_slices = || {
            gpu_scene
                .slices
                .iter()
                .zip(&shares)
                .filter(|(_, n)| **n > 0)
        };

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
            pass.set_bind_group(0, &targets.frame_bind, &[]);
            for (slice, &n) in drawn_slices() {
                pass.set_bind_group(1, &slice.cull, &[]);
                pass.dispatch_workgroups(n.div_ceil(WORKGROUP_SIZE), 1, 1);
            }
        }
        gbuffer_pass(encoder, targets, "clear", false, true, Some(0));
        let pipelines = if compute {
            &self.pipelines.compacted
        } else {
            &self.pipelines.direct
        };
        let draw_prefix = |pass: &mut wgpu::RenderPass, pipeline| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &targets.frame_bind, &[]);
            for (slice, &n) in drawn_slices() {
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
                let mut pass = gbuffer_pass(encoder, targets, "mesh", false, false, None);
                pass.set_pipeline(&self.pipelines.mesh);
                pass.set_bind_group(0, &targets.frame_bind, &[]);
                pass.set_vertex_buffer(0, vb.slice(..));
                pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..*count, 0, 0..1);
            }
            Mode::Points => {
                let mut pass = gbuffer_pass(encoder, targets, "points", false, false, None);
                draw_prefix(&mut pass, &pipelines.points);
            }
            _ => {
                let mut pass = gbuffer_pass(encoder, targets, "visibility", true, false, None);
                draw_prefix(&mut pass, &pipelines.visibility);
                drop(pass);
                let mut pass = gbuffer_pass(encoder, targets, "attributes", false, false, None);
                draw_prefix(&mut pass, &pipelines.attributes);
            }
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shade"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.output_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: load_ops(wgpu::LoadOp::Clear(wgpu::Color::BLACK)),
                })],
                depth_stencil_attachment: None,
                timestamp_writes: targets.queries.as_ref().map(|(q, _)| {
                    wgpu::RenderPassTimestampWrites {
                        query_set: q,
                        beginning_of_pass_write_index: None,
                        end_of_pass_write_index: Some(1),
                    }
                }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipelines.shade);
            pass.set_bind_group(0, &targets.frame_bind, &[]);
            pass.set_bind_group(1, &targets.gbuffer_bind, &[]);
            pass.draw(0..3, 0..1);
        }
        if let Some((set, resolve)) = &targets.queries {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
        }
        Ok(EncodedFrame {
            prefix_len,
            compute,
            eps: lod_eps,
            coarsened: lod_eps != wanted_eps,
            slices: gpu_scene.slices.len(),
            lod_eye,
        })
    }
}

impl Renderer {
    /// Records a frame with nothing in it: the output cleared to `background` (sRGB).
    pub fn encode_empty(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        background: [f32; 3],
    ) {
        let [r, g, b] = background.map(|c| srgb_to_linear(c) as f64);
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("empty"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.output_view,
                depth_slice: None,
                resolve_target: None,
                ops: load_ops(wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 })),
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
    }
}
