//! The renderer: the passes, made once per device, composed into frames. A frame is
//! recorded into a caller's encoder ([`Renderer::encode`]: the viewer records into its
//! own), or rendered offline and read back (pixels, coverage, depth and counters).
//!
//! ```text
//! CPU: plan (ε, visible chunks, their prefixes by binary search) ─► per slice: quads
//! cull (compute, optional): survivors of the selection test ─► indirect draw
//! pass 1 visibility:  depth only, pushed back by a fraction of the radius
//! pass 2 attributes:  depth test against pass 1, additive (colour·w, w), (normal·w, z·w)
//!        (or: the mesh reference, or plain points, instead of passes 1–2)
//! pass 3 shading:     full-screen, normalize and Blinn-Phong, sRGB out
//! ```
//!
//! Passes 1–2 (and the points) run through the raster pipeline ([`SplatPasses`]) or as
//! compute rasterization ([`ComputeRaster`], which needs the cull pass's lists and
//! resolves its buffers into the same G-buffer): [`Settings::raster`].

use rayon::prelude::*;

use super::camera::Camera;
use super::counters::read_counters_now;
use super::cull::CullPass;
use super::frame::{FrameUniform, frame_layout, srgb_to_linear};
use super::gbuffer::{GBuffer, Writes, store};
use super::gpu::Gpu;
use super::gpu_scene::{GpuScene, MeshUpload, SliceHome, SliceUpload};
use super::mesh::MeshPass;
use super::placement::Placement;
use super::plan::{EncodedFrame, plan};
use super::raster::ComputeRaster;
use super::readback;
use super::settings::{Culling, Mode, PrefixCut, Raster, Settings};
use super::shading::ShadingPass;
use super::splats::SplatPasses;
use super::targets::{ComputeBinds, FrameTargets, check_size, stamp};
use super::upload;
use crate::tree::report::{Report, Silent, Step};
use crate::tree::scene::Scene;
use crate::tree::select::is_drawn;

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

impl Image {
    /// Pixel `i`'s colour in linear light, each channel in 0–1 (`rgba` decoded).
    pub fn linear_rgb(&self, i: usize) -> [f32; 3] {
        [0, 1, 2].map(|k| srgb_to_linear(self.rgba[4 * i + k] as f32 / 255.0))
    }
}

#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Nodes handed to the GPU to test (the visible chunks' prefixes).
    pub tested: usize,
    /// Chunks of the model, and those with nodes to test.
    pub chunks: usize,
    pub chunks_tested: usize,
    /// Nodes that pass the exact selection test in the ranges handed over (CPU
    /// reference of the GPU test, frustum aside).
    pub selected: usize,
    /// GPU time of the frame (timestamp queries), when the adapter has them.
    pub gpu_ms: Option<f64>,
    /// The same per pass: visibility, attributes, shading.
    pub passes_ms: Option<[f64; 3]>,
    /// Splats the GPU drew, counted by the compute culling (None with vertex culling).
    pub gpu_drawn: Option<u64>,
    /// Of those, the splats on an outline (drawn with the coverage samples).
    pub gpu_outline: Option<u64>,
    /// ε of the selection, world error per unit of distance, and whether it was raised
    /// above the asked one because the GPU did not hold the asked ranges.
    pub eps: f64,
    pub coarsened: bool,
    /// What planning the frame (chunks, prefixes) took the CPU, ms.
    pub plan_ms: f64,
    /// A scene's instances the GPU placed itself (its far ones, `far.rs`), of those
    /// drawn.
    pub gpu_placed: Option<u64>,
}

impl FrameStats {
    /// The statistics of `frame` with its GPU `counters`: `(chunks, chunks_tested)` of
    /// the model (or the scene's models and test ranges), `selected` splats.
    pub(super) fn of(
        frame: &EncodedFrame,
        counters: &super::GpuCounters,
        (chunks, chunks_tested): (usize, usize),
        selected: usize,
    ) -> FrameStats {
        FrameStats {
            tested: frame.tested,
            chunks,
            chunks_tested,
            selected,
            gpu_ms: counters.gpu_ms,
            passes_ms: counters.passes_ms,
            gpu_drawn: counters.drawn,
            gpu_outline: counters.outline,
            eps: frame.eps,
            coarsened: frame.coarsened,
            plan_ms: frame.plan_ms,
            gpu_placed: counters.far.map(|f| f.visible),
        }
    }
}

