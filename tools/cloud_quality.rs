//! A face-less cloud's splats against a triangulation of the same points:
//! per view and as medians, FLIP and SSIM of the splats (leaves only, or at
//! `--error-px E` with level of detail), FLIP of the
//! triangulation at 1×, hole rate (see `spt::apps::cloud_quality`); for a sensor frame,
//! FLIP of the same triangulation over the points moved within their depth step. With `--images DIR`,
//! each view's splats, triangulation, reference and the splats' FLIP heat map as PNG. With `--bounds`, also the
//! triangulation's own splats (also against the cloud's splats) and the triangulation
//! shaded with the cloud's normals. With `--write-mesh OUT.ply`, the triangulation
//! written as a mesh.
//!
//! ```text
//! cargo run --release --example cloud_quality -- kinect_rgb.ply --grid 640x480
//! cargo run --release --example cloud_quality -- terrain_utm.ply --terrain [--images DIR]
//! ```

use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use spt::apps::cloud_quality::{
    CloudAndReference, Triangulation, ViewImages, measure, triangulated,
};
use spt::apps::stats::quantile;
use spt::eval::perceptual::flip_heat_map;
use spt::io::ply::{Encoding, FaceList, PlyLayout, PolyMesh, write_ply};
use spt::io::scalar::Scalar;
use spt::render::{Gpu, Renderer, Settings};

#[derive(Parser)]
struct Args {
    /// The cloud (PLY; faces, if any, are ignored).
    cloud: PathBuf,
    /// Triangulate on a sensor grid of W×H pixels (an RGB-D frame).
    #[arg(long, value_parser = parse_grid, conflicts_with = "terrain")]
    grid: Option<(u32, u32)>,
    /// Triangulate as a height field (2.5D Delaunay).
    #[arg(long)]
    terrain: bool,
    /// Orbit views at elevation 20°, azimuth every 360°/views.
    #[arg(long, default_value_t = 4)]
    views: u32,
    /// Distance in bounding-sphere radii.
    #[arg(long, default_value_t = 1.6)]
    distance: f64,
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Draw the splats without the EWA prefilter.
    #[arg(long)]
    no_ewa: bool,
    /// Level of detail's error bound in pixels (0: leaves only).
    #[arg(long, default_value_t = 0.0)]
    error_px: f64,
    /// Write each view's images (splats, triangulation at 1×, reference, and the splats' FLIP
    /// error as a heat map) into DIR.
    #[arg(long)]
    images: Option<PathBuf>,
    /// Also score the triangulation's own splats (the mesh pipeline) and the
    /// triangulation shaded with the cloud's estimated normals, against the reference.
    #[arg(long)]
    bounds: bool,
    /// Write the triangulation as a PLY mesh (double coordinates, the cloud's colours),
    /// and measure nothing.
    #[arg(long, value_name = "OUT.ply")]
    write_mesh: Option<PathBuf>,
}

/// Writes the triangulated cloud `g` to `path` as a binary PLY, positions in the file's
/// coordinates as doubles, one vertex per row of the cloud's file: the rows it dropped
/// (a frame's pixels without depth) are NaN, so that a sensor frame keeps its grid.
fn write_mesh(path: &std::path::Path, g: &spt::io::Geometry) -> anyhow::Result<()> {
    let row = |v: usize| g.rows.as_ref().map_or(v, |r| r[v] as usize);
    let rows = g
        .positions
        .len()
        .checked_sub(1)
        .map_or(0, |last| row(last) + 1);
    let mut positions = vec![[f64::NAN; 3]; rows];
    let mut colors = vec![[0u8; 3]; rows];
    for (v, p) in g.positions.iter().enumerate() {
        positions[row(v)] = (p.as_dvec3() + g.origin).to_array();
        if let Some(c) = &g.colors {
            colors[row(v)] = [c[v][0], c[v][1], c[v][2]];
        }
    }
    let triangles: Vec<[u32; 3]> = (g.triangles.iter())
        .map(|t| t.map(|v| row(v as usize) as u32))
        .collect();
    let mesh = PolyMesh {
        positions,
        normals: None,
        colors: g.colors.is_some().then_some(colors),
        faces: FaceList::triangles(&triangles),
    };
    let mut layout = PlyLayout::standard(Encoding::BinaryLittleEndian, &mesh);
    for p in layout.vertex_properties.iter_mut().take(3) {
        p.1 = Scalar::F64;
    }
    write_ply(path, &mesh, &layout).with_context(|| format!("writing {}", path.display()))
}

