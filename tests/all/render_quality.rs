//! Image quality against the mesh reference, on the GPU (any adapter: lavapipe, or
//! llvmpipe through OpenGL on a machine without Vulkan). Each test prints what it
//! measured.

use crate::common;

use spt::eval::metrics::{Comparison, compare};
use spt::io::torus_knot::torus_knot;
use spt::render::{Camera, Mode, Settings};
use spt::tree::scene::Scene;

/// Splats (ε = 0) against the mesh for 8 views around the model.
fn eight_views(scene: &Scene, what: &str) -> Vec<Comparison> {
    let r = common::renderer();
    let uploaded = r.upload(scene);
    let settings = Settings {
        error_px: 0.0,
        ..Settings::default()
    };
    let fov = 45f64.to_radians();
    let distance = Camera::framing_distance(fov, 1.0) * 1.05;
    (0..8)
        .map(|k| {
            let camera = Camera::orbit(scene.meta(), k as f64 * 45.0, 25.0 - 10.0 * (k % 3) as f64, distance, fov);
            let (splats, _) = r.render(scene, &uploaded, &camera, &settings, 512, 512).unwrap();
            let mesh_settings = Settings { mode: Mode::Mesh, ..settings };
            let (mesh, _) = r.render(scene, &uploaded, &camera, &mesh_settings, 512, 512).unwrap();
            let c = compare(&splats, &mesh);
            eprintln!(
                "{what} view {k}: PSNR {:.2} dB (both covered: {:.2} dB, away from edges: {:.2} dB over {:.0} % of the pixels), holes {:.4} %, spill {:.4} %, {} px",
                c.psnr_db,
                c.psnr_both_db,
                c.psnr_interior_db,
                100.0 * c.interior_pixels as f64 / c.union_pixels as f64,
                c.hole_rate * 100.0,
                c.spill_rate * 100.0,
                c.union_pixels
            );
            c
        })
        .collect()
}

/// Holes: at most 0.2 % of the mesh's pixels. PSNR: 30 dB away from the mesh's edges (more than 2 px from a silhouette or an occlusion
/// edge). Over the union of both masks the error is dominated by those edges: disks of
/// the covering radius and the 1 px prefilter widen every silhouette by 1–2 px against
/// an aliased reference, which the union PSNR (≥ 19 dB here) and the both-covered PSNR
/// (≥ 25 dB) count at full contrast; they are asserted so that they cannot regress.
fn assert_quality(results: &[Comparison], what: &str) {
    for (k, c) in results.iter().enumerate() {
        assert!(
            c.hole_rate <= 0.002,
            "{what} view {k}: hole rate {:.4} %",
            c.hole_rate * 100.0
        );
        assert!(
            c.psnr_db >= 19.0,
            "{what} view {k}: PSNR {:.2} dB",
            c.psnr_db
        );
        assert!(
            c.psnr_both_db >= 25.0,
            "{what} view {k}: PSNR where both cover {:.2} dB",
            c.psnr_both_db
        );
    }
}

#[test]
fn default_model_matches_its_mesh() {
    let scene = Scene::open(&common::default_model()).unwrap();
    assert_quality(&eight_views(&scene, "torus knot"), "torus knot");
}

#[test]
fn shared_meshes_match_their_mesh() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    for name in ["bunny.ply", "dragon40k.ply"] {
        let scene = Scene::open(&dir.join(name)).unwrap();
        assert_quality(&eight_views(&scene, name), name);
    }
}

/// Seen edge-on near a contour, patches lying a little off the surface leave slits that
/// only the sheet behind the contour shows through; shaded with that sheet's flipped
/// normal, each was a speck facing the other way (docs/image-quality.md). Pass 3 fills them
/// from the front surface on both sides. Counts pixels of the default model's view
/// (leaves only, 800×600, normals mode) whose normal turns more than 90° from the mean
/// of its four neighbours while these agree: 75 before the fill, 24 with it.
#[test]
fn contours_show_no_specks_of_the_hidden_side() {
    let scene = Scene::open(&common::default_model()).unwrap();
    let r = common::renderer();
    let uploaded = r.upload(&scene);
    let (camera, (width, height)) = framed_800x600(&scene);
    for raster in common::rasters() {
        let settings = Settings {
            error_px: 0.0,
            mode: Mode::Normals,
            raster,
            ..Settings::default()
        };
        let (image, _) = r
            .render(&scene, &uploaded, &camera, &settings, width, height)
            .unwrap();
        let (specks, agreeing) = flipped_normals(&image);
        let raster = raster.name();
        eprintln!(
            "{raster}: {specks} pixels of {agreeing} with agreeing neighbours face against them"
        );
        assert!(
            agreeing > 100_000,
            "{raster}: {agreeing} pixels with agreeing neighbours"
        );
        assert!(
            specks <= 40,
            "{raster}: {specks} pixels face against their neighbours"
        );
    }
}

