//! The splat passes as compute rasterization (docs/gpu.md): the same survivors, the
//! same splat mathematics (`shaders/ewa.wgsl`), drawn by compute shaders instead of the
//! raster pipeline. WGSL: `shaders/raster.wgsl` (the passes), `shaders/accumulate.wgsl`
//! (the per-pixel buffers), `shaders/resolve.wgsl` (buffers to G-buffer).
//!
//! ```text
//! cull (compute)     survivor lists per slice, as for the hardware path
//! visibility         per splat, per pixel of its box: atomicMax of the pushed-back depth
//! attributes         fragments within that depth: integer atomicAdd of the fixed-point
//!                    sums (colour·w, w, (normal+1)·w, (z/z₁)·w), atomicOr of coverage
//!   (points instead: the nearest depth, then the first point of the list at it, which
//!    stores its attributes)
//! resolve            sums / w into the G-buffer, the buffers cleared for the next frame
//! shading            pass 3, unchanged
//! ```
//!
//! Integer sums make the frame the same whatever order the threads run in: two runs
//! of a frame give the same bytes. A workgroup draws the pixels of its 64 splats
//! together, neighbouring threads taking neighbouring pixels (raster.wgsl), whatever the
//! footprints' sizes.

use std::sync::OnceLock;

use super::accumulation::{Accumulation, FLOAT_DEPTH, sums_bytes};
use super::bindings::{Slot, accumulate, raster as slots, resolve as out};
use super::cull::storage;
use super::far::FarArgs;
use super::gbuffer::{COVERAGE, GBUFFER, GBuffer};
use super::gpu_scene::Share;
use super::placement::Placement;
use super::settings::Mode;
use super::shaders::{
    ColorSource, PIXEL_TILE, QuadReach, RASTER_WORKGROUP, RasterPass, SplatClass, module,
};
use super::targets::{FrameTargets, stamp};
use crate::io::geometry::PointAttributes;
use crate::surfel::shape::SplatShape;
use crate::tree::NodeRecord;

/// The pipelines of one pass: the outline splats', then the inner ones'.
type ByClass = [wgpu::ComputePipeline; 2];

/// The compute rasterizer: layouts, and pipelines made when a frame first needs them
/// (a CPU adapter compiles each for a second or more).
pub(super) struct ComputeRaster {
    device: wgpu::Device,
    /// Group 1: a slice's nodes, survivors, shapes, attributes and compaction record, its
    /// model's placements and its survivors'.
    pub slice_layout: wgpu::BindGroupLayout,
    /// Group 2: the per-pixel buffers.
    accumulation_layout: wgpu::BindGroupLayout,
    /// Group 1 of the resolve: the G-buffer as storage textures.
    resolve_layout: wgpu::BindGroupLayout,
    raster_layout: wgpu::PipelineLayout,
    resolve_pipeline_layout: wgpu::PipelineLayout,
    /// WGSL `SKIP_SURROUNDED_SAMPLES`: not on a CPU, which runs both sides of a branch.
    skip_surrounded: bool,
    visibility: OnceLock<ByClass>,
    points: OnceLock<[ByClass; 3]>,
    attributes: [OnceLock<ByClass>; ColorSource::COUNT],
    resolve: OnceLock<wgpu::ComputePipeline>,
    /// The raster passes' shader module, parsed once for all their pipelines.
    shader: OnceLock<wgpu::ShaderModule>,
}

/// A compute-stage entry of `slot`: a write-only storage texture of `format`.
pub(super) fn storage_texture(
    slot: Slot,
    format: wgpu::TextureFormat,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: slot.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    }
}