pub struct Renderer {
    pub gpu: Gpu,
    /// Bind group 0 of every pass: the frame uniform.
    frame_layout: wgpu::BindGroupLayout,
    cull: CullPass,
    splats: SplatPasses,
    raster: ComputeRaster,
    mesh: MeshPass,
    shading: ShadingPass,
    /// The passes of far instances, made with a scene's first upload.
    far: std::sync::OnceLock<super::far::FarPass>,
    /// One thread for a scene's plan on a CPU adapter ([`Renderer::planning`]).
    plan_thread: Option<rayon::ThreadPool>,
}

impl Renderer {
    pub fn new(gpu: Gpu) -> Renderer {
        let device = &gpu.device;
        let frame_layout = frame_layout(device);
        Renderer {
            cull: CullPass::new(device, &frame_layout),
            splats: SplatPasses::new(&gpu, &frame_layout),
            raster: ComputeRaster::new(device, &frame_layout, gpu.on_cpu()),
            mesh: MeshPass::new(device, &frame_layout),
            shading: ShadingPass::new(device, &frame_layout),
            far: std::sync::OnceLock::new(),
            plan_thread: gpu.on_cpu().then(one_thread).flatten(),
            frame_layout,
            gpu,
        }
    }

    /// Runs a frame's plan: on rayon's pool, or on a thread of its own on a CPU
    /// adapter. There the rasterizer's threads still hold the cores when the frame
    /// after is planned, and a plan split over the pool's threads waits on whichever
    /// was preempted: the forest's fly-through planned in 2–8 ms on 2 cores (65
    /// involuntary context switches in one plan) against 1.0–1.7 ms on one thread
    /// (docs/scenes.md).
    pub(super) fn planning<R: Send>(&self, plan: impl FnOnce() -> R + Send) -> R {
        match &self.plan_thread {
            Some(pool) => pool.install(plan),
            None => plan(),
        }
    }

    /// Targets for frames of `size`, checked against the adapter's limits.
    pub fn targets(&self, size: (u32, u32)) -> anyhow::Result<FrameTargets> {
        let device = &self.gpu.device;
        check_size(&device.limits(), size)?;
        let gbuffer = GBuffer::new(device, size, self.gpu.compute_raster);
        let binds = [
            self.shading.bind(device, &gbuffer, &gbuffer.depth_view),
            self.splats
                .depth_bind(device, &gbuffer, self.gpu.read_only_depth),
        ];
        Ok(FrameTargets::new(
            &self.gpu,
            size,
            &self.frame_layout,
            (gbuffer, binds),
        ))
    }

