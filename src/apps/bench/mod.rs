//! `spt bench MODEL --out DIR`: speed against error (docs/design.md §9). For each camera path
//! (orbits near, mid and far, and a fly-through into the model) and each ε of the sweep,
//! SPT with both culling strategies; at the orbits, a random subset of leaves with as
//! many splats drawn as SPT drew; leaves only (no LOD) at ε = 0. Each configuration:
//! warm-up frames, timed frames (GPU timestamps, wall), splats, nodes tested, and PSNR, hole
//! and spill rates against the mesh (models with faces) or the leaves-only image (point
//! clouds). Then one configuration again, to check that the numbers are stable.
//! Writes `results.csv`, `summary.md` and `speed_vs_error.png`.

mod measure;
mod plan;
mod plot;
mod random_subset;
mod report;
mod scene;

use crate::apps::frame_args::with_up;
use crate::io::up::UpAxis;
use std::path::{Path, PathBuf};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::eval::perceptual::downsample;

use crate::render::{
    Camera, Culling, FrameTargets, Gpu, GpuScene, Mode, Raster, Renderer, Settings,
};
use crate::tree::scene::Scene;
use measure::{Frames, Measured, Reference, measure};
use report::{Environment, Row, Strategy, culling_name};

/// Frames per camera of the stability check's runs, at least.
/// The stability check's runs: warm-up frames per camera, and timed frames in all at
/// least. Frame times on a software rasterizer vary by about 20 % from frame to frame,
/// so a median within a few % takes about a hundred frames.
const STABILITY_WARMUP: u32 = 3;
const STABILITY_SAMPLES: u32 = 120;

/// The options of `spt bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {
    /// The model: a PLY file (mesh or point cloud), a LAS or LAZ file, or an .spt file;
    /// or a scene of instances (a .json file: docs/scenes.md).
    pub model: PathBuf,
    /// Folder for results.csv, summary.md and speed_vs_error.png (made if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Frame size, WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512", value_parser = crate::apps::frame_args::parse_size)]
    pub size: (u32, u32),
    /// Which axis is up, for the orbits (default: the model's; z for a sensor frame).
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub up: Option<UpAxis>,
    /// Cameras per orbit (evenly spaced azimuths, elevation 20°).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub views: u32,
    /// Cameras along the fly-through.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(2..=64))]
    pub fly_steps: u32,
    /// Untimed frames per camera before the timed ones.
    #[arg(long, default_value_t = 2)]
    pub warmup: u32,
    /// Timed frames per camera.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// The ε sweep in pixels, comma-separated (0: leaves only).
    #[arg(long, value_delimiter = ',', default_value = "0,0.25,0.5,1,2,4,8")]
    pub eps: Vec<f64>,
    /// Frame-time budgets in ms, comma-separated: for each, the least FLIP of the sweep
    /// among the ε whose median GPU time (wall time without GPU timing) fits in it.
    #[arg(long, value_delimiter = ',', default_value = "50,100,200,400")]
    pub budget_ms: Vec<f64>,
    /// A short run (2 views, 3 fly-through steps, 1 + 2 frames, ε 0, 1, 4), for checks.
    #[arg(long)]
    pub quick: bool,
    /// GPU backend: vulkan, gl, metal, dx12 or all (default: $SPT_BACKEND, else any).
    #[arg(long)]
    pub backend: Option<String>,
    /// How the splat passes draw (docs/gpu.md; auto: compute on a GPU, hardware on a
    /// CPU adapter). Compute rasterization culls in compute: its sweep has no
    /// vertex-culling rows.
    #[arg(long, value_enum, default_value = "auto")]
    pub raster: Raster,
}

/// How many times larger, in each direction, the antialiased reference is rendered.
const SUPERSAMPLE: u32 = 4;

/// Runs one configuration per call, with the state every run shares.
struct Bench<'a> {
    renderer: &'a Renderer,
    targets: FrameTargets,
    /// Targets [`SUPERSAMPLE`] times the size, for the antialiased references.
    supersampled: FrameTargets,
    frames: Frames<'a>,
    raster: Raster,
}

