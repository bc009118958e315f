//! Splat image quality against the mesh, view by view: FLIP and SSIM of the
//! splats (leaves only, without the prefilter, at ε = 1 px) and of the aliased mesh,
//! against the mesh rendered at 4×4 the size and averaged in linear light; and, with
//! `--crops`, each image (`view{k}_image{i}.png`, i in the order printed), the FLIP maps,
//! and side-by-side close-ups (splats | mesh reference) enlarged 3× without filtering,
//! for docs/image-quality.md. Each figure of a view is followed by its three parts: the pixels
//! both images cover away from the reference's outlines, those near one (within 2
//! pixels of a coverage step or an occluding edge), and those only one image covers.
//!
//! `--mesh` scores other meshes of the same surface at 1× on the same views (another
//! triangulation of the same samples from `tools/alt_triangulation.py`, or a denser
//! sampling); `--reference` takes the reference from another mesh of the same surface
//! (a denser sampling: closer to the surface itself than the model's own triangles).
//!
//! ```text
//! cargo run --release --example quality -- data/torus_knot.ply [--views 8] [--crops DIR]
//!     [--mesh OTHER.ply ...] [--reference DENSER.ply] [--distance RADII] [--error-px E]
//! ```

use std::path::PathBuf;

use clap::Parser;
use spt::apps::stats::quantile;
use spt::eval::perceptual::{downsample, flip_map, flip_mean, ssim_mean};
use spt::render::{Camera, Gpu, Image, Renderer, Settings};
use spt::tree::scene::Scene;

#[derive(Parser)]
struct Args {
    /// The model (PLY with faces, or .spt built from one).
    model: PathBuf,
    /// Orbit views at elevation 20°, azimuth every 360°/views.
    #[arg(long, default_value_t = 8)]
    views: u32,
    /// Distance in bounding-sphere radii.
    #[arg(long, default_value_t = 2.2)]
    distance: f64,
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Write, per view, the splats, the reference and a side-by-side crop into DIR.
    #[arg(long)]
    crops: Option<PathBuf>,
    /// Also score this mesh of the same surface, drawn as triangles at 1× (repeatable).
    #[arg(long)]
    mesh: Vec<PathBuf>,
    /// Render the reference from this mesh of the same surface instead of the model's.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// The level of detail's error bound, pixels, of the last column.
    #[arg(long, default_value_t = 1.0)]
    error_px: f64,
}

/// A model on the GPU.
struct Model {
    scene: Scene,
    gpu: spt::render::GpuScene,
}

const SUPERSAMPLE: u32 = 4;

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let renderer = Renderer::new(Gpu::new(None)?);
    eprintln!("adapter: {}", renderer.gpu.describe());
    let open = |path: &PathBuf| -> anyhow::Result<Model> {
        let scene = Scene::open(path)?;
        let gpu = renderer.upload(&scene);
        Ok(Model { scene, gpu })
    };
    let model = open(&args.model)?;
    let others = args
        .mesh
        .iter()
        .map(open)
        .collect::<anyhow::Result<Vec<_>>>()?;
    let reference_model = args.reference.as_ref().map(open).transpose()?;
    let render =
        |m: &Model, camera: &Camera, settings: &Settings, size: u32| -> anyhow::Result<Image> {
            Ok(renderer
                .render(&m.scene, &m.gpu, camera, settings, size, size)?
                .0)
        };
    let (mesh, leaves) = (Settings::mesh(), Settings::leaves());
    let no_ewa = Settings {
        ewa: false,
        ..leaves
    };
    let lod = Settings {
        error_px: args.error_px,
        ..Settings::default()
    };
    let mut configs = vec![
        ("mesh 1×".to_string(), mesh, &model),
        ("leaves".to_string(), leaves, &model),
        ("no EWA".to_string(), no_ewa, &model),
        (format!("ε={}", args.error_px), lod, &model),
    ];
    for (path, other) in args.mesh.iter().zip(&others) {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        configs.push((format!("{name} 1×"), mesh, other));
    }
    let mut flips = vec![Vec::new(); configs.len()];
    let mut ssims = vec![Vec::new(); configs.len()];
    for k in 0..args.views {
        let azimuth = 360.0 * k as f64 / args.views as f64;
        let camera = Camera::orbit(
            model.scene.meta(),
            azimuth,
            20.0,
            args.distance,
            45f64.to_radians(),
        );
        let reference = downsample(
            &render(
                reference_model.as_ref().unwrap_or(&model),
                &camera,
                &mesh,
                args.size * SUPERSAMPLE,
            )?,
            SUPERSAMPLE,
        );
        let mut line = format!("view {azimuth:5.1}°:");
        for (i, (name, settings, m)) in configs.iter().enumerate() {
            let image = render(m, &camera, settings, args.size)?;
            let (f, s) = (flip_mean(&image, &reference), ssim_mean(&image, &reference));
            let map = flip_map(&image, &reference);
            let [inside, outlines, rim] = split(&map, &image, &reference);
            line += &format!("  {name} {f:.4} ({inside:.4}+{outlines:.4}+{rim:.4})/{s:.3}");
            flips[i].push(f);
            ssims[i].push(s);
            if let Some(dir) = &args.crops {
                write_images(dir, (k, i), &image, &reference, &map)?;
            }
        }
        println!("{line}");
    }
    println!("median FLIP / SSIM over {} views:", args.views);
    for (i, (name, _, _)) in configs.iter().enumerate() {
        let f = quantile(&mut flips[i], 0.5).unwrap_or(f64::NAN);
        let s = quantile(&mut ssims[i], 0.5).unwrap_or(f64::NAN);
        println!("  {name:8} FLIP {f:.4}  SSIM {s:.3}");
    }
    Ok(())
}