fn parse_grid(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or("expected WxH")?;
    let n = |v: &str| v.parse::<u32>().map_err(|e| e.to_string());
    Ok((n(w)?, n(h)?))
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let triangulation = match (args.grid, args.terrain) {
        (Some((width, height)), _) => Triangulation::Grid { width, height },
        (None, true) => Triangulation::Terrain,
        (None, false) => anyhow::bail!("say how to triangulate: --grid WxH or --terrain"),
    };
    if let Some(out) = &args.write_mesh {
        let g = triangulated(&args.cloud, triangulation)?;
        write_mesh(out, &g)?;
        println!("{}: {} triangles", out.display(), g.triangles.len());
        return Ok(());
    }
    let renderer = Renderer::new(Gpu::new(None)?);
    eprintln!("adapter: {}", renderer.gpu.describe());
    let models = if args.bounds {
        CloudAndReference::with_bounds(&args.cloud, triangulation)?
    } else {
        CloudAndReference::open(&args.cloud, triangulation)?
    };
    let settings = Settings {
        ewa: !args.no_ewa,
        lod: args.error_px > 0.0,
        error_px: args.error_px,
        ..Settings::default()
    };
    if let Some(dir) = &args.images {
        std::fs::create_dir_all(dir)?;
    }
    let mut save = |k: u32, images: &ViewImages| {
        if let Some(dir) = &args.images {
            for (name, image) in [
                ("splats", &images.splats),
                ("mesh", &images.mesh),
                ("reference", &images.reference),
            ] {
                if let Err(e) = write_png(&dir.join(format!("view{k}_{name}.png")), image) {
                    eprintln!("view {k}: {e:#}");
                }
            }
            let heat = flip_heat_map(&images.splats, &images.reference);
            if let Err(e) = write_png(&dir.join(format!("view{k}_flip.png")), &heat) {
                eprintln!("view {k}: {e:#}");
            }
        }
    };
    let shape = (args.views, args.distance, args.size);
    let figures = measure(&renderer, &models, shape, &settings, &mut save)?;
    println!("view  splat FLIP  SSIM   mesh 1x FLIP  requantized 1x FLIP  holes");
    for (k, f) in figures.iter().enumerate() {
        let requantized = f
            .requantized_flip
            .map_or("–".to_owned(), |v| format!("{v:.4}"));
        println!(
            "{k:4}  {:10.4}  {:5.3}  {:12.4}  {requantized:>19}  {:.3} %",
            f.splat_flip,
            f.splat_ssim,
            f.mesh_flip,
            100.0 * f.hole_rate
        );
    }
    let median = |get: fn(&spt::apps::cloud_quality::ViewFigures) -> f64| {
        quantile(&mut figures.iter().map(get).collect::<Vec<_>>(), 0.5).unwrap_or(f64::NAN)
    };
    println!(
        "median splat FLIP {:.4}, SSIM {:.3}, triangulation at 1x {:.4}, holes {:.3} % (max {:.3} %)",
        median(|f| f.splat_flip),
        median(|f| f.splat_ssim),
        median(|f| f.mesh_flip),
        100.0 * median(|f| f.hole_rate),
        100.0 * figures.iter().map(|f| f.hole_rate).fold(0.0, f64::max),
    );
    if figures.iter().all(|f| f.requantized_flip.is_some()) {
        println!(
            "median requantized triangulation at 1x (points moved within their depth step) {:.4}",
            median(|f| f.requantized_flip.unwrap_or(f64::NAN))
        );
    }
    if args.bounds {
        let bound = |f: Option<f64>| f.unwrap_or(f64::NAN);
        for (k, f) in figures.iter().enumerate() {
            println!(
                "view {k}: triangulation's own splats {:.4}, against the cloud's splats {:.4}",
                bound(f.mesh_splat_flip),
                bound(f.mesh_splats_against_cloud)
            );
        }
        println!(
            "median triangulation's own splats {:.4}, against the cloud's splats {:.4}; triangulation at 1x with the cloud's normals {:.4}",
            median(|f| f.mesh_splat_flip.unwrap_or(f64::NAN)),
            median(|f| f.mesh_splats_against_cloud.unwrap_or(f64::NAN)),
            median(|f| f.cloud_normals_flip.unwrap_or(f64::NAN)),
        );
    }
    Ok(())
}

/// Writes a rendered image as PNG.
fn write_png(path: &std::path::Path, image: &spt::render::Image) -> anyhow::Result<()> {
    spt::io::png::write_png(path, image.width, image.height, &image.rgba)
}
