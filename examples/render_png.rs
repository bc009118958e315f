//! The engine alone (no apps, no command line): open a model (PLY, LAS, LAZ or .spt),
//! upload its tree, render one frame headless at ε = 1 px and write it as a PNG.
//!
//! `cargo run --release --no-default-features --example render_png -- MODEL OUT.png`

use std::path::PathBuf;

use spt::io::png::write_png;
use spt::render::{Camera, Gpu, Renderer, Settings};
use spt::tree::scene::Scene;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let model = args.next().unwrap_or_else(|| "data/torus_knot.ply".into());
    let output = args.next().unwrap_or_else(|| "frame.png".into());
    let (width, height) = (1024, 768);

    let scene = Scene::open(&model)?;
    let renderer = Renderer::new(Gpu::new(None)?);
    let uploaded = renderer.upload(&scene);
    let fov_y = 45f64.to_radians();
    let aspect = width as f64 / height as f64;
    let camera = Camera::framed(scene.meta(), scene.index.chunks(), fov_y, aspect);

    let settings = Settings::default();
    let (image, stats) = renderer.render(&scene, &uploaded, &camera, &settings, width, height)?;
    write_png(&output, image.width, image.height, &image.rgba)?;
    println!("{} splats drawn → {}", stats.selected, output.display());
    Ok(())
}
