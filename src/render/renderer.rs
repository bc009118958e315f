//! The renderer: pipelines made once per device, and offline frames (encode, submit,
//! read back pixels, coverage, depth and counters). The passes themselves are recorded
//! by `encode.rs`; the viewer records them into its own encoder instead.

use rayon::prelude::*;

use super::camera::Camera;
use super::gpu::Gpu;
use super::pipelines::Pipelines;
use super::readback;
use super::settings::{Mode, Settings};
use super::targets::FrameTargets;
use super::upload::GpuScene;
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
        // Read back: the output, the weight channel of the colour sum (coverage) and the
        // blended depth.
        let g = &targets.gbuffer;
        let out_buffer = readback::copy_texture(device, &mut encoder, &targets.output, 4);
        let weight_buffer = readback::copy_texture(device, &mut encoder, &g.color_sum, 8);
        let normal_buffer = readback::copy_texture(device, &mut encoder, &g.normal_sum, 8);
        let counters = self.read_counters_now(encoder, targets, gpu_scene, &frame)?;
        let (width, height) = targets.size;
        let rgba = readback::unpad_rgba8(&readback::read(device, &out_buffer)?, width, height);
        // A pixel counts as covered once it is at least half opaque.
        let coverage_threshold = if settings.mode == Mode::Shaded {
            0.5 * settings.coverage_weight
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
        let meta = scene.meta();
        let selected = scene.nodes()[..frame.prefix_len]
            .par_iter()
            .filter(|r| is_drawn(r, meta.error_scale, frame.lod_eye, frame.eps))
            .count();
        Ok((
            Image {
                width,
                height,
                rgba,
                covered,
                depth,
            },
            FrameStats {
                prefix_len: frame.prefix_len,
                selected,
                gpu_ms: counters.gpu_ms,
                gpu_drawn: counters.drawn,
            },
        ))
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
