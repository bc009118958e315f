//! The splat passes (docs/design.md §7): pass 1, visibility (depth only, pushed back), and
//! pass 2, attributes (additive (colour·w, w) and (normal·w, z·w) into the G-buffer),
//! or plain points (no blending) instead of both. One instanced quad of 4 vertices per
//! node: every node of the prefix, culled in the vertex stage ("direct"), or the
//! survivors that `cull.rs` compacted, drawn indirectly ("compacted"). WGSL:
//! `shaders/splat.wgsl`. The splat passes read each drawn node's record (32 bytes) and
//! shape (24 bytes, [`SplatShape`]); the cull pass reads each tested node's record and
//! each survivor's shape, to sort it into one of its two lists. Pass 2 also reads pass
//! 1's depth (bind group 2, the depth attachment held read-only), to leave out the
//! coverage samples of pixels inside the picture's outlines. Each quad is the screen
//! box of the splat's projected ellipse, grown by what its fragment shader keeps
//! beyond the patch ([`quad_reach`]). Every fragment shader writes a depth no nearer
//! than its quad's, which the quad carries (the splat's nearest point), so that the
//! GPU may reject fragments before running them.

use std::sync::OnceLock;

use wgpu::CompareFunction::{Greater, GreaterEqual};

use super::Gpu;
use super::bindings::{Slot, splat as slots};
use super::cull::Compaction;
use super::fullscreen::fragment_texture;
use super::gbuffer::{ADD, GBuffer, Writes, color_targets, depth_state, target};
use super::gpu_scene::Share;
use super::placement::Placement;
use super::settings::Mode;
use super::shaders::{ColorSource, QuadReach, SplatClass, module};
use super::targets::{FrameTargets, stamp};
use crate::io::geometry::PointAttributes;
use crate::surfel::shape::SplatShape;
use crate::tree::NodeRecord;

/// The splat pipelines of one culling strategy. Pass 2 draws two kinds of splat (WGSL
/// `SPLAT_CLASS`, `on_outline` in `shaders/shape.wgsl`) with two pipelines: those whose
/// rim may lie on an outline, with the coverage samples, and the others, without them.
/// After compute culling each kind is a list of its own, so every pass draws both
/// lists, each with its pipeline; vertex culling draws passes 1 and points once, and
/// pass 2 twice, each draw keeping its kind. Each colour source (WGSL `COLOR_SOURCE`)
/// has its own pass 2 pipelines, made when a frame first needs them: llvmpipe runs
/// every branch of a shader, so a colour chosen by a uniform `switch` cost every
/// vertex all of them (a sixth of the knot's frame at 64×64).
pub(super) struct SplatPipelines {
    pub visibility: Vec<wgpu::RenderPipeline>,
    pub points: Vec<wgpu::RenderPipeline>,
    attributes: [OnceLock<[wgpu::RenderPipeline; 2]>; ColorSource::COUNT],
    maker: PipelineMaker,
}

/// Layouts of bind groups 1 and 2 and the pipelines of both culling strategies.
pub(super) struct SplatPasses {
    /// The slice's nodes (binding 0), shapes (2), attributes (3) and its model's
    /// placements (4), for vertex culling.
    pub nodes_layout: wgpu::BindGroupLayout,
    /// The same with the survivors (1) and their placements (5), for compute culling.
    pub compacted_layout: wgpu::BindGroupLayout,
    /// Pass 1's depth as a texture, for pass 2 (group 2; see `fs_attributes`).
    depth_layout: wgpu::BindGroupLayout,
    pub direct: SplatPipelines,
    pub compacted: SplatPipelines,
}

/// The format of the texel that stands for pass 1's depth where it cannot be read
/// (`SplatPasses::depth_bind`); wgpu clears new textures to 0.
const NO_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// A read-only storage buffer of bind group 1 for the vertex stage.
fn vertex_storage(slot: Slot, min_size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: slot.binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(min_size),
        },
        count: None,
    }
}

/// How far the quads of fragment entry point `fs` reach beyond the patch (WGSL
/// `QUAD_REACH`): pass 1 and the inner splats' pass 2 keep only fragments whose centre
/// a patch covers, the outline splats' pass 2 those its coverage samples reach, the
/// points the prefilter's band.
fn quad_reach(fs: &str) -> QuadReach {
    match fs {
        "fs_visibility" | "fs_attributes_inner" => QuadReach::Patch,
        "fs_attributes" => QuadReach::Samples,
        _ => QuadReach::Band,
    }
}

/// Makes the splat pipelines of vertex entry point `vs` (bind group 1 laid out as
/// `layout` says; pass 2's `attributes_layout` adds group 2, pass 1's depth), which
/// reads compacted lists or not.
struct PipelineMaker {
    device: wgpu::Device,
    shader: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    attributes_layout: wgpu::PipelineLayout,
    vs: &'static str,
    compacted: bool,
    /// WGSL `SKIP_SURROUNDED_SAMPLES` ([`Gpu::skips_surrounded_samples`]).
    skip_surrounded: bool,
}

