//! Scenes of instances (docs/scenes.md) against the usual way: a scene of 16 instances
//! of bunny (rotations about mixed axes, scales 0.5–2, a geo-referenced cluster of 15
//! and one instance 10⁶ units from it) renders like a PLY model made of the transformed
//! copies, converted and drawn as one model: FLIP between the two images at most
//! [`SAME`] in each of 4 views (three of the cluster, one of the far instance) at
//! leaves only; at ε = 1 px, as close to the leaves as the model's own frame
//! ([`LOD_WORSE`]), with as many splats (within 30 %).
//!
//! The far copy's reference is a PLY of that copy alone: one model holding it and the
//! cluster would store its vertices as f32 offsets 10⁶ units from its origin, 6 cm
//! apart, against a bunny 15 cm wide; an instance keeps its translation in f64.

use std::path::Path;

use glam::{DQuat, DVec3};

use crate::common;
use spt::eval::perceptual::flip_mean;
use spt::io::ply::{FaceList, PolyMesh};
use spt::render::{Camera, Image, Settings};
use spt::tree::instances::{InstancedScene, Similarity};
use spt::tree::report::Silent;
use spt::tree::scene::Scene;

/// Largest FLIP between a scene's frame and its reference's at leaves only, per view.
const SAME: f64 = 0.01;
/// At ε = 1 px each draws its own tree's inner nodes, and two trees' cuts differ by
/// about what each differs from the leaves (measured: 0.02–0.06 both, and 0.02–0.05
/// between them; the far copy's own tree, built from the rotated vertices, differs from
/// the instance's too). So the scene's frame is held to the model's own error against
/// the leaves: at most 10 % and 0.002 above it.
const LOD_WORSE: f64 = 1.10;
const LOD_SLACK: f64 = 0.002;
const SIZE: u32 = 512;
/// Where the cluster stands (a UTM-like position).
const BASE: DVec3 = DVec3::new(512_340.0, 5_403_120.0, 210.0);
const FAR: DVec3 = DVec3::new(1.0e6, 0.0, 0.0);

/// The 16 instances: 15 on a grid 0.45 apart about BASE, one FAR beyond it.
fn similarities() -> Vec<Similarity> {
    (0..16)
        .map(|k| {
            let (row, col) = ((k / 4) as f64, (k % 4) as f64);
            let translation = match k {
                15 => BASE + FAR,
                _ => BASE + DVec3::new(0.45 * col, 0.45 * row, 0.1 * (k % 3) as f64),
            };
            let axis = DVec3::new(1.0 + (k % 3) as f64, (k % 5) as f64 - 2.0, 0.5).normalize();
            Similarity {
                translation,
                rotation: DQuat::from_axis_angle(axis, 0.4 * k as f64),
                scale: 0.5 + 1.5 * k as f64 / 15.0,
            }
        })
        .collect()
}

/// The copies of `bunny` (file coordinates) at `similarities`, as one mesh.
fn copies(bunny: &PolyMesh, similarities: &[Similarity]) -> PolyMesh {
    let n = bunny.positions.len() as u32;
    let mut out = PolyMesh::default();
    let mut triangles = Vec::new();
    for (k, s) in similarities.iter().enumerate() {
        out.positions.extend(
            bunny
                .positions
                .iter()
                .map(|p| s.apply(DVec3::from(*p)).to_array()),
        );
        // to_mesh writes triangles only.
        for t in bunny.faces.indices.chunks_exact(3) {
            triangles.push([t[0], t[1], t[2]].map(|v| v + k as u32 * n));
        }
    }
    out.faces = FaceList::triangles(&triangles);
    out
}

/// The scene file of `bunny` at `similarities`.
fn scene_json(bunny: &Path, similarities: &[Similarity]) -> String {
    let entries: Vec<String> = similarities
        .iter()
        .map(|s| {
            let t = s.translation;
            let q = s.rotation;
            format!(
                r#"{{"model": 0, "translation": [{}, {}, {}], "rotation": [{}, {}, {}, {}], "scale": {}}}"#,
                t.x, t.y, t.z, q.x, q.y, q.z, q.w, s.scale
            )
        })
        .collect();
    format!(
        r#"{{"models": [{:?}], "instances": [{}]}}"#,
        bunny.display().to_string(),
        entries.join(",\n")
    )
}

/// A camera at `eye` looking at `target`, y up (bunny's).
fn camera(eye: DVec3, target: DVec3) -> Camera {
    Camera {
        eye,
        target,
        up: DVec3::Y,
        fov_y: 45f64.to_radians(),
    }
}