impl Bench<'_> {
    /// The culling strategies of the sweep: both, or compute culling alone when the
    /// splats are drawn in compute (which culls in compute).
    fn cullings(&self) -> &'static [Culling] {
        match self.raster {
            Raster::Compute => &[Culling::Compute],
            _ => &[Culling::Compute, Culling::Vertex],
        }
    }

    /// The references of each camera: the mesh (or the leaves), at 1× and supersampled.
    fn references(
        &self,
        scene: &Scene,
        gpu_scene: &GpuScene,
        cameras: &[Camera],
    ) -> anyhow::Result<Vec<Reference>> {
        let settings = Settings {
            mode: if gpu_scene.mesh_triangles() > 0 {
                Mode::Mesh
            } else {
                Mode::Shaded
            },
            lod: false,
            ..Settings::default()
        };
        let draw = |targets: &FrameTargets, c: &Camera| {
            self.renderer
                .render_into(targets, scene, gpu_scene, c, &settings)
                .map(|f| f.0)
        };
        cameras
            .iter()
            .map(|c| {
                let aliased = draw(&self.targets, c)?;
                let antialiased = downsample(&draw(&self.supersampled, c)?, SUPERSAMPLE);
                self.frames.progress.inc(1);
                Ok(Reference {
                    aliased,
                    antialiased,
                })
            })
            .collect()
    }

    fn run(
        &self,
        scene: (&Scene, &GpuScene),
        cameras: &[Camera],
        references: &[Reference],
        eps_px: f64,
        culling: Culling,
    ) -> anyhow::Result<Measured> {
        let settings = sweep_settings(eps_px, culling, self.raster);
        measure(
            self.renderer,
            &self.targets,
            scene,
            cameras,
            &settings,
            references,
            &self.frames,
        )
    }
}

/// The settings of one point of the sweep: ε in pixels (0: leaves only), culling and
/// raster path.
fn sweep_settings(eps_px: f64, culling: Culling, raster: Raster) -> Settings {
    Settings {
        error_px: eps_px,
        lod: eps_px > 0.0,
        culling,
        raster,
        ..Settings::default()
    }
}

/// Today's date (UTC), YYYY-MM-DD, from the system clock.
fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!("{y:04}-{m:02}-{d:02}")
}

/// `--quick` applied and the sweep checked.
fn effective_args(args: &BenchArgs) -> anyhow::Result<BenchArgs> {
    let mut args = args.clone();
    if args.quick {
        (args.views, args.fly_steps, args.warmup, args.frames) = (2, 3, 1, 2);
        args.eps = vec![0.0, 1.0, 4.0];
    }
    if args.eps.iter().any(|e| !e.is_finite() || *e < 0.0) {
        anyhow::bail!("--eps: every ε must be a finite number ≥ 0");
    }
    if args.budget_ms.iter().any(|b| !b.is_finite() || *b <= 0.0) {
        anyhow::bail!("--budget-ms: every budget must be a finite number of ms > 0");
    }
    Ok(args)
}

/// What labels the results: model, reference, adapter, machine and date.
fn environment(args: &BenchArgs, scene: &Scene, gpu: &Gpu) -> Environment {
    Environment {
        model: args.model.file_name().map_or_else(
            || args.model.display().to_string(),
            |n| n.to_string_lossy().to_string(),
        ),
        reference: if scene.mesh.is_some() {
            "mesh"
        } else {
            "leaves-only image"
        },
        adapter: gpu.info.name.clone(),
        backend: format!("{:?}", gpu.info.backend),
        driver: format!("{} {}", gpu.info.driver, gpu.info.driver_info),
        machine: report::machine(),
        date: today(),
        size: args.size,
        raster: args.raster.name(),
    }
}

