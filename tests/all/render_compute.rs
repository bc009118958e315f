//! The compute rasterizer (`--raster compute`, `spt::render::Raster`) against the raster
//! pipeline: the same picture, measured as each path's FLIP against the supersampled
//! mesh (the meshes) or against the cloud's own triangulation (the clouds, through
//! `spt::apps::cloud_quality`), and a frame that is the same bytes every run. Pass 3 in
//! compute against the fragment pass: the same pixels within one 8-bit step, and its
//! sRGB encoding exact.
//!
//! The FLIP comparisons shade both paths with the fragment pass
//! (`common::fragment_shading_renderer`), as their references are: lavapipe's raster
//! pipeline encodes sRGB a little low (of the 256 levels given half a step and 0.01
//! above, 231 come back one step low), which pass 3 in compute does not, and against
//! references encoded that way its exact bytes measured 2–4 % higher FLIP (bunny,
//! leaves: 0.0136 → 0.0142, 2026-12-03). A GPU's raster pipeline encodes exactly.
//!
//! Measured on lavapipe (2026-11-27), 4 orbit views, 512², medians, FLIP hardware →
//! compute (covered pixels equal in every case):
//! * knot: ε = 1 px 0.0410 → 0.0407, leaves 0.0414 → 0.0411;
//! * bunny: 0.0145 → 0.0143, leaves 0.0139 → 0.0136;
//! * dragon40k: 0.0180 → 0.0179, leaves 0.0179 → 0.0176;
//! * kinect_rgb (leaves, against its sensor grid): 0.1176 → 0.1175, holes 0.196 % both;
//! * terrain_utm (leaves, against its TIN, 2026-11-28): 0.1721 → 0.1720, holes 0.013 %
//!   both.
//!
//! The compute path's sums are exact (fixed point) where the raster path's are half
//! floats: its FLIP is the same or a little lower.
//!
//! Asserted: the compute path's FLIP within [`SAME_PICTURE`] of the raster path's, its
//! covered pixels within [`SAME_COVERAGE`], and two frames byte-identical.

use crate::common;

use spt::apps::cloud_quality::{CloudAndReference, Triangulation, ViewFigures, measure};
use spt::apps::stats::quantile;
use spt::eval::perceptual::{downsample, flip_mean};
use spt::render::{Camera, Image, Mode, PrefixCut, Raster, Settings};
use spt::tree::scene::Scene;

/// How much higher the compute path's median FLIP may be than the raster path's: 2 %.
const SAME_PICTURE: f64 = 0.02;
/// How much lower it may be: 5 %. Its sums are exact where the raster path's round to
/// half floats (measured: up to 2.4 % lower, bunny's leaves).
const BETTER: f64 = 0.05;
/// Largest relative difference of the number of covered pixels: 0.2 %.
const SAME_COVERAGE: f64 = 0.002;
const SIZE: u32 = 512;

fn median(mut values: Vec<f64>) -> f64 {
    quantile(&mut values, 0.5).expect("views")
}

fn covered(image: &Image) -> usize {
    image.covered.iter().filter(|c| **c).count()
}

/// Both paths' median FLIP against the mesh rendered at 4×4, over 4 orbit views, and
/// their covered pixels in all, for `settings` (whose `raster` is set for each path).
fn flip_of_both(scene: &Scene, settings: Settings, what: &str) -> [(f64, usize); 2] {
    let r = common::fragment_shading_renderer();
    let gpu = r.upload(scene);
    let fov = 45f64.to_radians();
    let mut flips = [Vec::new(), Vec::new()];
    let mut pixels = [0, 0];
    for k in 0..4 {
        let camera = Camera::orbit(scene.meta(), 30.0 + 90.0 * k as f64, 20.0, 2.2, fov);
        let (fine, _) = r
            .render(scene, &gpu, &camera, &Settings::mesh(), SIZE * 4, SIZE * 4)
            .unwrap();
        let reference = downsample(&fine, 4);
        for (i, raster) in Raster::ALL.into_iter().enumerate() {
            let settings = Settings { raster, ..settings };
            let (image, _) = r
                .render(scene, &gpu, &camera, &settings, SIZE, SIZE)
                .unwrap();
            flips[i].push(flip_mean(&image, &reference));
            pixels[i] += covered(&image);
        }
    }
    let [hardware, compute] = flips.map(median);
    eprintln!(
        "{what}: FLIP hardware {hardware:.4}, compute {compute:.4}; covered pixels {} and {}",
        pixels[0], pixels[1]
    );
    [(hardware, pixels[0]), (compute, pixels[1])]
}

/// FLIP `c` of the compute path no more than [`SAME_PICTURE`] above the raster path's
/// `h`, and no further below than [`BETTER`] (more would be another picture, not the
/// same one with exact sums).
fn assert_same_flip(c: f64, h: f64, what: &str) {
    assert!(
        c <= (1.0 + SAME_PICTURE) * h && c >= (1.0 - BETTER) * h,
        "{what}: FLIP {c} in compute, {h} through the raster pipeline"
    );
}

