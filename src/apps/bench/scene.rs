//! `spt bench SCENE.json --out DIR`: speed against error for a scene of instances
//! (docs/scenes.md). The model benchmark's camera paths (orbits near, mid and far, and
//! the fly-through) over the scene's box and its ε sweep; each configuration: warm-up
//! and timed frames (GPU timestamps, wall), the CPU's plan, splats drawn, instances
//! drawn, the ε drawn (raised where the survivor room is full), and FLIP against the
//! scene drawn at leaves only where that is affordable (at most [`LEAVES_AFFORDABLE`]
//! leaves in all). Writes `results.csv` and `summary.md`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;

use super::BenchArgs;
use super::plan::{ORBITS, fly_through, orbit};
use crate::apps::stats::quantile;
use crate::eval::perceptual::flip_mean;
use crate::render::{Camera, Gpu, GpuInstances, Image, Renderer, Settings};
use crate::tree::instances::InstancedScene;
use crate::tree::report::Silent;
use crate::tree::select::error_per_distance;

/// Leaves a scene may hold in all (each instance's model's, summed) for its frames at
/// leaves only to serve as the reference.
const LEAVES_AFFORDABLE: u64 = 20_000_000;

/// One configuration's medians over its cameras' timed frames.
struct Row {
    path: String,
    eps_px: f64,
    drawn_eps_px: f64,
    gpu_ms: f64,
    wall_ms: f64,
    plan_ms: f64,
    splats: f64,
    instances: f64,
    flip: Option<f64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    quantile(&mut v, 0.5).unwrap_or(f64::NAN)
}

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let scene = InstancedScene::open(&args.model, &Silent)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot make the folder", args.out.display()))?;
    let renderer = Renderer::new(Gpu::new(args.backend.as_deref())?);
    say!("adapter   {}", renderer.gpu.describe());
    let gpu = renderer.upload_instanced(&scene);
    let leaves: u64 = (scene.models.iter().enumerate())
        .map(|(m, model)| model.meta().leaf_count * scene.count_of(m) as u64)
        .sum();
    let affordable = leaves <= LEAVES_AFFORDABLE;
    let fov = 45f64.to_radians();
    let (views, steps) = if args.quick {
        (2, 3)
    } else {
        (args.views as usize, args.fly_steps as usize)
    };
    let mut paths: Vec<(String, Vec<Camera>)> = ORBITS
        .iter()
        .map(|(name, fill)| {
            (
                format!("orbit-{name}"),
                orbit(&scene.meta, *fill, views, fov),
            )
        })
        .collect();
    paths.push(("fly-through".into(), fly_through(&scene.meta, steps, fov)));
    let eps: Vec<f64> = if args.quick {
        vec![1.0, 4.0]
    } else {
        args.eps.clone()
    };
    let bench = SceneBench {
        renderer: &renderer,
        scene: &scene,
        gpu: &gpu,
        args,
    };
    let mut rows = Vec::new();
    for (path, cameras) in &paths {
        let references = match affordable {
            true => Some(bench.references(cameras)?),
            false => None,
        };
        for &e in eps.iter().filter(|&&e| e > 0.0 || affordable) {
            let row = bench.measure(path, cameras, e, references.as_deref())?;
            say!(
                "{path:<12} ε {e:>5} px: {:>10.0} splats, {:>7.0} instances, GPU {:.2} ms, plan {:.2} ms{}",
                row.splats,
                row.instances,
                row.gpu_ms,
                row.plan_ms,
                row.flip.map_or(String::new(), |f| format!(", FLIP {f:.4}"))
            );
            rows.push(row);
        }
    }
    write_results(&args.out, &rows, (&scene, leaves, affordable), &renderer)?;
    say!("wrote     {}", args.out.join("summary.md").display());
    Ok(())
}

struct SceneBench<'a> {
    renderer: &'a Renderer,
    scene: &'a InstancedScene,
    gpu: &'a GpuInstances,
    args: &'a BenchArgs,
}