/// The view that frames `scene` at 800×600 (a 45° field of view), and that size.
fn framed_800x600(scene: &Scene) -> (Camera, (u32, u32)) {
    let (width, height) = (800, 600);
    let aspect = f64::from(width) / f64::from(height);
    let fov = 45f64.to_radians();
    let camera = Camera::framed(scene.meta(), scene.index.chunks(), fov, aspect);
    (camera, (width, height))
}

/// Of the covered pixels of a normals-mode image whose four neighbours are covered and
/// each within acos 0.7 of their mean normal: (those facing more than 90° from that
/// mean, all of them).
fn flipped_normals(image: &spt::render::Image) -> (usize, usize) {
    let (w, h) = (image.width as usize, image.height as usize);
    // Normals mode shows n · 0.5 + 0.5 in linear light.
    let normal = |x: usize, y: usize| {
        let i = y * w + x;
        let n = glam::Vec3::from(image.linear_rgb(i)) * 2.0 - 1.0;
        image.covered[i].then(|| n.normalize_or_zero())
    };
    let (mut specks, mut agreeing) = (0, 0);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let around = [
                normal(x + 1, y),
                normal(x - 1, y),
                normal(x, y + 1),
                normal(x, y - 1),
            ];
            let (Some(n), Some(around)) =
                (normal(x, y), around.into_iter().collect::<Option<Vec<_>>>())
            else {
                continue;
            };
            let mean = around.iter().sum::<glam::Vec3>().normalize_or_zero();
            if around.iter().all(|a| a.dot(mean) > 0.7) {
                agreeing += 1;
                specks += (n.dot(mean) < 0.0) as usize;
            }
        }
    }
    (specks, agreeing)
}

/// One frame of `scene` from `camera` with `settings`, 256×256.
fn frame(scene: &Scene, camera: &Camera, settings: &Settings) -> spt::render::Image {
    let r = common::renderer();
    let uploaded = r.upload(scene);
    r.render(scene, &uploaded, camera, settings, 256, 256)
        .unwrap()
        .0
}

#[test]
fn a_model_translated_by_1e7_renders_the_same_image() {
    let g = spt::io::ply::read_ply(&common::default_model())
        .unwrap()
        .geometry;
    let mut moved = common::to_mesh(&g);
    for p in &mut moved.positions {
        p[0] += 1e7;
        p[1] -= 1e7;
    }
    let dir = common::temp_dir();
    let path = dir.path().join("moved.ply");
    common::write_double(&path, &moved);
    let (a, b) = (
        Scene::open(&common::default_model()).unwrap(),
        Scene::open(&path).unwrap(),
    );
    let fov = 45f64.to_radians();
    for raster in common::rasters() {
        let settings = Settings {
            raster,
            ..Settings::default()
        };
        translated_renders_the_same(&a, &b, &settings, fov);
    }
}

/// [`a_model_translated_by_1e7_renders_the_same_image`] with `settings`: `a` and `b`
/// (`a` moved) from the same orbit view.
fn translated_renders_the_same(a: &Scene, b: &Scene, settings: &Settings, fov: f64) {
    let ia = frame(a, &Camera::orbit(a.meta(), 40.0, 30.0, 2.5, fov), settings);
    // The copy's header lacks the knot's `up_axis z`: seen about the same axis.
    let b_meta = spt::tree::TreeMeta {
        up: a.meta().up,
        ..b.meta().clone()
    };
    let ib = frame(b, &Camera::orbit(&b_meta, 40.0, 30.0, 2.5, fov), settings);
    let c = compare(&ib, &ia);
    eprintln!(
        "translated by 1e7: PSNR {:.2} dB, holes {:.4} %, spill {:.4} %",
        c.psnr_db,
        c.hole_rate * 100.0,
        c.spill_rate * 100.0
    );
    assert!(
        c.psnr_db >= 40.0 && c.hole_rate < 0.001 && c.spill_rate < 0.001,
        "{c:?}"
    );
}