fn assert_same_picture([(h, hp), (c, cp)]: [(f64, usize); 2], what: &str) {
    assert_same_flip(c, h, what);
    let spread = (cp as f64 - hp as f64).abs() / hp.max(1) as f64;
    assert!(
        spread <= SAME_COVERAGE,
        "{what}: {cp} pixels covered in compute, {hp} through the raster pipeline"
    );
}

#[test]
fn the_compute_path_draws_the_meshes_as_the_raster_path_does() {
    if !common::renderer().gpu.compute_raster {
        return;
    }
    let mut models = vec![(common::default_model(), "torus knot")];
    if let Some(dir) = common::shared_data() {
        models.push((dir.join("bunny.ply"), "bunny"));
        models.push((dir.join("dragon40k.ply"), "dragon40k"));
    }
    for (path, name) in models {
        let scene = Scene::open(&path).unwrap();
        for (settings, how) in [
            (Settings::default(), "ε 1 px"),
            (Settings::leaves(), "leaves"),
        ] {
            let what = format!("{name}, {how}");
            assert_same_picture(flip_of_both(&scene, settings, &what), &what);
        }
    }
}

/// `spt::apps::cloud_quality`'s figures of `file` with both paths: median FLIP and
/// hole rate, leaves only.
fn cloud_figures(file: &str, triangulation: Triangulation) -> Option<[(f64, f64); 2]> {
    let dir = common::shared_data()?;
    if !common::renderer().gpu.compute_raster {
        return None;
    }
    let models = CloudAndReference::open(&dir.join(file), triangulation).unwrap();
    let run = |raster| {
        let settings = Settings {
            raster,
            ..Settings::leaves()
        };
        let figures = measure(
            common::fragment_shading_renderer(),
            &models,
            (4, 1.6, 512),
            &settings,
            &mut |_, _| {},
        )
        .unwrap();
        let get = |f: fn(&ViewFigures) -> f64| median(figures.iter().map(f).collect());
        (get(|f| f.splat_flip), get(|f| f.hole_rate))
    };
    let both = Raster::ALL.map(run);
    eprintln!(
        "{file}: FLIP hardware {:.4}, compute {:.4}; holes {:.3} % and {:.3} %",
        both[0].0,
        both[1].0,
        100.0 * both[0].1,
        100.0 * both[1].1
    );
    Some(both)
}

#[test]
fn the_compute_path_draws_the_clouds_as_the_raster_path_does() {
    let cases = [
        (
            "kinect_rgb.ply",
            Triangulation::Grid {
                width: 640,
                height: 480,
            },
        ),
        ("terrain_utm.ply", Triangulation::Terrain),
    ];
    for (file, triangulation) in cases {
        let Some([(h, h_holes), (c, c_holes)]) = cloud_figures(file, triangulation) else {
            return;
        };
        assert_same_flip(c, h, file);
        // Hole rates of 0.01–0.2 %: within a tenth of a percentage point of each other.
        assert!(
            (c_holes - h_holes).abs() <= 0.001,
            "{file}: holes {c_holes} in compute, {h_holes} through the raster pipeline"
        );
    }
}

/// The fixed-point sums do not depend on the order the threads add them in: two
/// frames of the same view are the same bytes, in every kind of frame (splats, points,
/// a cloud's slits and fills), where the raster pipeline's blending order changes the
/// low bits of a half-float sum from run to run under compute culling.
#[test]
fn a_frame_drawn_in_compute_is_the_same_bytes_every_time() {
    if !common::renderer().gpu.compute_raster {
        return;
    }
    let knot = Scene::open(&common::default_model()).unwrap();
    let mut cases = vec![
        (knot, Mode::Shaded, "knot"),
        (
            Scene::open(&common::default_model()).unwrap(),
            Mode::Points,
            "knot as points",
        ),
    ];
    if let Some(dir) = common::shared_data() {
        cases.push((
            Scene::open(&dir.join("terrain_utm.ply")).unwrap(),
            Mode::Shaded,
            "terrain_utm",
        ));
    }
    let r = common::renderer();
    for (scene, mode, what) in cases {
        let gpu = r.upload(&scene);
        let camera = Camera::orbit(scene.meta(), 30.0, 30.0, 1.6, 45f64.to_radians());
        let settings = Settings {
            mode,
            raster: Raster::Compute,
            ..Settings::default()
        };
        let frame = || {
            r.render(&scene, &gpu, &camera, &settings, 256, 256)
                .unwrap()
                .0
        };
        let (first, second) = (frame(), frame());
        assert!(covered(&first) > 256 * 256 / 10, "{what}: drawn");
        assert!(first.rgba == second.rgba, "{what}: two frames differ");
        assert!(first.depth == second.depth, "{what}: depths differ");
    }
}