/// The camera paths: the three orbits, then the fly-through.
fn camera_paths(scene: &Scene, args: &BenchArgs) -> Vec<(String, Vec<Camera>)> {
    let (meta, fov) = (&with_up(scene.meta(), args.up), 45f64.to_radians());
    let mut paths: Vec<(String, Vec<Camera>)> = plan::ORBITS
        .iter()
        .map(|(name, fill)| {
            (
                format!("orbit-{name}"),
                plan::orbit(meta, *fill, args.views as usize, fov),
            )
        })
        .collect();
    paths.push((
        "fly-through".into(),
        plan::fly_through(meta, args.fly_steps as usize, fov),
    ));
    paths
}

/// A progress bar over every frame the run will draw: references, SPT (each culling),
/// random subsets (orbits, ε > 0) and the stability check.
fn frame_progress(args: &BenchArgs, paths: &[(String, Vec<Camera>)]) -> ProgressBar {
    let per_camera = (args.warmup + args.frames) as u64;
    let cams: u64 = paths.iter().map(|p| p.1.len() as u64).sum();
    let orbit_cams = args.views as u64 * 3;
    let positive = args.eps.iter().filter(|e| **e > 0.0).count() as u64;
    let cullings = match args.raster {
        Raster::Compute => 1,
        _ => 2,
    };
    let total = cams
        + cams * args.eps.len() as u64 * cullings * per_camera
        + orbit_cams * positive * per_camera
        + 2 * args.views as u64
            * (args.warmup.max(STABILITY_WARMUP)
                + args.frames.max(STABILITY_SAMPLES.div_ceil(args.views))) as u64;
    let progress = ProgressBar::with_draw_target(
        Some(total),
        if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    progress.set_style(
        ProgressStyle::with_template("{msg:>28} [{bar:40}] {pos}/{len} frames {elapsed} ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    progress
}

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    if crate::tree::instances::is_scene(&args.model) {
        return scene::run(args);
    }
    let mut args = effective_args(args)?;
    let scene = Scene::open(&args.model)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot make the folder", args.out.display()))?;
    let renderer = Renderer::new(Gpu::new(args.backend.as_deref())?);
    args.raster = renderer.raster(args.raster);
    let env = environment(&args, &scene, &renderer.gpu);
    say!("adapter   {}", env.label());
    let gpu_scene = renderer.upload(&scene);
    let paths = camera_paths(&scene, &args);
    let progress = frame_progress(&args, &paths);
    let bench = Bench {
        renderer: &renderer,
        targets: renderer.targets(args.size)?,
        supersampled: renderer.targets((args.size.0 * SUPERSAMPLE, args.size.1 * SUPERSAMPLE))?,
        frames: Frames {
            warmup: args.warmup,
            timed: args.frames,
            progress: &progress,
        },
        raster: args.raster,
    };
    let leaves = random_subset::leaves(&scene);
    let mut rows: Vec<Row> = Vec::new();
    let mut mid_refs = Vec::new();
    for (path, cameras) in &paths {
        progress.set_message(format!("{path}: references"));
        let references = bench.references(&scene, &gpu_scene, cameras)?;
        let sweep = Sweep {
            bench: &bench,
            scene: (&scene, &gpu_scene),
            leaves: &leaves,
            path,
            cameras,
            references: &references,
        };
        sweep.run(&args.eps, &mut rows)?;
        if path == "orbit-mid" {
            mid_refs = references;
        }
    }
    let (checks, stable) = stability_runs(
        &bench,
        (&scene, &gpu_scene),
        &paths,
        &mid_refs,
        &args,
        &rows,
    )?;
    progress.finish_and_clear();
    for c in &checks {
        say!("stability {c}");
    }
    write_results(&args.out, &env, &rows, &checks, &args.budget_ms)?;
    if !stable {
        anyhow::bail!(
            "the numbers are not stable between two runs of the same configuration (see summary.md)"
        );
    }
    Ok(())
}

/// One camera path's sweep: SPT at every ε with both cullings, and at the orbits a
/// random subset of leaves as large as what SPT drew.
struct Sweep<'a> {
    bench: &'a Bench<'a>,
    scene: (&'a Scene, &'a GpuScene),
    leaves: &'a [(crate::tree::NodeRecord, crate::surfel::shape::SplatShape)],
    path: &'a str,
    cameras: &'a [Camera],
    references: &'a [Reference],
}

impl Sweep<'_> {
    fn row(&self, strategy: Strategy, culling: Culling, eps_px: f64, m: Measured) -> Row {
        let row = Row {
            path: self.path.to_owned(),
            strategy,
            culling,
            eps_px,
            cameras: self.cameras.len(),
            m,
        };
        print_row(&row);
        row
    }

    fn run(&self, eps: &[f64], rows: &mut Vec<Row>) -> anyhow::Result<()> {
        let progress = self.bench.frames.progress;
        let mut leaves_drawn = None;
        for &eps_px in eps {
            let strategy = if eps_px == 0.0 {
                Strategy::NoLod
            } else {
                Strategy::Spt
            };
            let mut spt_drawn = 0.0;
            for &culling in self.bench.cullings() {
                let what = format!("{}: spt ε {eps_px} {}", self.path, culling_name(culling));
                progress.set_message(what);
                let mut m =
                    self.bench
                        .run(self.scene, self.cameras, self.references, eps_px, culling)?;
                if culling == Culling::Compute {
                    spt_drawn = m.splats;
                    leaves_drawn = leaves_drawn.or((eps_px == 0.0).then_some(m.splats));
                } else {
                    // Vertex culling drops the same splats by the same test
                    // (`splat_visible`), but only compute culling counts them.
                    m.splats = spt_drawn;
                }
                rows.push(self.row(strategy, culling, eps_px, m));
            }
            if eps_px > 0.0 && self.path.starts_with("orbit") {
                let m = self.random_subset(eps_px, spt_drawn, leaves_drawn)?;
                rows.push(self.row(Strategy::Random, Culling::Compute, eps_px, m));
            }
        }
        Ok(())
    }

    /// A random subset of leaves drawing as many splats as SPT drew (`spt_drawn`): drawn
    /// from all leaves, of which a share (`leaves_drawn` of all) passes the frustum at
    /// these cameras.
    fn random_subset(
        &self,
        eps_px: f64,
        spt_drawn: f64,
        leaves_drawn: Option<f64>,
    ) -> anyhow::Result<Measured> {
        let visible = leaves_drawn
            .map_or(1.0, |d| d / self.leaves.len().max(1) as f64)
            .clamp(1e-6, 1.0);
        let n = (spt_drawn / visible).round() as usize;
        let meta = self.scene.0.meta();
        let subset = random_subset::random_subset(meta, self.leaves, n, 0x5EED ^ n as u64);
        let subset_gpu = self.bench.renderer.upload(&subset);
        self.bench
            .frames
            .progress
            .set_message(format!("{}: random ε {eps_px}", self.path));
        self.bench.run(
            (&subset, &subset_gpu),
            self.cameras,
            self.references,
            0.0,
            Culling::Compute,
        )
    }
}

