//! Image error as the graphics field judges it: NVIDIA FLIP and SSIM over the
//! pixels either image covers, against the mesh rendered at 4×4 the size and averaged in
//! linear light. 8 orbit views (elevation 20°, azimuth every 45°, distance 2.2 bounding-
//! sphere radii), 512×512, median over the views; printed with `--nocapture`.
//!
//! Asserted: the metric is zero for the reference itself, the numbers are in range, the
//! splats (elliptical, Phong-shaded, curved patches clipped at the mesh's border,
//! coverage-sampled silhouettes) stay within [`MAX_RATIO`] of the aliased mesh's FLIP
//! with SSIM ≥ 0.96 (flat disks scored 4.3–5.3× and 0.82–0.86), level of detail at ε = 1 px stays within [`MAX_LOD_COST`] of the leaves'
//! FLIP, and the EWA prefilter lowers FLIP on the scans. On the knot the
//! prefilter is judged against the surface the mesh samples (the same analytic knot
//! sampled 16× more densely): against the knot's own triangles its patches, which follow
//! the smooth surface, reach a fraction of a pixel past the polygon's silhouette, and
//! the prefilter draws that faithfully (docs/image-quality.md).

use crate::common;

use spt::apps::stats::quantile;
use spt::eval::perceptual::{downsample, flip_mean, ssim_mean};
use spt::io::ply::{Encoding, PlyLayout, write_ply};
use spt::io::torus_knot::torus_knot;
use spt::render::{Camera, Image, Settings};
use spt::tree::scene::Scene;

const SIZE: u32 = 512;
/// The bound: largest splat FLIP over the aliased mesh's FLIP (measured: knot
/// 1.8×, bunny 1.8×, dragon 1.5×).
const MAX_RATIO: f64 = 2.0;
/// Smallest SSIM of the splats (measured 0.972–0.978).
const MIN_SSIM: f64 = 0.96;
/// Largest FLIP with the EWA prefilter over FLIP without it, against a model's own
/// mesh (measured: knot 1.01, bunny 0.96, dragon 0.90).
const MAX_PREFILTER_COST: f64 = 1.03;
/// The bound on level of detail: largest FLIP at ε = 1 px over FLIP of the
/// leaves only (measured: knot 1.07, bunny 1.00, dragon 1.01).
const MAX_LOD_COST: f64 = 1.10;
const SUPERSAMPLE: u32 = 4;

/// Median of `values` (nearest rank, as every command reports it).
fn median(mut values: Vec<f64>) -> f64 {
    quantile(&mut values, 0.5).expect("eight views")
}

struct Figures {
    mesh_flip: f64,
    splat_flip: f64,
    no_ewa_flip: f64,
    lod_flip: f64,
    splat_ssim: f64,
}

/// The figures of `scene` against `surface`'s mesh (a denser sampling of the same
/// surface; None: the scene's own mesh), on `scene`'s orbit views.
fn measure(scene: &Scene, surface: Option<&Scene>, what: &str) -> Figures {
    let r = common::renderer();
    let gpu = r.upload(scene);
    let surface_gpu = surface.map(|s| r.upload(s));
    let (reference, reference_gpu) = match (surface, &surface_gpu) {
        (Some(s), Some(g)) => (s, g),
        _ => (scene, &gpu),
    };
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
    let lod = Settings::default();
    let [mut m, mut s, mut n, mut l, mut q] = std::array::from_fn(|_| Vec::new());
    for k in 0..8 {
        let camera = Camera::orbit(scene.meta(), 45.0 * k as f64, 20.0, 2.2, fov);
        let size = SIZE * SUPERSAMPLE;
        let (fine, _) = r
            .render(reference, reference_gpu, &camera, &mesh, size, size)
            .unwrap();
        let reference = downsample(&fine, SUPERSAMPLE);
        assert_eq!(flip_mean(&reference, &reference), 0.0);
        let splats = render(&camera, &leaves, SIZE);
        m.push(flip_mean(&render(&camera, &mesh, SIZE), &reference));
        s.push(flip_mean(&splats, &reference));
        n.push(flip_mean(&render(&camera, &no_ewa, SIZE), &reference));
        l.push(flip_mean(&render(&camera, &lod, SIZE), &reference));
        q.push(ssim_mean(&splats, &reference));
    }
    let f = Figures {
        mesh_flip: median(m),
        splat_flip: median(s),
        no_ewa_flip: median(n),
        lod_flip: median(l),
        splat_ssim: median(q),
    };
    eprintln!(
        "{what}: FLIP mesh 1× {:.4}, splats leaves only {:.4} ({:.1}×), no EWA {:.4}, ε = 1 px {:.4} ({:.3}×); SSIM of splats {:.3}",
        f.mesh_flip,
        f.splat_flip,
        f.splat_flip / f.mesh_flip,
        f.no_ewa_flip,
        f.lod_flip,
        f.lod_flip / f.splat_flip,
        f.splat_ssim
    );
    f
}

fn assert_in_range(f: &Figures, what: &str) {
    for v in [f.mesh_flip, f.splat_flip, f.no_ewa_flip, f.lod_flip] {
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
        f.lod_flip <= MAX_LOD_COST * f.splat_flip,
        "{what}: FLIP {} at ε = 1 px, {} for the leaves only",
        f.lod_flip,
        f.splat_flip
    );
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
    let f = measure(&scene, None, "torus knot");
    assert_in_range(&f, "torus knot");
    let Some(dir) = common::shared_data() else {
        return;
    };
    for name in ["bunny.ply", "dragon40k.ply"] {
        let scene = Scene::open(&dir.join(name)).unwrap();
        let f = measure(&scene, None, name);
        assert_in_range(&f, name);
        assert!(
            f.splat_flip <= f.no_ewa_flip,
            "{name}: FLIP {} with the prefilter, {} without",
            f.splat_flip,
            f.no_ewa_flip
        );
    }
}

/// Against the surface the default model samples (`gen_model --segments 2000 --sides
/// 400`, 16× denser), the splats are nearer to it than the model's own triangles
/// (measured 0.0818 against 0.0916; 0.0605 before the shading and colour fields were
/// fitted to the triangles' normals and colours), and the prefilter lowers FLIP (0.0818
/// against 0.0856 without).
#[test]
fn the_knot_s_splats_are_nearer_its_surface_than_its_triangles() {
    let dir = common::temp_dir();
    let path = dir.path().join("knot_2000x400.ply");
    let dense = torus_knot(2000, 400, true);
    let layout = PlyLayout::standard(Encoding::BinaryLittleEndian, &dense);
    write_ply(&path, &dense, &layout).unwrap();
    let surface = Scene::open(&path).unwrap();
    let scene = Scene::open(&common::default_model()).unwrap();
    let f = measure(&scene, Some(&surface), "torus knot against its surface");
    assert!(
        f.splat_flip < f.mesh_flip,
        "splats {}, the model's triangles {}",
        f.splat_flip,
        f.mesh_flip
    );
    assert!(
        f.splat_flip <= f.no_ewa_flip,
        "FLIP {} with the prefilter, {} without",
        f.splat_flip,
        f.no_ewa_flip
    );
    assert!(f.splat_ssim >= MIN_SSIM, "SSIM {}", f.splat_ssim);
}