#[test]
fn a_scene_of_instances_draws_as_the_transformed_copies_do() {
    let Some(data) = common::shared_data() else {
        return;
    };
    let dir = common::temp_dir();
    let bunny_path = data.join("bunny.ply");
    let geometry = spt::io::formats::read_model(&bunny_path).unwrap().geometry;
    let bunny = common::to_mesh(&geometry);
    let similarities = similarities();
    let cluster = &similarities[..15];
    common::write_double(&dir.path().join("cluster.ply"), &copies(&bunny, cluster));
    common::write_double(
        &dir.path().join("far.ply"),
        &copies(&bunny, &similarities[15..]),
    );
    let json = dir.path().join("scene.json");
    std::fs::write(&json, scene_json(&bunny_path, &similarities)).unwrap();

    let r = common::renderer();
    let scene = InstancedScene::open(&json, &Silent).unwrap();
    assert_eq!((scene.models.len(), scene.instances.len()), (1, 16));
    let uploaded = r.upload_instanced(&scene);
    let centre = BASE + DVec3::new(0.675, 0.675, 0.1);
    let far = BASE + FAR;
    let views = [
        (
            "cluster",
            camera(centre + DVec3::new(0.3, -2.4, 1.4), centre),
            "cluster.ply",
        ),
        (
            "cluster, low",
            camera(centre + DVec3::new(-2.0, -1.0, 0.3), centre),
            "cluster.ply",
        ),
        (
            "close-up",
            camera(BASE + DVec3::new(0.5, -0.5, 0.5), BASE),
            "cluster.ply",
        ),
        (
            "far instance",
            camera(far + DVec3::new(0.4, -0.6, 0.5), far),
            "far.ply",
        ),
    ];
    let leaves = Settings {
        lod: false,
        ..Settings::default()
    };
    let lod = Settings::default();
    for (view, cam, reference) in &views {
        let model = Scene::open(&dir.path().join(reference)).unwrap();
        let gpu = r.upload(&model);
        let draw = |s: &Settings| r.render(&model, &gpu, cam, s, SIZE, SIZE).unwrap();
        let draw_scene = |s: &Settings| {
            let (image, stats, _) = r
                .render_instanced(&scene, &uploaded, cam, s, (SIZE, SIZE))
                .unwrap();
            (image, stats)
        };
        let ((exact, _), (lod_image, lod_stats)) = (draw(&leaves), draw(&lod));
        let ((scene_exact, _), (scene_lod, scene_stats)) = (draw_scene(&leaves), draw_scene(&lod));
        assert!(
            covered(&exact) > 2000,
            "{view}: the reference shows the bunnies"
        );
        let same = flip_mean(&scene_exact, &exact);
        let (own, model_own) = (flip_mean(&scene_lod, &exact), flip_mean(&lod_image, &exact));
        let splats = scene_stats.gpu_drawn.unwrap_or(0) as f64 / lod_stats.selected.max(1) as f64;
        eprintln!(
            "{view}: leaves FLIP {same:.4}; ε 1 px against the leaves: scene {own:.4}, model \
             {model_own:.4} (the two ε 1 px frames {:.4}), splats {splats:.2}× the model's",
            flip_mean(&scene_lod, &lod_image)
        );
        assert!(same <= SAME, "{view}: leaves, FLIP {same:.4} > {SAME}");
        assert!(
            own <= model_own * LOD_WORSE + LOD_SLACK,
            "{view}: ε 1 px, the scene's FLIP {own:.4} against the model's {model_own:.4}"
        );
        assert!(
            (0.7..1.3).contains(&splats),
            "{view}: {splats:.2}× the model's splats"
        );
    }
}

fn covered(image: &Image) -> usize {
    image.covered.iter().filter(|c| **c).count()
}