/// Pass 3 as one compute thread per pixel (after the compute rasterizer, where the
/// adapter can store into the output's `Rgba8Unorm` view) shades as the full-screen
/// fragment pass does: the same covered pixels, and colours within one 8-bit step of
/// the raster pipeline's sRGB encoding (the shader encodes its own). Measured on
/// lavapipe (2026-12-03, 256², orbit 30°/30°), bytes of 262,144 that differ, each by
/// one step: knot 6,152, as points 6,050, its normals 5,164, in eye-dome lighting
/// 5,854, terrain_utm (gaps filled) 10,944.
#[test]
fn shading_in_compute_matches_the_fragment_pass() {
    let compute = common::renderer();
    if !compute.gpu.compute_shading {
        return;
    }
    let fragment = common::fragment_shading_renderer();
    let knot = || Scene::open(&common::default_model()).unwrap();
    let mut cases = vec![
        (knot(), Mode::Shaded, "knot"),
        (knot(), Mode::Points, "knot as points"),
        (knot(), Mode::Normals, "knot's normals"),
        (knot(), Mode::Edl, "knot in eye-dome lighting"),
    ];
    if let Some(dir) = common::shared_data() {
        let terrain = Scene::open(&dir.join("terrain_utm.ply")).unwrap();
        cases.push((terrain, Mode::Shaded, "terrain_utm"));
    }
    for (scene, mode, what) in cases {
        let camera = Camera::orbit(scene.meta(), 30.0, 30.0, 1.6, 45f64.to_radians());
        let settings = Settings {
            mode,
            raster: Raster::Compute,
            ..Settings::default()
        };
        let [a, b] = [compute, fragment].map(|r| {
            let gpu = r.upload(&scene);
            r.render(&scene, &gpu, &camera, &settings, 256, 256)
                .unwrap()
                .0
        });
        assert!(covered(&a) > 256 * 256 / 10, "{what}: drawn");
        assert!(a.covered == b.covered, "{what}: covered pixels differ");
        let steps: Vec<u8> = a
            .rgba
            .iter()
            .zip(&b.rgba)
            .map(|(x, y)| x.abs_diff(*y))
            .collect();
        let differing = steps.iter().filter(|d| **d > 0).count();
        let largest = steps.iter().max().copied().unwrap_or(0);
        eprintln!(
            "{what}: {differing} of {} bytes differ, by at most {largest}",
            steps.len()
        );
        assert!(largest <= 1, "{what}: a colour differs by {largest} steps");
    }
}

/// Pass 3 in compute encodes sRGB exactly: a background given as each 8-bit level, and
/// as half a step less and more 0.01 above it, comes back as the level it rounds to, in
/// every one of the 256 (pass 3 shades the background too).
#[test]
fn shading_in_compute_encodes_srgb_exactly() {
    let r = common::renderer();
    if !r.gpu.compute_shading {
        return;
    }
    let scene = Scene::open(&common::default_model()).unwrap();
    let gpu = r.upload(&scene);
    let camera = Camera::orbit(scene.meta(), 30.0, 20.0, 2.2, 45f64.to_radians());
    let targets = r.targets((16, 16)).unwrap();
    for level in 0..=255u8 {
        let at = |offset: f32| (level as f32 + offset).clamp(0.0, 255.0) / 255.0;
        let settings = Settings {
            raster: Raster::Compute,
            background: [at(0.0), at(0.49), at(0.51)],
            ..Settings::default()
        };
        let (image, _) = r
            .render_into(&targets, &scene, &gpu, &camera, &settings)
            .unwrap();
        assert!(!image.covered[0], "the corner shows the background");
        let want = [level, level, level.saturating_add(1)];
        assert_eq!(image.rgba[0..3], want, "level {level}");
    }
}

/// Ending each chunk's prefix at its block rather than its node hands the GPU more
/// nodes to test and draws the same bytes: the GPU's test rejects every node past the
/// exact end (compute rasterization, whose frames do not depend on the order of the
/// survivors).
#[test]
fn a_prefix_cut_at_the_block_draws_what_one_cut_at_the_node_draws() {
    if !common::renderer().gpu.compute_raster {
        return;
    }
    let mut cases = vec![(Scene::open(&common::default_model()).unwrap(), "knot")];
    if let Some(dir) = common::shared_data() {
        cases.push((
            Scene::open(&dir.join("terrain_utm.ply")).unwrap(),
            "terrain_utm",
        ));
    }
    let r = common::renderer();
    for (scene, what) in cases {
        let gpu = r.upload(&scene);
        let camera = Camera::orbit(scene.meta(), 30.0, 30.0, 1.6, 45f64.to_radians());
        let frame = |prefix_cut| {
            let settings = Settings {
                raster: Raster::Compute,
                prefix_cut,
                ..Settings::default()
            };
            r.render(&scene, &gpu, &camera, &settings, 256, 256)
                .unwrap()
        };
        let ((node, node_stats), (block, block_stats)) =
            (frame(PrefixCut::Node), frame(PrefixCut::Block));
        eprintln!(
            "{what}: nodes tested, cut at the node {}, at the block {}",
            node_stats.tested, block_stats.tested
        );
        assert!(
            block_stats.tested > node_stats.tested,
            "{what}: the block cut tests more"
        );
        assert_eq!(
            block_stats.selected, node_stats.selected,
            "{what}: survivors"
        );
        assert!(node.rgba == block.rgba, "{what}: the pictures differ");
        assert!(node.depth == block.depth, "{what}: depths differ");
    }
}
