//! Image error as the graphics field judges it (issue 12): NVIDIA FLIP and SSIM over the
//! pixels either image covers, against the mesh rendered at 4×4 the size and averaged in
//! linear light. 8 orbit views (elevation 20°, azimuth every 45°, distance 2.2 bounding-
//! sphere radii), 512×512, median over the views; printed with `--nocapture`.
//!
//! What this asserts is what holds today: the metric is zero for the reference itself,
//! the numbers are in range, and the splats (elliptical, Phong-shaded, curved patches
//! clipped at the mesh's border, coverage-sampled silhouettes) stay within
//! [`MAX_RATIO`] of the aliased mesh's FLIP with SSIM ≥ [`MIN_SSIM`] (the baseline
//! before them was 4.3–5.3× and 0.82–0.86).
//! Issue 12's targets (2×, SSIM 0.96) are not reached; the README says why 2× of the
//! aliased mesh is a bar that even another triangulation of the same samples misses.

mod common;

use spt::apps::stats::quantile;
use spt::render::perceptual::{downsample, flip_mean, ssim_mean};
use spt::render::{Camera, Image, Scene, Settings};

const SIZE: u32 = 512;
/// Largest splat FLIP over the aliased mesh's FLIP (measured 2.3–3.8×).
const MAX_RATIO: f64 = 4.0;
/// Smallest SSIM of the splats (measured 0.954–0.974).
const MIN_SSIM: f64 = 0.95;
/// Largest FLIP with the EWA prefilter over FLIP without it (measured 0.95–1.02: the
/// prefilter's band gives partly covered silhouette pixels a colour, which helps where
/// the patches end on the surface's silhouette and costs where they overshoot it).
const MAX_PREFILTER_COST: f64 = 1.03;
const SUPERSAMPLE: u32 = 4;

/// Median of `values` (nearest rank, as every command reports it).
fn median(mut values: Vec<f64>) -> f64 {
    quantile(&mut values, 0.5).expect("eight views")
}

struct Figures {
    mesh_flip: f64,
    splat_flip: f64,
    no_ewa_flip: f64,
    splat_ssim: f64,
}

fn measure(scene: &Scene, what: &str) -> Figures {
    let r = common::renderer();
    let gpu = r.upload(scene);
    let fov = 45f64.to_radians();
    let render = |camera: &Camera, settings: &Settings, size: u32| -> Image {
        r.render(scene, &gpu, camera, settings, size, size)
            .unwrap()
            .0
    };
    let (mesh, leaves) = (Settings::mesh(), Settings::leaves());
    let no_ewa = Settings {
        ewa: false,
        ..leaves
    };
    let (mut m, mut s, mut n, mut q) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for k in 0..8 {
        let camera = Camera::orbit(scene.meta(), 45.0 * k as f64, 20.0, 2.2, fov);
        let reference = downsample(&render(&camera, &mesh, SIZE * SUPERSAMPLE), SUPERSAMPLE);
        assert_eq!(flip_mean(&reference, &reference), 0.0);
        let splats = render(&camera, &leaves, SIZE);
        m.push(flip_mean(&render(&camera, &mesh, SIZE), &reference));
        s.push(flip_mean(&splats, &reference));
        n.push(flip_mean(&render(&camera, &no_ewa, SIZE), &reference));
        q.push(ssim_mean(&splats, &reference));
    }
    let f = Figures {
        mesh_flip: median(m),
        splat_flip: median(s),
        no_ewa_flip: median(n),
        splat_ssim: median(q),
    };
    eprintln!(
        "{what}: FLIP mesh 1× {:.4}, splats leaves only {:.4} ({:.1}×), no EWA {:.4}; SSIM of splats {:.3}",
        f.mesh_flip,
        f.splat_flip,
        f.splat_flip / f.mesh_flip,
        f.no_ewa_flip,
        f.splat_ssim
    );
    f
}

fn assert_in_range(f: &Figures, what: &str) {
    for v in [f.mesh_flip, f.splat_flip, f.no_ewa_flip] {
        assert!(v > 0.0 && v < 1.0, "{what}: FLIP {v}");
    }
    assert!(
        f.splat_ssim > 0.0 && f.splat_ssim <= 1.0,
        "{what}: SSIM {}",
        f.splat_ssim
    );
    assert!(
        f.splat_flip <= MAX_RATIO * f.mesh_flip,
        "{what}: splats {} against the aliased mesh's {}",
        f.splat_flip,
        f.mesh_flip
    );
    assert!(f.splat_ssim >= MIN_SSIM, "{what}: SSIM {}", f.splat_ssim);
    assert!(
        f.splat_flip <= MAX_PREFILTER_COST * f.no_ewa_flip,
        "{what}: FLIP {} with the prefilter, {} without",
        f.splat_flip,
        f.no_ewa_flip
    );
}

#[test]
fn flip_and_ssim_against_the_supersampled_mesh() {
    let scene = Scene::open(&common::default_model()).unwrap();
    let f = measure(&scene, "torus knot");
    assert_in_range(&f, "torus knot");
    let Some(dir) = common::shared_data() else {
        return;
    };
    for name in ["bunny.ply", "dragon40k.ply"] {
        let scene = Scene::open(&dir.join(name)).unwrap();
        assert_in_range(&measure(&scene, name), name);
    }
}