/// Writes view k's image of configuration i and its FLIP map into `dir`; for the
/// splats (i = 1) also the reference and the side-by-side close-up.
fn write_images(
    dir: &std::path::Path,
    (k, i): (u32, usize),
    image: &Image,
    reference: &Image,
    map: &[f32],
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)?;
    let grey: Vec<u8> = map.iter().map(|e| (e * 255.0).round() as u8).collect();
    image::save_buffer(
        dir.join(format!("view{k}_flip{i}.png")),
        &grey,
        image.width,
        image.height,
        image::ExtendedColorType::L8,
    )?;
    save(image, &dir.join(format!("view{k}_image{i}.png")))?;
    if i == 1 {
        save(image, &dir.join(format!("view{k}_splats.png")))?;
        save(reference, &dir.join(format!("view{k}_reference.png")))?;
        side_by_side(image, reference, &dir.join(format!("view{k}_crop.png")))?;
    }
    Ok(())
}

fn save(image: &Image, path: &std::path::Path) -> anyhow::Result<()> {
    image::save_buffer(
        path,
        &image.rgba,
        image.width,
        image.height,
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(())
}

/// The central quarter of both images, side by side, each pixel a 3×3 block.
fn side_by_side(left: &Image, right: &Image, path: &std::path::Path) -> anyhow::Result<()> {
    const ZOOM: u32 = 3;
    let (cw, ch) = (left.width / 4, left.height / 4);
    let (x0, y0) = (left.width / 2 - cw / 2, left.height / 2 - ch / 2);
    let gap = 4;
    let (w, h) = (2 * cw * ZOOM + gap, ch * ZOOM);
    let mut out = image::RgbaImage::from_pixel(w, h, image::Rgba([0, 0, 0, 255]));
    for (side, img) in [left, right].into_iter().enumerate() {
        for y in 0..h {
            for x in 0..cw * ZOOM {
                let (sx, sy) = (x0 + x / ZOOM, y0 + y / ZOOM);
                let o = 4 * (sy * img.width + sx) as usize;
                let px = image::Rgba([img.rgba[o], img.rgba[o + 1], img.rgba[o + 2], 255]);
                out.put_pixel(x + side as u32 * (cw * ZOOM + gap), y, px);
            }
        }
    }
    out.save(path)?;
    Ok(())
}

/// FLIP summed over three kinds of pixels, each divided by the size of the union of
/// both images' coverage (the three parts of the mean): those both images cover away
/// from the reference's outlines, those both cover near one ([`near_outline`]), and
/// those only one image covers.
fn split(errors: &[f32], image: &Image, reference: &Image) -> [f64; 3] {
    let near = near_outline(reference, OUTLINE_REACH);
    let (mut parts, mut n) = ([0.0; 3], 0usize);
    for (i, e) in errors.iter().enumerate() {
        let part = match (image.covered[i], reference.covered[i]) {
            (false, false) => continue,
            (true, true) if near[i] => 1,
            (true, true) => 0,
            _ => 2,
        };
        parts[part] += *e as f64;
        n += 1;
    }
    parts.map(|p| p / n.max(1) as f64)
}

/// How far (pixels, in x and y) from an outline a pixel counts as near it.
const OUTLINE_REACH: i32 = 2;

/// The pixels within `reach` of an outline of `image`: a step in coverage, or between
/// covered neighbours whose depths differ by more than 5 % (an occluding edge).
fn near_outline(image: &Image, reach: i32) -> Vec<bool> {
    let (w, h) = (image.width as i32, image.height as i32);
    let at = |x: i32, y: i32| (y * w + x) as usize;
    let step = |a: usize, b: usize| {
        let (da, db) = (image.depth[a], image.depth[b]);
        image.covered[a] != image.covered[b]
            || (image.covered[a] && (da - db).abs() > 0.05 * da.min(db))
    };
    let mut edge = vec![false; image.covered.len()];
    for y in 0..h {
        for x in 0..w {
            let i = at(x, y);
            if (x + 1 < w && step(i, at(x + 1, y))) || (y + 1 < h && step(i, at(x, y + 1))) {
                edge[i] = true;
            }
        }
    }
    let mut near = vec![false; edge.len()];
    for y in 0..h {
        for x in 0..w {
            near[at(x, y)] = (-reach..=reach).any(|dy| {
                (-reach..=reach).any(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    u >= 0 && v >= 0 && u < w && v < h && edge[at(u, v)]
                })
            });
        }
    }
    near
}