/// `spt scatter` over the default model's triangles writes a scene that `spt info` and
/// `spt render` read: the asked count, on the base, repeatable by its seed.
#[test]
fn a_scattered_scene_opens_and_draws() {
    let dir = common::temp_dir();
    let knot = common::default_model();
    let scene = dir.path().join("knots.json");
    let scatter = |seed: &str| {
        let (code, out, err) = common::run_spt(&[
            "scatter".as_ref(),
            knot.as_os_str(),
            knot.as_os_str(),
            "-o".as_ref(),
            scene.as_os_str(),
            "--count".as_ref(),
            "40".as_ref(),
            "--scale".as_ref(),
            "0.02,0.05".as_ref(),
            "--max-slope".as_ref(),
            "90".as_ref(),
            "--seed".as_ref(),
            seed.as_ref(),
        ]);
        assert_eq!(code, Some(0), "{out}{err}");
        std::fs::read(dir.path().join("knots.instances.ply")).unwrap()
    };
    let first = scatter("3");
    assert_eq!(first, scatter("3"), "the same seed, the same instances");
    assert_ne!(first, scatter("4"), "another seed, other instances");
    let (code, out, err) = common::run_spt(&["info".as_ref(), scene.as_os_str()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("40 instances"), "{out}");
    let png = dir.path().join("knots.png");
    let (code, out, err) = common::run_spt(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
        "--size".as_ref(),
        "96x64".as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("instances 41 drawn"), "{out}");
    assert!(png.exists());
}

/// Largest FLIP between a scene's frame with its far instances placed by the GPU and
/// the same frame planned wholly on the CPU: the two test the same nodes at placements
/// rounded apart by an f32 ulp (measured: 0.0000–0.0011).
const GPU_PLACED_SAME: f64 = 0.005;

/// Far instances placed by the GPU (render/far.rs) draw what the CPU's plan of every
/// instance draws: 1,024 bunnies on a grid at a UTM-like position and 64 more 10⁶
/// units away, seen whole from afar, from low within the grid (near instances planned
/// on the CPU, far ones on the GPU) and at the far cluster (its placements kept to
/// 10⁻⁴ units by an f32 and its f16 rest).
#[test]
fn far_instances_placed_by_the_gpu_draw_as_the_cpu_plans_them() {
    let Some(data) = common::shared_data() else {
        return;
    };
    let dir = common::temp_dir();
    let bunny = data.join("bunny.ply");
    let grid = |origin: DVec3, side: usize| {
        (0..side * side).map(move |k| Similarity {
            translation: origin + DVec3::new(0.3 * (k % side) as f64, 0.3 * (k / side) as f64, 0.0),
            rotation: DQuat::from_rotation_y(0.7 * k as f64) * DQuat::from_rotation_x(1.2),
            scale: 0.5 + 1.5 * ((k * 7) % 16) as f64 / 15.0,
        })
    };
    let similarities: Vec<Similarity> = grid(BASE, 32).chain(grid(BASE + FAR, 8)).collect();
    let json = dir.path().join("grid.json");
    std::fs::write(&json, scene_json(&bunny, &similarities)).unwrap();
    let r = common::renderer();
    let scene = InstancedScene::open(&json, &Silent).unwrap();
    let uploaded = r.upload_instanced(&scene);
    let centre = BASE + DVec3::new(4.65, 4.65, 0.0);
    let cluster = BASE + FAR + DVec3::new(1.05, 1.05, 0.0);
    let views = [
        (
            "grid from afar",
            camera(centre + DVec3::new(0.0, -12.0, 8.0), centre),
            true,
        ),
        (
            "grid, low",
            camera(BASE + DVec3::new(-0.4, -0.4, 0.25), centre),
            false,
        ),
        (
            "far cluster",
            camera(cluster + DVec3::new(0.0, -4.0, 2.5), cluster),
            true,
        ),
    ];
    for (view, cam, all_far) in &views {
        let draw = |far_on_gpu: bool| {
            let settings = Settings {
                far_on_gpu,
                ..Settings::default()
            };
            r.render_instanced(&scene, &uploaded, cam, &settings, (256, 256))
                .unwrap()
        };
        let (gpu_image, gpu_stats, gpu_visible) = draw(true);
        let (cpu_image, cpu_stats, cpu_visible) = draw(false);
        let (gpu_drawn, cpu_drawn) = (gpu_stats.gpu_drawn.unwrap(), cpu_stats.gpu_drawn.unwrap());
        let flip = flip_mean(&gpu_image, &cpu_image);
        eprintln!(
            "{view}: {gpu_visible} instances, {gpu_drawn} splats ({cpu_drawn} planned on the \
             CPU), CPU ranges {} against {}, FLIP {flip:.4}",
            gpu_stats.chunks_tested, cpu_stats.chunks_tested
        );
        assert!(
            covered(&cpu_image) > 2000,
            "{view}: the bunnies are in view"
        );
        assert_eq!(gpu_visible, cpu_visible, "{view}: instances drawn");
        let ratio = gpu_drawn as f64 / cpu_drawn as f64;
        assert!(
            (0.995..1.005).contains(&ratio),
            "{view}: {ratio:.4}× the splats"
        );
        assert!(flip <= GPU_PLACED_SAME, "{view}: FLIP {flip:.4}");
        if *all_far {
            assert_eq!(
                gpu_stats.chunks_tested, 0,
                "{view}: every instance placed by the GPU"
            );
        } else {
            assert!(
                gpu_stats.chunks_tested > 0,
                "{view}: near instances planned on the CPU"
            );
        }
    }
}