impl ComputeRaster {
    /// The layouts on `device`; `on_cpu`: the adapter is a CPU rasterizer (the
    /// fragments then take every coverage sample, see `skip_surrounded`).
    pub fn new(
        device: &wgpu::Device,
        frame_layout: &wgpu::BindGroupLayout,
        on_cpu: bool,
    ) -> ComputeRaster {
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let compaction = size_of::<super::cull::Compaction>() as u64;
        let slice_layout = layout(
            "raster slice",
            &[
                storage(slots::NODES, true, size_of::<NodeRecord>() as u64),
                storage(slots::SURVIVORS, true, 4),
                storage(slots::SHAPES, true, size_of::<SplatShape>() as u64),
                storage(slots::ATTRIBUTES, true, size_of::<PointAttributes>() as u64),
                storage(slots::COMPACTION, true, compaction),
                storage(slots::PLACEMENTS, true, size_of::<Placement>() as u64),
                storage(slots::SURVIVOR_PLACEMENTS, true, 4),
            ],
        );
        let buffers: Vec<_> = accumulate::ALL.map(|s| storage(s, false, 4)).into();
        let accumulation_layout = layout("accumulation", &buffers);
        let resolve_layout = layout(
            "resolved gbuffer",
            &[
                storage_texture(out::COLOR_OUT, GBUFFER),
                storage_texture(out::NORMAL_OUT, GBUFFER),
                storage_texture(out::COVERAGE_OUT, COVERAGE),
                storage_texture(out::DEPTH_OUT, FLOAT_DEPTH),
            ],
        );
        let pipeline_layout = |group_1| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[
                    Some(frame_layout),
                    Some(group_1),
                    Some(&accumulation_layout),
                ],
                immediate_size: 0,
            })
        };
        ComputeRaster {
            device: device.clone(),
            raster_layout: pipeline_layout(&slice_layout),
            resolve_pipeline_layout: pipeline_layout(&resolve_layout),
            slice_layout,
            accumulation_layout,
            resolve_layout,
            skip_surrounded: !on_cpu,
            visibility: OnceLock::new(),
            points: OnceLock::new(),
            attributes: Default::default(),
            resolve: OnceLock::new(),
            shader: OnceLock::new(),
        }
    }

    /// The raster pipeline of `pass` for `class` and `color`.
    fn pipeline(
        &self,
        pass: RasterPass,
        class: SplatClass,
        color: ColorSource,
    ) -> wgpu::ComputePipeline {
        let reach = match pass {
            RasterPass::Visibility => QuadReach::Patch,
            RasterPass::Attributes if class == SplatClass::Inner => QuadReach::Patch,
            RasterPass::Attributes => QuadReach::Samples,
            _ => QuadReach::Band,
        };
        let constants = [
            ("RASTER_PASS", pass as u32 as f64),
            ("SPLAT_CLASS", class as u32 as f64),
            ("COLOR_SOURCE", color as u32 as f64),
            ("QUAD_REACH", reach as u32 as f64),
            (
                "SKIP_SURROUNDED_SAMPLES",
                f64::from(u8::from(self.skip_surrounded)),
            ),
        ];
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("raster"),
                layout: Some(&self.raster_layout),
                module: self.shader.get_or_init(|| module(&self.device, "raster")),
                entry_point: Some("raster"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    // Every thread writes its own entries of the workgroup's memory
                    // before any is read: zeroing it first would be wasted.
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            })
    }

    /// `pass`'s pipelines for both classes of splat.
    fn by_class(&self, pass: RasterPass, color: ColorSource) -> ByClass {
        [SplatClass::Outline, SplatClass::Inner].map(|class| self.pipeline(pass, class, color))
    }

    fn resolve_pipeline(&self) -> &wgpu::ComputePipeline {
        self.resolve.get_or_init(|| {
            self.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("resolve"),
                    layout: Some(&self.resolve_pipeline_layout),
                    module: &module(&self.device, "resolve"),
                    entry_point: Some("resolve"),
                    compilation_options: Default::default(),
                    cache: None,
                })
        })
    }

    /// The stages of display mode `mode`'s two passes, each a list of pipeline pairs
    /// run one after the other: pass 1 (visibility, or the points' depth), then pass 2
    /// (attributes, or the points' winner and write).
    fn stages(&self, mode: Mode) -> [Vec<&ByClass>; 2] {
        if mode == Mode::Points {
            let [depth, winner, write] = self.points.get_or_init(|| {
                [
                    RasterPass::PointDepth,
                    RasterPass::PointWinner,
                    RasterPass::PointWrite,
                ]
                .map(|pass| self.by_class(pass, ColorSource::Node))
            });
            return [vec![depth], vec![winner, write]];
        }
        let color = ColorSource::of(mode);
        let visibility = self
            .visibility
            .get_or_init(|| self.by_class(RasterPass::Visibility, ColorSource::Node));
        let attributes = self.attributes[color as usize]
            .get_or_init(|| self.by_class(RasterPass::Attributes, color));
        [vec![visibility], vec![attributes]]
    }

    /// A slice's bind group 1 for the raster passes.
    pub fn bind_slice(&self, buffers: [(Slot, &wgpu::Buffer); 7]) -> wgpu::BindGroup {
        let entries = buffers.map(|(slot, b)| wgpu::BindGroupEntry {
            binding: slot.binding,
            resource: b.as_entire_binding(),
        });
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raster slice"),
            layout: &self.slice_layout,
            entries: &entries,
        })
    }

    /// Records the splat passes of `mode` over every slice's survivor lists (the cull
    /// pass filled them), then the resolve into `targets`' G-buffer.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        accumulation: &Accumulation,
        shares: &[Share],
        mode: Mode,
    ) {
        let [first, second] = self.stages(mode);
        let passes = [
            ("visibility", first, None, stamp::VISIBILITY_END),
            ("attributes", second, None, stamp::ATTRIBUTES_END),
        ];
        let max_groups = self.device.limits().max_compute_workgroups_per_dimension;
        for (label, stages, begin, end) in passes {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: targets.compute_timestamps(begin, Some(end)),
            });
            pass.set_bind_group(0, &targets.frame_bind, &[]);
            pass.set_bind_group(2, &accumulation.bind, &[]);
            for pipelines in stages {
                for pipeline in pipelines {
                    pass.set_pipeline(pipeline);
                    for share in shares.iter().filter(|s| s.drawn()) {
                        pass.set_bind_group(1, &share.slice.rasterized, &[]);
                        match share.far {
                            Some(args) => {
                                pass.dispatch_workgroups_indirect(args, FarArgs::RASTER_AT)
                            }
                            None => {
                                let groups = share.count.div_ceil(RASTER_WORKGROUP);
                                let (x, y) = grid(groups, max_groups);
                                pass.dispatch_workgroups(x, y, 1);
                            }
                        }
                    }
                }
            }
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("resolve"),
            timestamp_writes: None,
        });
        pass.set_pipeline(self.resolve_pipeline());
        pass.set_bind_group(0, &targets.frame_bind, &[]);
        pass.set_bind_group(1, &accumulation.resolve_bind, &[]);
        pass.set_bind_group(2, &accumulation.bind, &[]);
        let (w, h) = targets.size;
        pass.dispatch_workgroups(w.div_ceil(PIXEL_TILE), h.div_ceil(PIXEL_TILE), 1);
    }

    /// The per-pixel buffers of a `size` frame drawing into `gbuffer`.
    pub fn accumulation(&self, gbuffer: &GBuffer, size: (u32, u32)) -> Accumulation {
        let layouts = [&self.accumulation_layout, &self.resolve_layout];
        Accumulation::new(&self.device, layouts, gbuffer, size)
    }

    /// Checks that the per-pixel buffers of a `size` frame fit one storage binding.
    pub fn check_size(&self, size: (u32, u32)) -> anyhow::Result<()> {
        let bytes = sums_bytes(size);
        let limit = self.device.limits().max_storage_buffer_binding_size;
        if bytes > limit {
            anyhow::bail!(
                "{}×{} needs {} MB of sums per binding, more than this adapter binds ({} MB): \
                 use --raster hardware or a smaller size",
                size.0,
                size.1,
                bytes >> 20,
                limit >> 20
            );
        }
        Ok(())
    }
}

/// Workgroups (x, y) of a dispatch of `groups` in all, x at most `max` (the rows' last
/// groups find no survivor and return).
fn grid(groups: u32, max: u32) -> (u32, u32) {
    let x = groups.clamp(1, max);
    (x, groups.div_ceil(x))
}

#[cfg(test)]
mod tests {
    use super::grid;

    #[test]
    fn a_large_dispatch_is_folded_into_rows() {
        assert_eq!(grid(10, 65535), (10, 1));
        assert_eq!(grid(0, 65535), (1, 0));
        assert_eq!(grid(200_000, 65535), (65535, 4));
    }

    #[test]
    fn the_compaction_record_reads_as_the_raster_survivors() {
        super::super::shaders::assert_wgsl_size::<super::super::cull::Compaction>(
            "raster",
            "Survivors",
        );
    }
}