impl SceneBench<'_> {
    fn frame(
        &self,
        camera: &Camera,
        settings: &Settings,
    ) -> anyhow::Result<(Image, crate::render::FrameStats, usize)> {
        self.renderer
            .render_instanced(self.scene, self.gpu, camera, settings, self.args.size)
    }

    /// Each camera's frame at leaves only.
    fn references(&self, cameras: &[Camera]) -> anyhow::Result<Vec<Image>> {
        let leaves = Settings {
            lod: false,
            ..Settings::default()
        };
        cameras
            .iter()
            .map(|c| Ok(self.frame(c, &leaves)?.0))
            .collect()
    }

    /// The medians of `path`'s cameras at ε = `eps_px` (0: leaves only).
    fn measure(
        &self,
        path: &str,
        cameras: &[Camera],
        eps_px: f64,
        references: Option<&[Image]>,
    ) -> anyhow::Result<Row> {
        let settings = Settings {
            error_px: eps_px,
            lod: eps_px > 0.0,
            raster: self.args.raster,
            ..Settings::default()
        };
        let (mut gpu, mut wall, mut plan, mut splats, mut instances, mut flips, mut drawn) =
            (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
        for (k, camera) in cameras.iter().enumerate() {
            for _ in 0..self.args.warmup {
                self.frame(camera, &settings)?;
            }
            for _ in 0..self.args.frames.max(1) {
                let start = std::time::Instant::now();
                let (image, stats, visible) = self.frame(camera, &settings)?;
                wall.push(start.elapsed().as_secs_f64() * 1e3);
                gpu.extend(stats.gpu_ms);
                plan.push(stats.plan_ms);
                splats.push(stats.gpu_drawn.unwrap_or(0) as f64);
                instances.push(visible as f64);
                let per_px = error_per_distance(1.0, camera.fov_y, self.args.size.1);
                drawn.push(stats.eps / per_px);
                if let Some(r) = references {
                    flips.push(flip_mean(&image, &r[k]));
                }
            }
        }
        Ok(Row {
            path: path.to_string(),
            eps_px,
            drawn_eps_px: median(drawn),
            gpu_ms: median(gpu),
            wall_ms: median(wall),
            plan_ms: median(plan),
            splats: median(splats),
            instances: median(instances),
            flip: references.map(|_| median(flips)),
        })
    }
}

/// `results.csv` and `summary.md` in `out`.
fn write_results(
    out: &Path,
    rows: &[Row],
    (scene, leaves, affordable): (&InstancedScene, u64, bool),
    renderer: &Renderer,
) -> anyhow::Result<()> {
    let mut csv =
        String::from("path,eps_px,drawn_eps_px,gpu_ms,wall_ms,plan_ms,splats,instances,flip\n");
    let mut md = format!(
        "# spt bench: {} instances of {} models\n\nAdapter: {}. {} leaves in all at leaves only{}.\n\n\
         | path | ε px (drawn) | splats | instances | GPU ms | wall ms | CPU plan ms | FLIP vs leaves |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
        scene.instances.len(),
        scene.models.len(),
        renderer.gpu.describe(),
        leaves,
        if affordable {
            ""
        } else {
            " (too many for a reference: no FLIP)"
        }
    );
    for r in rows {
        let flip = r.flip.map_or("–".to_string(), |f| format!("{f:.4}"));
        writeln!(
            csv,
            "{},{},{:.3},{:.3},{:.3},{:.3},{:.0},{:.0},{}",
            r.path,
            r.eps_px,
            r.drawn_eps_px,
            r.gpu_ms,
            r.wall_ms,
            r.plan_ms,
            r.splats,
            r.instances,
            flip
        )?;
        writeln!(
            md,
            "| {} | {} ({:.2}) | {:.0} | {:.0} | {:.2} | {:.2} | {:.2} | {flip} |",
            r.path, r.eps_px, r.drawn_eps_px, r.splats, r.instances, r.gpu_ms, r.wall_ms, r.plan_ms
        )?;
    }
    let write = |name: &str, text: &str| {
        crate::io::atomic::write_atomically(&out.join(name), |w| w.write_all(text.as_bytes()))
    };
    write("results.csv", &csv)?;
    write("summary.md", &md)?;
    Ok(())
}
