//! `spt scatter BASE MODEL… -o SCENE.json`: places instances of the models over a base
//! surface (a mesh's triangles, or a cloud's ground triangulation) at a density per unit
//! area, with random yaw and scale, and writes the instance file and a scene that
//! draws the base once and the instances over it (docs/scenes.md).

use std::path::{Path, PathBuf};

use anyhow::bail;
use clap::Args;
use glam::DVec3;

use crate::apps::text::count;
use crate::io::atomic::check_writable;
use crate::io::formats::read_model;
use crate::io::triangulate;
use crate::tree::instances::scatter::{Spread, Standing, scatter};
use crate::tree::instances::table::write_instances;
use crate::tree::spt_file::{SptFile, is_spt};

#[derive(Args, Debug, Clone)]
pub struct ScatterArgs {
    /// The surface to scatter over: a mesh (its triangles) or a cloud (a terrain: its
    /// Delaunay triangulation in x–y). PLY, LAS or LAZ.
    pub base: PathBuf,
    /// The models to place (PLY, LAS, LAZ or .spt), picked at random for each instance.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// The scene file to write; the instances go beside it, in SCENE.instances.ply.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Instances per unit of surface area (per m² on a metric terrain).
    #[arg(long, default_value_t = 0.01)]
    pub density: f64,
    /// Or this many instances in all, whatever the area (replaces --density).
    #[arg(long, value_name = "N")]
    pub count: Option<usize>,
    /// The file the scene draws as the base (its .spt, say); default BASE itself.
    #[arg(long, value_name = "FILE")]
    pub draw_base: Option<PathBuf>,
    /// Yaw range about z, degrees: MIN,MAX.
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 360.0])]
    pub yaw: Vec<f64>,
    /// Scale range: MIN,MAX.
    #[arg(long, value_delimiter = ',', default_values_t = [0.8, 1.2])]
    pub scale: Vec<f64>,
    /// Leave out ground steeper than this, degrees from level.
    #[arg(long, default_value_t = 35.0)]
    pub max_slope: f64,
    /// Seed of the random placement: the same seed gives the same scene.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

pub fn run(args: &ScatterArgs) -> anyhow::Result<()> {
    let spread = spread(args)?;
    let table = instances_path(&args.output);
    let read: Vec<&Path> = (std::iter::once(&args.base)
        .chain(&args.models)
        .chain(&args.draw_base))
    .map(PathBuf::as_path)
    .collect();
    for written in [&args.output, &table] {
        check_writable(written, &read)?;
    }
    let (positions, triangles) = base_surface(&args.base)?;
    let models: Vec<Standing> = args
        .models
        .iter()
        .map(|m| standing(m))
        .collect::<anyhow::Result<_>>()?;
    let instances = scatter(&positions, &triangles, &models, 1, &spread);
    write_instances(&table, &instances)?;
    let drawn_base = args.draw_base.as_ref().unwrap_or(&args.base);
    write_scene(&args.output, drawn_base, &args.models, &table)?;
    say!(
        "scattered {} instances of {} models over {} triangles of {}",
        count(instances.len() as u64),
        models.len(),
        count(triangles.len() as u64),
        args.base.display()
    );
    say!(
        "wrote     {} and {}",
        args.output.display(),
        table.display()
    );
    Ok(())
}

/// The spread the arguments ask for, checked.
fn spread(args: &ScatterArgs) -> anyhow::Result<Spread> {
    let pair = |v: &[f64], what: &str| match v {
        [a, b] => Ok([*a, *b]),
        _ => Err(anyhow::anyhow!("{what} takes two numbers, MIN,MAX")),
    };
    let (yaw, scale) = (pair(&args.yaw, "--yaw")?, pair(&args.scale, "--scale")?);
    if !(args.density.is_finite() && args.density > 0.0) {
        bail!("--density must be positive");
    }
    if !(scale[0] > 0.0 && scale[0] <= scale[1] && scale[1].is_finite()) {
        bail!("--scale must be MIN,MAX with 0 < MIN ≤ MAX");
    }
    if !(yaw.iter().all(|y| y.is_finite()) && yaw[0] <= yaw[1]) {
        bail!("--yaw must be MIN,MAX degrees with MIN ≤ MAX");
    }
    Ok(Spread {
        density: args.density,
        count: args.count,
        yaw_deg: yaw,
        scale,
        max_slope_deg: args.max_slope,
        seed: args.seed,
    })
}

/// The base's vertices (file coordinates) and triangles: its own, or a terrain's.
fn base_surface(path: &Path) -> anyhow::Result<(Vec<DVec3>, Vec<[u32; 3]>)> {
    let model = read_model(path)?.drawable(path)?;
    let g = &model.geometry;
    let triangles = match g.triangles.is_empty() {
        true => triangulate::terrain(g),
        false => g.triangles.clone(),
    };
    if triangles.is_empty() {
        bail!(
            "{}: no surface to scatter over (no triangles)",
            path.display()
        );
    }
    let positions = g
        .positions
        .iter()
        .map(|p| g.origin + p.as_dvec3())
        .collect();
    Ok((positions, triangles))
}

/// How a model stands: its box and up axis, from an `.spt` file's header or the file.
fn standing(path: &Path) -> anyhow::Result<Standing> {
    let (bounds, up) = if is_spt(path) {
        let meta = SptFile::open(path)?.meta;
        (meta.bounds, meta.up)
    } else {
        let model = read_model(path)?.drawable(path)?;
        (model.geometry.bounds, model.summary.up)
    };
    let up = up.map_or(DVec3::Z, |u| u.vector());
    Ok(Standing::of(bounds.min.into(), bounds.max.into(), up))
}

/// The instance file beside scene `scene`: `NAME.instances.ply`.
pub fn instances_path(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    scene.with_file_name(format!("{stem}.instances.ply"))
}

/// Writes the scene: the base drawn once, then the instance file (models 1…).
fn write_scene(scene: &Path, base: &Path, models: &[PathBuf], table: &Path) -> anyhow::Result<()> {
    let dir = scene.parent().unwrap_or(Path::new("."));
    let named = |p: &Path| -> anyhow::Result<String> {
        let p = std::path::absolute(p)?;
        let dir = std::path::absolute(dir)?;
        Ok(p.strip_prefix(&dir)
            .map_or(p.clone(), Path::to_path_buf)
            .display()
            .to_string())
    };
    let mut paths = vec![named(base)?];
    for m in models {
        paths.push(named(m)?);
    }
    let text = serde_json::json!({
        "models": paths,
        "instances": [{"model": 0}, {"file": named(table)?}],
    });
    let bytes = serde_json::to_vec_pretty(&text)?;
    crate::io::atomic::write_atomically(scene, |w| w.write_all(&bytes))?;
    Ok(())
}
