//! One configuration of `spt bench` measured over its cameras: warm-up frames, then
//! timed frames (GPU timestamps and wall time), the splats drawn, the nodes tested, and the
//! last frame's error against the reference images of the same camera: PSNR, hole and
//! spill rates against the reference at 1×, FLIP and SSIM against it supersampled.

use std::time::Instant;

use indicatif::ProgressBar;

use crate::apps::stats::quantile;
use crate::eval::metrics::compare;
use crate::eval::perceptual::{flip_mean, ssim_mean};
use crate::render::{Camera, FrameTargets, GpuScene, Image, Renderer, Settings};
use crate::tree::scene::Scene;

/// How many frames, and where progress goes.
pub struct Frames<'a> {
    pub warmup: u32,
    pub timed: u32,
    pub progress: &'a ProgressBar,
}

/// The reference of one camera: the mesh (or, for point clouds, the leaves) at 1×,
/// and rendered at 4×4 the size, averaged in linear light (antialiased).
pub struct Reference {
    pub aliased: Image,
    pub antialiased: Image,
}

/// What one configuration measured, over all its cameras.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Measured {
    /// Splats drawn per frame: the GPU's count with compute culling, else the CPU
    /// reference of the same test; mean over the cameras.
    pub splats: f64,
    /// Nodes the GPU tested per frame (the visible chunks' prefixes), mean.
    pub tested: f64,
    /// Over every timed frame of every camera.
    pub gpu_ms_median: Option<f64>,
    pub gpu_ms_p95: Option<f64>,
    /// Submit to read-back done, per frame.
    pub wall_ms_median: f64,
    /// Means over the cameras of [`crate::eval::metrics::Comparison`]'s figures.
    pub psnr_db: f64,
    pub hole_rate: f64,
    pub spill_rate: f64,
    /// Means over the cameras of FLIP and SSIM against the antialiased reference.
    pub flip: f64,
    pub ssim: f64,
}

/// Draws `frames` of each camera with `settings` and measures them against
/// `references` (one per camera).
pub fn measure(
    renderer: &Renderer,
    targets: &FrameTargets,
    scene: (&Scene, &GpuScene),
    cameras: &[Camera],
    settings: &Settings,
    references: &[Reference],
    frames: &Frames,
) -> anyhow::Result<Measured> {
    let runs = measure_runs(
        renderer, targets, scene, cameras, settings, references, frames, 1,
    )?;
    Ok(runs.into_iter().next().expect("one run"))
}

/// [`measure`] for `runs` runs of the same configuration whose timed frames alternate
/// (run 1, run 2, …, run 1, …), so that a slow spell of the machine falls on all of
/// them alike and what differs between them is the renderer's own variation.
#[allow(clippy::too_many_arguments)]
pub fn measure_runs(
    renderer: &Renderer,
    targets: &FrameTargets,
    (scene, gpu_scene): (&Scene, &GpuScene),
    cameras: &[Camera],
    settings: &Settings,
    references: &[Reference],
    frames: &Frames,
    runs: usize,
) -> anyhow::Result<Vec<Measured>> {
    let mut gpu_ms = vec![Vec::new(); runs];
    let mut wall_ms = vec![Vec::new(); runs];
    let mut measured = vec![Measured::default(); runs];
    for (camera, reference) in cameras.iter().zip(references) {
        let mut last = vec![None; runs];
        for k in 0..frames.warmup + frames.timed {
            for run in 0..runs {
                let start = Instant::now();
                let frame = renderer.render_into(targets, scene, gpu_scene, camera, settings)?;
                if k >= frames.warmup {
                    wall_ms[run].push(start.elapsed().as_secs_f64() * 1e3);
                    gpu_ms[run].extend(frame.1.gpu_ms);
                }
                frames.progress.inc(1);
                last[run] = Some(frame);
            }
        }
        for (m, frame) in measured.iter_mut().zip(last) {
            let (image, stats) = frame.expect("at least one frame");
            m.splats += stats.gpu_drawn.map_or(stats.selected as f64, |d| d as f64);
            m.tested += stats.tested as f64;
            let c = compare(&image, &reference.aliased);
            m.flip += flip_mean(&image, &reference.antialiased);
            m.ssim += ssim_mean(&image, &reference.antialiased);
            m.psnr_db += c.psnr_db.min(PSNR_CAP_DB);
            m.hole_rate += c.hole_rate;
            m.spill_rate += c.spill_rate;
        }
    }
    let n = cameras.len().max(1) as f64;
    for (run, m) in measured.iter_mut().enumerate() {
        m.splats /= n;
        m.tested /= n;
        m.psnr_db /= n;
        m.hole_rate /= n;
        m.spill_rate /= n;
        m.flip /= n;
        m.ssim /= n;
        m.gpu_ms_median = quantile(&mut gpu_ms[run], 0.5);
        m.gpu_ms_p95 = quantile(&mut gpu_ms[run], 0.95);
        m.wall_ms_median = quantile(&mut wall_ms[run], 0.5).unwrap_or(0.0);
    }
    Ok(measured)
}

/// PSNR of identical images is infinite; the figures cap it here.
pub const PSNR_CAP_DB: f64 = 99.0;