impl PipelineMaker {
    /// The pipeline of fragment entry point `fs`, its vertex stage specialised to the
    /// splat class and colour source given.
    fn pipeline(
        &self,
        fs: &str,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: Option<wgpu::DepthStencilState>,
        (class, color): (SplatClass, ColorSource),
    ) -> wgpu::RenderPipeline {
        let layout = match fs.starts_with("fs_attributes") {
            true => &self.attributes_layout,
            false => &self.layout,
        };
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fs),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &self.shader,
                    entry_point: Some(self.vs),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[
                            ("SPLAT_CLASS", class as u32 as f64),
                            ("COLOR_SOURCE", color as u32 as f64),
                            ("QUAD_REACH", quad_reach(fs) as u32 as f64),
                        ],
                        ..Default::default()
                    },
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleStrip,
                    ..Default::default()
                },
                depth_stencil: depth,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &self.shader,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[(
                            "SKIP_SURROUNDED_SAMPLES",
                            f64::from(u8::from(self.skip_surrounded)),
                        )],
                        ..Default::default()
                    },
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
    }

    /// Pass 2's pipelines for `color`: the outline splats', then the others'.
    fn attributes(&self, color: ColorSource) -> [wgpu::RenderPipeline; 2] {
        let targets = color_targets(Some(ADD));
        let depth = || depth_state(GreaterEqual, false);
        [
            self.pipeline(
                "fs_attributes",
                &targets,
                depth(),
                (SplatClass::Outline, color),
            ),
            self.pipeline(
                "fs_attributes_inner",
                &targets,
                depth(),
                (SplatClass::Inner, color),
            ),
        ]
    }

    /// The pipelines of fragment entry point `fs` for all splats: one per list after
    /// compute culling (outline, inner), else one.
    fn every_splat(
        &self,
        fs: &str,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: Option<wgpu::DepthStencilState>,
    ) -> Vec<wgpu::RenderPipeline> {
        let classes: &[SplatClass] = match self.compacted {
            true => &[SplatClass::Outline, SplatClass::Inner],
            false => &[SplatClass::All],
        };
        let draw = |&class| self.pipeline(fs, targets, depth.clone(), (class, ColorSource::Node));
        classes.iter().map(draw).collect()
    }

    fn pipelines(self) -> SplatPipelines {
        let points = color_targets(None);
        let nearest = depth_state(Greater, true);
        SplatPipelines {
            visibility: self.every_splat("fs_visibility", &[], nearest.clone()),
            points: self.every_splat("fs_points", &points, nearest),
            attributes: Default::default(),
            maker: self,
        }
    }
}

impl SplatPipelines {
    /// Pass 2's pipelines for display mode `mode`, made at the first call.
    pub fn attributes(&self, mode: Mode) -> &[wgpu::RenderPipeline; 2] {
        let color = ColorSource::of(mode);
        self.attributes[color as usize].get_or_init(|| self.maker.attributes(color))
    }
}

