//! `spt render MODEL -o out.png`: one frame, headless, with the camera and display
//! options of the viewer; prints what it drew and the GPU time.

use std::path::Path;

use anyhow::Context;

pub use crate::apps::frame_args::RenderArgs;
use crate::apps::stats::Summary;
use crate::apps::text::count;
use crate::render::{Gpu, Renderer};
use crate::tree::report::Silent;
use crate::tree::scene::Scene;
use crate::tree::select::error_per_distance;

pub fn run(model: &Path, output: &Path, args: &RenderArgs) -> anyhow::Result<()> {
    crate::io::atomic::check_writable(output, &[model])?;
    let budget = args.gpu_budget();
    let scene = match budget {
        Some(_) => Scene::open_for_streaming(model, &Silent)?,
        None => Scene::open(model)?,
    };
    let camera = args.camera(&scene)?;
    let gpu = Gpu::new(args.backend.as_deref())?;
    say!("adapter   {}", gpu.describe());
    let renderer = Renderer::new(gpu);
    let settings = args.settings();
    let uploaded = match budget {
        None => renderer.upload(&scene),
        Some(bytes) => {
            let (mut uploaded, mut residency) = renderer.begin_streaming(&scene, bytes)?;
            let state = (&mut uploaded, &mut residency);
            renderer.stream_for_view(&scene, state, &camera, &settings, args.size);
            say!(
                "gpu memory {} ({} of {} slices)",
                residency.memory_line(),
                uploaded.resident_slices(),
                uploaded.planned_slices()
            );
            uploaded
        }
    };
    let mut times = FrameTimes::default();
    let mut last = None;
    for _ in 0..args.frames {
        let start = std::time::Instant::now();
        let frame = renderer
            .render(
                &scene,
                &uploaded,
                &camera,
                &settings,
                args.size.0,
                args.size.1,
            )
            .with_context(|| format!("rendering {}", model.display()))?;
        times.add(&frame.1, start);
        last = Some(frame);
    }
    let (image, stats) = last.expect("at least one frame");
    // Under a budget the file was opened without its checks: they run now, before the
    // picture is written.
    scene.check_file()?;
    crate::io::png::write_png(output, image.width, image.height, &image.rgba)?;
    if stats.coarsened {
        let px = stats.eps / error_per_distance(1.0, camera.fov_y, args.size.1);
        say!(
            "lod       coarser than asked: ε = {px:.3} px (the rest of the list is not on the GPU)"
        );
    }
    say!(
        "splats    {} drawn of {} nodes; the GPU tested {} nodes in {} ranges of {} chunks",
        count(stats.selected as u64),
        count(scene.nodes().len() as u64),
        count(stats.tested as u64),
        count(stats.chunks_tested as u64),
        count(stats.chunks as u64),
    );
    if let Some(n) = stats.gpu_drawn {
        say!(
            "culled    {} splats survived the compute culling: {:.2} nodes tested per survivor; \
             {} of them on an outline",
            count(n),
            stats.tested as f64 / n.max(1) as f64,
            count(stats.gpu_outline.unwrap_or(0)),
        );
    }
    say!("raster    {}", renderer.raster(settings.raster).name());
    let plan = times.print(stats.selected);
    let cut = renderer.prefix_cut(settings.prefix_cut).name();
    say!(
        "cpu plan  {plan:.3} ms per frame (median): chunks in view, their prefixes cut at the {cut}"
    );
    say!("wrote     {}", output.display());
    Ok(())
}

/// The times of the frames `spt render` draws: GPU (in all and per pass, where the
/// adapter measures them), wall, and the CPU's plan.
#[derive(Default)]
pub(crate) struct FrameTimes {
    gpu_ms: Vec<f64>,
    passes_ms: [Vec<f64>; 3],
    wall_ms: Vec<f64>,
    plan_ms: Vec<f64>,
}

impl FrameTimes {
    /// A frame's statistics, the frame having started at `start`.
    pub fn add(&mut self, stats: &crate::render::FrameStats, start: std::time::Instant) {
        self.wall_ms.push(start.elapsed().as_secs_f64() * 1e3);
        self.plan_ms.push(stats.plan_ms);
        self.gpu_ms.extend(stats.gpu_ms);
        for (all, ms) in self
            .passes_ms
            .iter_mut()
            .zip(stats.passes_ms.into_iter().flatten())
        {
            all.push(ms);
        }
    }

    /// Prints the times ([`print_times`], for `selected` splats); returns the median
    /// CPU plan, ms.
    pub fn print(mut self, selected: usize) -> f64 {
        print_times(
            &mut self.gpu_ms,
            self.passes_ms,
            &mut self.wall_ms,
            selected,
        );
        Summary::of(&mut self.plan_ms).map_or(0.0, |s| s.median)
    }
}

/// Prints the frames' GPU time (in all and per pass, where the adapter measures it),
/// the GPU's splat rate for `selected` splats, and the wall time.
fn print_times(
    gpu_ms: &mut Vec<f64>,
    passes_ms: [Vec<f64>; 3],
    wall_ms: &mut Vec<f64>,
    selected: usize,
) {
    let summary = |v: &mut Vec<f64>| match Summary::of(v) {
        Some(s) if s.count > 1 => format!(
            "{:.3} ms (median of {}), p95 {:.3} ms",
            s.median, s.count, s.p95
        ),
        _ => format!("{:.3} ms", v.first().copied().unwrap_or(0.0)),
    };
    match Summary::of(gpu_ms) {
        None => say!("gpu time  not measured (the adapter has no timestamp queries)"),
        Some(s) => {
            say!("gpu time  {}", summary(gpu_ms));
            let [visibility, attributes, shading] =
                passes_ms.map(|mut v| Summary::of(&mut v).map_or(0.0, |s| s.median));
            say!(
                "passes    visibility {visibility:.3} ms, attributes {attributes:.3} ms, \
                 shading {shading:.3} ms (medians)"
            );
            say!(
                "rate      {:.3} M splats/s (GPU)",
                selected as f64 / s.median / 1e3
            );
        }
    }
    say!(
        "wall time {} per frame (read-back included)",
        summary(wall_ms)
    );
}