/// Stability: the mid orbit at ε = 1 px (or the sweep's nearest), compute culling,
/// twice more, their frames interleaved; their splat counts must also equal the
/// sweep's. Returns the findings and whether they hold.
fn stability_runs(
    bench: &Bench,
    scene: (&Scene, &GpuScene),
    paths: &[(String, Vec<Camera>)],
    mid_refs: &[Reference],
    args: &BenchArgs,
    rows: &[Row],
) -> anyhow::Result<(Vec<String>, bool)> {
    let eps_check = args
        .eps
        .iter()
        .copied()
        .min_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))
        .unwrap_or(1.0);
    let progress = bench.frames.progress;
    progress.set_message("stability: twice again".to_string());
    let mid = &paths[1].1;
    // Enough frames for a steady median, even in a --quick run.
    let frames = Frames {
        warmup: args.warmup.max(STABILITY_WARMUP),
        timed: args.frames.max(STABILITY_SAMPLES.div_ceil(args.views)),
        progress,
    };
    let settings = sweep_settings(eps_check, Culling::Compute, bench.raster);
    let mut again = measure::measure_runs(
        bench.renderer,
        &bench.targets,
        scene,
        mid,
        &settings,
        mid_refs,
        &frames,
        2,
    )?;
    let (twice, once) = (
        again.pop().expect("two runs"),
        again.pop().expect("two runs"),
    );
    let swept = rows
        .iter()
        .find(|r| r.path == "orbit-mid" && r.culling == Culling::Compute && r.eps_px == eps_check)
        .expect("measured in the sweep");
    Ok(stability(swept, &once, &twice))
}