    /// Records one frame of `scene` into `encoder`, drawing into `targets.output`. The
    /// frame uniform and the compaction records are written through the queue, so they
    /// take effect at the next submit.
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
        let rasterized = self.rasterized(settings, targets.size)?;
        let compute =
            (settings.culling == Culling::Compute || rasterized) && settings.mode != Mode::Mesh;
        let trim = self.prefix_cut(settings.prefix_cut) == PrefixCut::Node;
        let frame = plan(
            scene,
            camera,
            settings,
            targets.size,
            gpu_scene,
            (compute, trim),
        );
        let uniform = FrameUniform::new(scene.meta(), camera, settings, targets.size, frame.eps);
        let queue = &self.gpu.queue;
        queue.write_buffer(&targets.frame_buffer, 0, bytemuck::bytes_of(&uniform));
        let meta = scene.meta();
        let alone = Placement::alone(meta.origin.into(), camera.eye, meta.error_scale);
        queue.write_buffer(&gpu_scene.placements, 0, bytemuck::bytes_of(&alone));
        let shares = gpu_scene.shares(&frame.ranges);
        let mesh = gpu_scene.mesh.as_ref();
        self.encode_passes(
            encoder,
            targets,
            (&shares, &[]),
            settings,
            (compute, rasterized, mesh),
        );
        Ok(frame)
    }

    /// Records the passes of a frame planned into `shares`: culling (`compute`), the
    /// splat passes in compute (`rasterized`) or through the raster pipeline (or the
    /// `mesh`, in mesh mode), shading, and the timestamps' resolve.
    pub(super) fn encode_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        (shares, far): (&[super::gpu_scene::Share], &[super::far::FarDraw]),
        settings: &Settings,
        (compute, rasterized, mesh): (bool, bool, Option<&super::gpu_scene::MeshBuffers>),
    ) {
        let start = targets.compute_timestamps(Some(stamp::START), None);
        if compute {
            let queue = &self.gpu.queue;
            self.cull
                .encode(queue, encoder, &targets.frame_bind, shares, start);
        }
        if !far.is_empty() {
            self.far_pass().encode(encoder, &targets.frame_bind, far);
        }
        if rasterized {
            let binds = self.compute_binds(targets);
            let (accumulation, outputs) = (&binds.accumulation, binds.outputs.as_ref());
            self.raster
                .encode(encoder, targets, accumulation, shares, settings.mode);
            self.shading
                .encode(encoder, targets, &binds.gbuffer, outputs);
        } else {
            self.encode_hardware(encoder, targets, shares, settings, mesh);
        }
        if let Some((set, resolve)) = &targets.queries {
            encoder.resolve_query_set(set, 0..stamp::COUNT, resolve, 0);
        }
    }

    /// The passes of far instances (`far.rs`).
    pub(super) fn far_pass(&self) -> &super::far::FarPass {
        self.far.get_or_init(|| {
            super::far::FarPass::new(&self.gpu.device, &self.frame_layout, &self.cull.layout)
        })
    }

    /// The way `asked` draws on this adapter: [`Raster::Auto`] is compute
    /// rasterization on a GPU that has it (on an H100 the raster pipeline runs on 2 of
    /// 66 TPCs), the raster pipeline on a CPU adapter (on lavapipe it drew the default
    /// model in the viewer's 1024×768 window in 270 ms against compute's 662 ms;
    /// docs/gpu.md).
    pub fn raster(&self, asked: Raster) -> Raster {
        let gpu = &self.gpu;
        match asked {
            Raster::Auto if gpu.compute_raster && !gpu.on_cpu() => Raster::Compute,
            Raster::Auto => Raster::Hardware,
            chosen => chosen,
        }
    }

    /// The cut `asked` makes on this adapter: [`PrefixCut::Auto`] ends each prefix at
    /// its node on a CPU adapter only, at its block on a GPU. Trimming costs the CPU a binary search in each prefix's last block
    /// of nodes (memory-mapped, mostly cache misses: about 0.4 µs a chunk, 11.6 ms on one
    /// core for the prefixes of a 200 M-point tile seen whole; docs/viewer.md) and saves
    /// the GPU's test of at most 63 nodes per chunk: a few nanoseconds on a GPU, about as
    /// much as the search on a CPU adapter, whose culling runs on the same cores.
    pub fn prefix_cut(&self, asked: PrefixCut) -> PrefixCut {
        match asked {
            PrefixCut::Auto if self.gpu.on_cpu() => PrefixCut::Node,
            PrefixCut::Auto => PrefixCut::Block,
            chosen => chosen,
        }
    }

    /// Whether `settings` draw the splat passes of a `size` frame in compute: an error
    /// where they ask for it and the adapter cannot (no storage textures of the
    /// G-buffer's formats, or per-pixel buffers larger than it binds); [`Raster::Auto`]
    /// then draws through the raster pipeline.
    pub(super) fn rasterized(&self, settings: &Settings, size: (u32, u32)) -> anyhow::Result<bool> {
        let chosen = self.raster(settings.raster) == Raster::Compute && settings.mode != Mode::Mesh;
        if !chosen {
            return Ok(false);
        }
        let fits = self.raster.check_size(size);
        if settings.raster == Raster::Auto {
            return Ok(fits.is_ok());
        }
        if !self.gpu.compute_raster {
            anyhow::bail!(
                "this adapter ({}) cannot draw the splats in compute (no storage textures \
                 of the G-buffer's formats): use --raster hardware",
                self.gpu.info.name
            );
        }
        fits.map(|()| true)
    }

    /// What `targets`' frames drawn in compute bind ([`ComputeBinds`]), made at the
    /// first call.
    fn compute_binds<'t>(&self, targets: &'t FrameTargets) -> &'t ComputeBinds {
        targets.compute.get_or_init(|| {
            let g = &targets.gbuffer;
            let accumulation = self.raster.accumulation(g, targets.size);
            let device = &self.gpu.device;
            ComputeBinds {
                gbuffer: self.shading.bind(device, g, &accumulation.depth_view),
                outputs: self.shading.bind_outputs(targets),
                accumulation,
            }
        })
    }

    /// The splat passes (or the mesh) through the raster pipeline, between the
    /// G-buffer's clear and pass 3.
    fn encode_hardware(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        shares: &[super::gpu_scene::Share],
        settings: &Settings,
        mesh: Option<&super::gpu_scene::MeshBuffers>,
    ) {
        let compute = settings.culling == Culling::Compute && settings.mode != Mode::Mesh;
        let g = &targets.gbuffer;
        // Each timestamp is written once: the modes without pass 1 end it with the clear.
        // The frame starts with the cull pass where there is one (it writes START).
        let one_pass = matches!(settings.mode, Mode::Mesh | Mode::Points);
        let clear_end = one_pass.then_some(stamp::VISIBILITY_END);
        let clear_start = (!compute).then_some(stamp::START);
        let clear_stamps = targets.timestamps(clear_start, clear_end);
        g.pass(encoder, "clear", Writes::All, true, clear_stamps);
        match (settings.mode, mesh) {
            (Mode::Mesh, Some(mesh)) => {
                let stamps = targets.timestamps(None, Some(stamp::ATTRIBUTES_END));
                self.mesh
                    .encode(encoder, g, &targets.frame_bind, mesh, stamps)
            }
            _ => self
                .splats
                .encode(encoder, targets, shares, settings.mode, compute),
        }
        self.shading
            .encode(encoder, targets, &targets.gbuffer_bind, None);
    }

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
                ops: store(wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 })),
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
    }

    /// Uploads a scene's list (once, in binding-size slices) and mesh.
    pub fn upload(&self, scene: &Scene) -> GpuScene {
        self.upload_reporting(scene, &Silent)
    }

    /// [`Renderer::upload`], telling `report` the nodes uploaded, slice by slice.
    pub fn upload_reporting(&self, scene: &Scene, report: &dyn Report) -> GpuScene {
        let nodes = scene.nodes();
        report.step(Step::Upload, nodes.len() as u64);
        let mut gpu_scene = self.empty_gpu_scene(scene, None);
        let home = gpu_scene.home();
        for k in 0..gpu_scene.planned_slices() {
            let range = gpu_scene.slice_range(k);
            report.advance(range.len() as u64);
            gpu_scene.insert(self.upload_slice(scene, &home, k, range));
        }
        if let Some(mesh) = self.upload_mesh(scene) {
            gpu_scene.set_mesh(mesh);
        }
        gpu_scene
    }

    /// A scene's list with nothing uploaded yet, planned in slices for a GPU memory
    /// `budget` (bytes) or, without one, in the largest slices a binding holds.
    pub fn empty_gpu_scene(&self, scene: &Scene, budget: Option<u64>) -> GpuScene {
        let total = scene.nodes().len();
        upload::empty_gpu_scene(&self.gpu, total, budget, scene.meta().has_attributes, None)
    }

    /// Uploads slice `k` of a scene's list, the node `range` of the plan of
    /// [`Renderer::empty_gpu_scene`] ([`GpuScene::slice_range`]), into `home`
    /// ([`GpuScene::home`]).
    pub fn upload_slice(
        &self,
        scene: &Scene,
        home: &SliceHome,
        k: usize,
        range: std::ops::Range<usize>,
    ) -> SliceUpload {
        let attributes = scene.attributes().get(range.clone()).unwrap_or(&[]);
        let max_ranges = upload::max_ranges(scene, &range);
        let slice = (
            &scene.nodes()[range.clone()],
            &scene.shapes()[range.clone()],
            attributes,
        );
        upload::upload_slice(
            &self.gpu.device,
            (&self.splats, &self.cull, &self.raster),
            (k, range.start),
            slice,
            (&home.placements, home.room),
            max_ranges,
        )
    }

    /// Uploads the mesh reference of a scene that has one.
    pub fn upload_mesh(&self, scene: &Scene) -> Option<MeshUpload> {
        let mesh = scene.mesh.as_ref()?;
        Some(MeshUpload(MeshPass::upload(&self.gpu.device, mesh)))
    }

    /// Renders one frame and reads it back, with its statistics. `selected` is the CPU
    /// reference count of the selection test (O(prefix)); the viewer skips it.
    pub fn render(
        &self,
        scene: &Scene,
        gpu_scene: &GpuScene,
        camera: &Camera,
        settings: &Settings,
        width: u32,
        height: u32,
    ) -> anyhow::Result<(Image, FrameStats)> {
        let targets = self.targets((width, height))?;
        self.render_into(&targets, scene, gpu_scene, camera, settings)
    }

    /// [`Renderer::render`] into targets kept by the caller.
    pub fn render_into(
        &self,
        targets: &FrameTargets,
        scene: &Scene,
        gpu_scene: &GpuScene,
        camera: &Camera,
        settings: &Settings,
    ) -> anyhow::Result<(Image, FrameStats)> {
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        let frame = self.encode(&mut encoder, targets, scene, gpu_scene, camera, settings)?;
        let (image, counters) = self.read_frame(encoder, targets, &[gpu_scene], &frame)?;
        let meta = scene.meta();
        let nodes = scene.nodes();
        let selected = frame
            .ranges
            .par_iter()
            .flat_map(|r| nodes[r.clone()].par_iter())
            .filter(|r| is_drawn(r, meta.error_scale, frame.lod_eye, frame.eps))
            .count();
        let chunks = (scene.index.chunks().len(), frame.ranges.len());
        Ok((image, FrameStats::of(&frame, &counters, chunks, selected)))
    }

    /// Submits `encoder` (a frame recorded into `targets`) and reads the frame back:
    /// the output, pass 3's covered mask, the depth (from the colour and normal sums'
    /// weights and view distances) and the counters of `gpu_scenes`' slices.
    pub(super) fn read_frame(
        &self,
        mut encoder: wgpu::CommandEncoder,
        targets: &FrameTargets,
        gpu_scenes: &[&GpuScene],
        frame: &EncodedFrame,
    ) -> anyhow::Result<(Image, super::GpuCounters)> {
        let device = &self.gpu.device;
        let g = &targets.gbuffer;
        let out_buffer = readback::copy_texture(device, &mut encoder, &targets.output, 4);
        let covered_buffer = readback::copy_texture(device, &mut encoder, &targets.covered, 4);
        let weight_buffer = readback::copy_texture(device, &mut encoder, &g.color_sum, 8);
        let normal_buffer = readback::copy_texture(device, &mut encoder, &g.normal_sum, 8);
        let counters = read_counters_now(&self.gpu, encoder, targets, gpu_scenes, frame)?;
        let (width, height) = targets.size;
        let rgba = readback::unpad_rgba8(&readback::read(device, &out_buffer)?, width, height);
        let covered = readback::mask(&readback::read(device, &covered_buffer)?, width, height);
        let weights = readback::read(device, &weight_buffer)?;
        let normals = readback::read(device, &normal_buffer)?;
        let depth = readback::depth(&weights, &normals, width, height);
        let image = Image {
            width,
            height,
            rgba,
            covered,
            depth,
        };
        Ok((image, counters))
    }

    /// Reads back the shaded pixels last drawn into `targets` (RGBA8, sRGB), with
    /// whatever was drawn over them (the viewer's panel).
    pub fn read_output(&self, targets: &FrameTargets) -> anyhow::Result<Vec<u8>> {
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        let buffer = readback::copy_texture(device, &mut encoder, &targets.output, 4);
        self.gpu.queue.submit([encoder.finish()]);
        let (width, height) = targets.size;
        Ok(readback::unpad_rgba8(
            &readback::read(device, &buffer)?,
            width,
            height,
        ))
    }
}

/// A pool of one thread (None where the system gives none: the plan then runs on
/// rayon's own).
fn one_thread() -> Option<rayon::ThreadPool> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1);
    pool.thread_name(|_| "spt-plan".into()).build().ok()
}