#[test]
fn hard_views_render_without_garbage() {
    let scene = Scene::open(&common::default_model()).unwrap();
    let meta = scene.meta();
    let fov = 60f64.to_radians();
    let (centre, radius) = spt::render::camera::bounding_sphere(meta);
    let inside = Camera {
        eye: centre + glam::DVec3::new(0.3, 0.1, 0.05) * radius,
        target: centre + glam::DVec3::X * radius,
        up: glam::DVec3::Z,
        fov_y: fov,
    };
    let grazing = Camera {
        eye: centre + glam::DVec3::new(0.0, -3.0, 0.02) * radius,
        target: centre,
        up: glam::DVec3::Z,
        fov_y: fov,
    };
    let cases = [
        (
            "camera inside the bounding box",
            inside,
            Settings::default(),
        ),
        ("grazing view", grazing, Settings::default()),
        (
            "ε huge: the root alone",
            Camera::orbit(meta, 0.0, 20.0, 3.0, fov),
            Settings {
                error_px: 1e9,
                ..Settings::default()
            },
        ),
        (
            "no EWA",
            Camera::orbit(meta, 0.0, 20.0, 3.0, fov),
            Settings {
                ewa: false,
                ..Settings::default()
            },
        ),
        (
            "levels",
            Camera::orbit(meta, 0.0, 20.0, 3.0, fov),
            Settings {
                mode: Mode::Levels,
                error_px: 4.0,
                ..Settings::default()
            },
        ),
        (
            "points",
            Camera::orbit(meta, 0.0, 20.0, 3.0, fov),
            Settings {
                mode: Mode::Points,
                ..Settings::default()
            },
        ),
    ];
    for ((what, camera, settings), raster) in cases.into_iter().flat_map(|case| {
        common::rasters()
            .into_iter()
            .map(move |raster| (case, raster))
    }) {
        let settings = Settings { raster, ..settings };
        let what = format!("{what}, {} raster", raster.name());
        let img = frame(&scene, &camera, &settings);
        let covered = img.covered.iter().filter(|c| **c).count();
        eprintln!("{what}: {covered} pixels covered");
        assert!(covered > 0, "{what}: nothing drawn");
        // Uncovered pixels are exactly the background; covered ones are not black
        // (black is what a NaN in the G-buffer becomes).
        for (i, &c) in img.covered.iter().enumerate() {
            let px = &img.rgba[i * 4..i * 4 + 3];
            if !c {
                assert_eq!(px, [255, 255, 255], "{what}: pixel {i}");
            }
        }
        let black = (0..img.covered.len())
            .filter(|&i| img.covered[i] && img.rgba[i * 4..i * 4 + 3] == [0, 0, 0])
            .count();
        assert!(
            black * 1000 <= covered,
            "{what}: {black} black pixels of {covered}"
        );
    }
    // The root alone is one node.
    let r = common::renderer();
    let up = r.upload(&scene);
    let (_, stats) = r
        .render(
            &scene,
            &up,
            &Camera::orbit(meta, 0.0, 20.0, 3.0, fov),
            &Settings {
                error_px: 1e9,
                ..Settings::default()
            },
            64,
            64,
        )
        .unwrap();
    assert_eq!(stats.selected, 1);
}

#[test]
fn kinect_frame_renders_in_its_colours() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let scene = Scene::open(&dir.join("kinect_rgb.ply")).unwrap();
    // The sensor looks along +z from the origin: look from behind it, at the scene.
    let meta = scene.meta();
    let (centre, _) = spt::render::camera::bounding_sphere(meta);
    let camera = Camera {
        eye: glam::DVec3::ZERO,
        target: centre,
        up: glam::DVec3::NEG_Y,
        fov_y: 60f64.to_radians(),
    };
    let img = frame(
        &scene,
        &camera,
        &Settings {
            error_px: 0.0,
            ..Settings::default()
        },
    );
    let covered: Vec<usize> = (0..img.covered.len()).filter(|&i| img.covered[i]).collect();
    let saturated = covered
        .iter()
        .filter(|&&i| {
            let p = &img.rgba[i * 4..i * 4 + 3];
            p.iter().max().unwrap() - p.iter().min().unwrap() > 30
        })
        .count();
    eprintln!(
        "kinect: {} pixels covered, {saturated} with distinct colour",
        covered.len()
    );
    assert!(covered.len() > 256 * 256 / 4);
    assert!(
        saturated * 10 > covered.len(),
        "the frame is grey: colours lost"
    );
}

#[test]
fn compute_culling_draws_what_the_cpu_reference_selects() {
    let scene = Scene::open(&common::default_model()).unwrap();
    let r = common::renderer();
    let up = r.upload(&scene);
    let fov = 45f64.to_radians();
    for (k, error_px) in [(0, 0.0), (1, 1.0), (2, 4.0)] {
        // The whole model in view: frustum culling removes nothing.
        let camera = Camera::orbit(scene.meta(), 60.0 * k as f64, 20.0, 3.0, fov);
        let base = Settings {
            error_px,
            culling: spt::render::Culling::Vertex,
            ..Settings::default()
        };
        let (vertex, sv) = r.render(&scene, &up, &camera, &base, 256, 256).unwrap();
        let compute_settings = Settings {
            culling: spt::render::Culling::Compute,
            ..base
        };
        let (compute, sc) = r
            .render(&scene, &up, &camera, &compute_settings, 256, 256)
            .unwrap();
        let c = compare(&compute, &vertex);
        eprintln!(
            "ε {error_px} px: CPU reference {}, GPU compute culling {:?}; images {:.1} dB apart",
            sv.selected, sc.gpu_drawn, c.psnr_db
        );
        assert_eq!(
            sc.gpu_drawn,
            Some(sv.selected as u64),
            "ε {error_px}: the GPU test and the CPU reference disagree"
        );
        assert!(
            c.psnr_db >= 45.0 && c.hole_rate == 0.0,
            "ε {error_px}: {c:?}"
        );
    }
}