/// `results.csv`, `summary.md`, `speed_vs_error.png`, and a note for each budget where
/// the random subset beat SPT.
fn write_results(
    out: &Path,
    env: &Environment,
    rows: &[Row],
    checks: &[String],
    budgets: &[f64],
) -> anyhow::Result<()> {
    report::write_csv(&out.join("results.csv"), env, rows)?;
    let summary = report::summary(env, rows, checks) + &report::budget_table(rows, budgets);
    report::write_text(&out.join("summary.md"), &summary)?;
    for (budget, path, best) in report::within_budgets(rows, budgets) {
        say!(
            "budget    {budget} ms, {path}: {}",
            best.map_or("no ε of the sweep fits".into(), |r| format!(
                "FLIP {:.4} at ε {} px ({:.1} ms)",
                r.m.flip,
                r.eps_px,
                report::frame_ms(r)
            ))
        );
    }
    plot::write(&out.join("speed_vs_error.png"), env, rows)?;
    for pair in report::equal_budget_pairs(rows) {
        if report::verdict(pair.0, pair.1) == "**no**" {
            say!(
                "note      {} ε {}: random subset FLIP {:.4} < SPT {:.4} at {:.0} / {:.0} splats",
                pair.0.path,
                pair.0.eps_px,
                pair.1.m.flip,
                pair.0.m.flip,
                pair.1.m.splats,
                pair.0.m.splats
            );
        }
    }
    say!(
        "wrote     {}",
        out.join("{results.csv, summary.md, speed_vs_error.png}")
            .display()
    );
    Ok(())
}

/// Two runs of one configuration, frames interleaved: identical splat counts and nodes tested (also
/// equal to the sweep's), and median GPU times within 10 %. Returns the findings and
/// whether they hold.
fn stability(swept: &Row, once: &Measured, twice: &Measured) -> (Vec<String>, bool) {
    let same = |a: &Measured, b: &Measured| a.splats == b.splats && a.tested == b.tested;
    let counts = same(&swept.m, once) && same(once, twice);
    let mut checks = vec![format!(
        "{} ε {} px, compute culling, run twice more: splats {:.1} and {:.1} (sweep {:.1}), \
         tested {:.1} and {:.1} (sweep {:.1}): {}",
        swept.path,
        swept.eps_px,
        once.splats,
        twice.splats,
        swept.m.splats,
        once.tested,
        twice.tested,
        swept.m.tested,
        if counts { "identical" } else { "DIFFERENT" }
    )];
    let timing = match (once.gpu_ms_median, twice.gpu_ms_median) {
        (Some(a), Some(b)) => {
            let change = (b - a).abs() / a.min(b).max(1e-9);
            checks.push(format!(
                "median GPU ms {a:.3} and {b:.3}: {:.1} % apart ({})",
                change * 100.0,
                if change <= 0.10 {
                    "within 10 %"
                } else {
                    "MORE THAN 10 %"
                }
            ));
            change <= 0.10
        }
        _ => {
            checks.push("no GPU times (no timestamp queries): timing not checked".into());
            true
        }
    };
    (checks, counts && timing)
}

fn print_row(r: &Row) {
    say!(
        "{:<12} {:<7} {:<8} ε {:<5} splats {:>10.0} tested {:>10.0} gpu {:>9} ms  psnr {:>6.2} dB  holes {:.3} %  flip {:.4}",
        r.path,
        r.strategy.name(),
        culling_name(r.culling),
        r.eps_px,
        r.m.splats,
        r.m.tested,
        r.m.gpu_ms_median.map_or("–".into(), |v| format!("{v:.2}")),
        r.m.psnr_db,
        r.m.hole_rate * 100.0,
        r.m.flip
    );
}