impl SplatPasses {
    pub fn new(gpu: &Gpu, frame_layout: &wgpu::BindGroupLayout) -> SplatPasses {
        let device = &gpu.device;
        let node = size_of::<NodeRecord>() as u64;
        let shape = size_of::<SplatShape>() as u64;
        let attribute = size_of::<PointAttributes>() as u64;
        let bind_layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let placement = size_of::<Placement>() as u64;
        let nodes_layout = bind_layout(
            "nodes",
            &[
                vertex_storage(slots::NODES, node),
                vertex_storage(slots::SHAPES, shape),
                vertex_storage(slots::ATTRIBUTES, attribute),
                vertex_storage(slots::PLACEMENTS, placement),
            ],
        );
        let compacted_layout = bind_layout(
            "compacted nodes",
            &[
                vertex_storage(slots::NODES, node),
                vertex_storage(slots::SURVIVORS, size_of::<u32>() as u64),
                vertex_storage(slots::SHAPES, shape),
                vertex_storage(slots::ATTRIBUTES, attribute),
                vertex_storage(slots::PLACEMENTS, placement),
                vertex_storage(slots::SURVIVOR_PLACEMENTS, size_of::<u32>() as u64),
            ],
        );
        let depth_layout = bind_layout(
            "pass 1 depth",
            &[fragment_texture(slots::VISIBLE_DEPTH.binding)],
        );
        let pipeline_layout = |groups: &[&wgpu::BindGroupLayout]| {
            let groups: Vec<_> = groups.iter().map(|&g| Some(g)).collect();
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &groups,
                immediate_size: 0,
            })
        };
        let shader = module(device, "splat");
        let maker = |layout: &wgpu::BindGroupLayout, vs, compacted| PipelineMaker {
            device: device.clone(),
            shader: shader.clone(),
            layout: pipeline_layout(&[frame_layout, layout]),
            attributes_layout: pipeline_layout(&[frame_layout, layout, &depth_layout]),
            vs,
            compacted,
            skip_surrounded: gpu.skips_surrounded_samples(),
        };
        SplatPasses {
            direct: maker(&nodes_layout, "vs_splat", false).pipelines(),
            compacted: maker(&compacted_layout, "vs_splat_compacted", true).pipelines(),
            nodes_layout,
            compacted_layout,
            depth_layout,
        }
    }

    /// Bind group 2 of pass 2: `gbuffer`'s depth, which pass 1 wrote, where the
    /// adapter can read a depth attachment as a texture in the pass that tests it
    /// (`read_only_depth`, not on GL). Elsewhere a texel of depth 0, which surrounds
    /// no pixel: pass 2 then samples every outline splat's coverage.
    pub fn depth_bind(
        &self,
        device: &wgpu::Device,
        gbuffer: &GBuffer,
        read_only_depth: bool,
    ) -> wgpu::BindGroup {
        let none = || {
            let usage = wgpu::TextureUsages::TEXTURE_BINDING;
            let texel = target(device, (1, 1), NO_DEPTH, "no depth", usage);
            texel.create_view(&Default::default())
        };
        let view = match read_only_depth {
            true => gbuffer.depth_view.clone(),
            false => none(),
        };
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pass 1 depth"),
            layout: &self.depth_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: slots::VISIBLE_DEPTH.binding,
                resource: wgpu::BindingResource::TextureView(&view),
            }],
        })
    }

    /// Draws each slice's share of the frame's ranges with each of `pipelines` in turn,
    /// with the frame's bind group and, for pass 2, pass 1's depth (`binds`). After
    /// compute culling, pipeline k draws the k-th list of survivors (indirect,
    /// [`Compaction::DRAWS_AT`]); else every pipeline draws every node of each range (its
    /// instances are its nodes' slice indices).
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass,
        pipelines: &[wgpu::RenderPipeline],
        (frame_bind, depth_bind): (&wgpu::BindGroup, Option<&wgpu::BindGroup>),
        shares: &[Share],
        compacted: bool,
    ) {
        for (pipeline, draw_at) in pipelines.iter().zip(Compaction::DRAWS_AT) {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, frame_bind, &[]);
            if let Some(depth) = depth_bind {
                pass.set_bind_group(slots::VISIBLE_DEPTH.group, depth, &[]);
            }
            for share in shares.iter().filter(|s| s.drawn()) {
                if compacted {
                    pass.set_bind_group(1, &share.slice.compacted, &[]);
                    pass.draw_indirect(&share.slice.compaction, draw_at);
                } else {
                    pass.set_bind_group(1, &share.slice.direct, &[]);
                    for r in &share.ranges {
                        pass.draw(0..4, r.clone());
                    }
                }
            }
        }
    }

    /// The pipelines of a culling strategy.
    fn of(&self, compacted: bool) -> &SplatPipelines {
        if compacted {
            &self.compacted
        } else {
            &self.direct
        }
    }
}

impl SplatPasses {
    /// Records the splat passes of display mode `mode` (points, or visibility then
    /// attributes) for the nodes of `shares`, each pass one render pass over the
    /// G-buffer, its pipelines drawing every slice's share: after compute culling
    /// (`compacted`) each slice's survivor lists, else every node of its ranges, tested
    /// as it is drawn. Writes the passes' timestamps into `targets`' queries.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        shares: &[Share],
        mode: Mode,
        compacted: bool,
    ) {
        let pipelines = self.of(compacted);
        let g = &targets.gbuffer;
        let draw = |encoder: &mut wgpu::CommandEncoder, label, writes, pipeline, end| {
            let mut pass = g.pass(encoder, label, writes, false, targets.timestamps(None, end));
            let depth = (writes == Writes::Attributes).then_some(&targets.depth_bind);
            let binds = (&targets.frame_bind, depth);
            self.draw(&mut pass, pipeline, binds, shares, compacted);
        };
        let attributes_end = Some(stamp::ATTRIBUTES_END);
        if mode == Mode::Points {
            draw(
                encoder,
                "points",
                Writes::All,
                &pipelines.points,
                attributes_end,
            );
            return;
        }
        let visibility_end = Some(stamp::VISIBILITY_END);
        let visibility = &pipelines.visibility;
        draw(
            encoder,
            "visibility",
            Writes::Depth,
            visibility,
            visibility_end,
        );
        let attributes = pipelines.attributes(mode);
        draw(
            encoder,
            "attributes",
            Writes::Attributes,
            attributes,
            attributes_end,
        );
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_shape_record_matches_its_wgsl_struct() {
        super::super::shaders::assert_wgsl_size::<super::SplatShape>("shape", "SplatShape");
    }
}
