//! The LiDAR display modes on a small LAZ tile: ground rows and water rows
//! (`common::las_files::sample`), seen from above. In classification mode the ground
//! draws brown and the water blue, each where it lies; intensity draws grey; a model
//! without attributes draws the neutral grey in every attribute mode.

use crate::common;

use spt::render::{Camera, Image, Mode, Settings};
use spt::tree::scene::Scene;

fn render(scene: &Scene, mode: Mode) -> Image {
    let r = common::renderer();
    let gpu = r.upload(scene);
    let camera = Camera::orbit(scene.meta(), 0.0, 89.0, 1.6, 45f64.to_radians());
    let settings = Settings {
        mode,
        ..Settings::leaves()
    };
    r.render(scene, &gpu, &camera, &settings, 256, 256)
        .unwrap()
        .0
}

/// (pixels bluer than red, pixels redder than blue, grey pixels) among the covered ones.
fn hues(image: &Image) -> (usize, usize, usize) {
    let mut counts = (0, 0, 0);
    for (p, _) in image
        .rgba
        .chunks_exact(4)
        .zip(&image.covered)
        .filter(|(_, c)| **c)
    {
        let [r, g, b] = [p[0] as i32, p[1] as i32, p[2] as i32];
        if b > r + 40 {
            counts.0 += 1;
        } else if r > b + 40 {
            counts.1 += 1;
        } else if (r - g).abs() < 8 && (g - b).abs() < 8 {
            counts.2 += 1;
        }
    }
    counts
}

#[test]
fn classes_draw_in_their_colours_and_intensity_in_grey() {
    let dir = common::temp_dir();
    let path = dir.path().join("tile.laz");
    std::fs::write(&path, common::las_files::sample(64 * 48, true)).unwrap();
    let scene = Scene::open(&path).unwrap();
    assert!(scene.meta().has_attributes);
    let (water, ground, _) = hues(&render(&scene, Mode::Classification));
    eprintln!("classification: {water} water-blue and {ground} ground-brown pixels");
    // 32 water rows against 16 ground rows.
    assert!(water > 2 * ground / 3 && ground > 1000, "{water} {ground}");
    let (blue, red, grey) = hues(&render(&scene, Mode::Intensity));
    eprintln!("intensity: {grey} grey pixels, {blue} blue, {red} red");
    assert!(blue + red < grey / 50, "{blue} {red} {grey}");
}

#[test]
fn a_model_without_attributes_draws_grey_in_the_attribute_modes() {
    let scene = Scene::open(std::path::Path::new("data/torus_knot.ply")).unwrap();
    assert!(!scene.meta().has_attributes);
    for mode in [Mode::Classification, Mode::Intensity, Mode::Returns] {
        let (blue, red, grey) = hues(&render(&scene, mode));
        assert!(blue + red < grey / 50, "{mode:?}: {blue} {red} {grey}");
    }
}