#[test]
fn splats_crossing_the_near_plane_are_skipped_not_garbled() {
    let scene = Scene::open(&common::default_model()).unwrap();
    let meta = scene.meta();
    // Stand on a leaf, 1 % of its radius above it, and look along the surface: that disk
    // (and its neighbours) spans the near plane.
    let leaf = scene.nodes().iter().find(|r| r.error == 0).unwrap();
    let origin = glam::DVec3::from(meta.origin);
    let (p, n) = (
        leaf.position().as_dvec3() + origin,
        leaf.normal().as_dvec3(),
    );
    let along = n.any_orthonormal_vector();
    let eye = p + n * (leaf.radius() as f64 * 0.01);
    for (error_px, raster) in [0.0, 1.0]
        .into_iter()
        .flat_map(|e| common::rasters().into_iter().map(move |r| (e, r)))
    {
        let camera = Camera {
            eye,
            target: eye + along,
            up: n,
            fov_y: 70f64.to_radians(),
        };
        let img = frame(
            &scene,
            &camera,
            &Settings {
                error_px,
                raster,
                ..Settings::default()
            },
        );
        let covered = img.covered.iter().filter(|c| **c).count();
        let black = (0..img.covered.len())
            .filter(|&i| img.covered[i] && img.rgba[i * 4..i * 4 + 3] == [0, 0, 0])
            .count();
        eprintln!("near plane, ε {error_px}: {covered} pixels covered, {black} black");
        assert!(covered > 1000, "the surface ahead is drawn");
        assert!(black * 1000 <= covered, "{black} black pixels of {covered}");
        for (i, &c) in img.covered.iter().enumerate() {
            if !c {
                assert_eq!(&img.rgba[i * 4..i * 4 + 3], [255, 255, 255], "pixel {i}");
            }
        }
    }
}

/// A cloud's estimated normals face either way; on a rim, a splat just past the
/// horizon faces away, flips to face the eye, and cancels the rim's normals: a dark
/// dot on the rim. Pass 3 takes such a pixel's normal from its neighbours on the same
/// surface (docs/point-clouds.md). Counts the pixels inside the picture more than 40
/// levels darker than the median of their 3 × 3 neighbourhood ([`dark_dots`]) on the
/// knot's surface sampled 2000 × 400, drawn as a cloud and as its mesh (leaves only,
/// 800×600): the cloud's are at most the mesh's (hardware raster, lavapipe: 121 before
/// the fill, 18 with it, the mesh 34).
#[test]
fn an_unoriented_cloud_s_rims_show_no_dark_dots() {
    let dir = common::temp_dir();
    let knot = torus_knot(2000, 400, false);
    let (mesh, cloud) = common::mesh_and_its_cloud(dir.path(), knot, "knot");
    let (camera, size) = framed_800x600(&mesh);
    for (raster, splats, triangles) in common::cloud_and_mesh_frames((&cloud, &mesh), &camera, size)
    {
        let (dots, reference) = (dark_dots(&splats), dark_dots(&triangles));
        eprintln!("{raster}: {dots} dark dots on the cloud, {reference} on the mesh");
        assert!(
            reference > 10,
            "{raster}: the mesh's dark pixels: {reference}"
        );
        assert!(
            dots <= reference,
            "{raster}: {dots} dark dots, the mesh {reference}"
        );
    }
}

/// Pixels inside a surface (their 3 × 3 neighbourhood covered) more than 40 levels
/// darker (the mean of R, G and B, sRGB) than the median of that neighbourhood.
fn dark_dots(image: &spt::render::Image) -> usize {
    let (w, h) = (image.width as usize, image.height as usize);
    let grey = |i: usize| {
        image.rgba[4 * i..][..3]
            .iter()
            .map(|&c| f32::from(c))
            .sum::<f32>()
            / 3.0
    };
    let mut dots = 0;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let around = (0..9).map(|k| (y + k / 3 - 1) * w + x + k % 3 - 1);
            if !around.clone().all(|i| image.covered[i]) {
                continue;
            }
            let mut greys: Vec<f32> = around.map(grey).collect();
            let median = *greys.select_nth_unstable_by(4, f32::total_cmp).1;
            dots += (median - grey(y * w + x) > 40.0) as usize;
        }
    }
    dots
}
