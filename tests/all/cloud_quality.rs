//! Real clouds against a triangulation of their own points, with `SPT_DATA`:
//! the RGB-D frame on its sensor grid, the LiDAR tile as a 2.5D Delaunay terrain; 4 orbit
//! views at elevation 20°, distance 1.6, 512², leaves-only splats against the
//! triangulation rendered at 4×4 and averaged in linear light (`spt::apps::cloud_quality`).
//!
//! What this asserts is what holds today, so that it cannot get worse unnoticed: the
//! bounds below sit just above the measured medians and worst views (lavapipe,
//! 2026-11-24; docs/point-clouds.md):
//! * kinect_rgb: FLIP 0.118, holes 0.20 %, worst view 0.39 % (splats of its pixel
//!   grid's triangles, `spt::surfel::grid`, a long triangle's its own,
//!   `spt::surfel::long_triangles`; 0.175 when the vertices' ellipses reached along
//!   them);
//! * terrain_utm: FLIP 0.119, holes 0.010 %, worst view 0.023 % (splats of its TIN, a
//!   long triangle's its own and as thin as it, `spt::surfel::terrain`; 0.124 with
//!   ellipses no thinner than a quarter, 0.153 with the cloud's coverings shaded by the
//!   TIN and walls guessed from each sample's steepest drop, 0.178 with normals fitted
//!   to 24 neighbours);
//! * autzen_trim.laz: FLIP 0.110, holes 0.022 %, worst view 0.041 % (0.127 with
//!   ellipses no thinner than a quarter, 0.162 before the TIN's splats, 0.286 before
//!   the tile's spacing bounded the coverings).
//!
//! With disks of the nearest neighbours' spacing they were 0.37 / 8.9 % and
//! 0.26 / 1.0 %. The hole bound (0.5 %) holds on every view, and is asserted on the worst; the FLIP bound
//! (0.12) is asserted on both clouds. Level of detail at ε = 1 px stays within
//! [`LOD_COST`] of the leaves' FLIP (measured: terrain 1.00, autzen 1.08, kinect 1.09),
//! so that work on the inner nodes cannot blur or blot a cloud's level of detail
//! unnoticed.
//! The display modes of clouds (EDL, elevation) are checked on the tile.

use crate::common;

use spt::apps::cloud_quality::{CloudAndReference, Triangulation, ViewFigures, measure};
use spt::apps::stats::quantile;
use spt::render::{Camera, Mode, Settings};

/// Largest median FLIP at ε = 1 px over the leaves' median FLIP, at most 10 % more. It
/// was 1.25 on the tiles and 1.55 on the frame until a node's errors saw its children
/// as their ellipses (`spt::tree::errors`): as disks of their major semi-axis, a fan of
/// needles from a tree's top or a frame's risers reached a crown's width sideways, and
/// a parent as wide overhung them by nothing, so that level of detail drew blobs over
/// the spires and across the slits between the risers (autzen 1.50×, kinect 1.48×).
const LOD_COST: f64 = 1.1;

fn median(figures: &[ViewFigures], get: fn(&ViewFigures) -> f64) -> f64 {
    quantile(&mut figures.iter().map(get).collect::<Vec<_>>(), 0.5).unwrap()
}

/// Asserts the median FLIP over the views, and the median and worst views' hole rates.
/// And the median FLIP at ε = 1 px, within `lod_cost` of the leaves'.
fn check(
    file: &str,
    triangulation: Triangulation,
    (max_flip, lod_cost): (f64, f64),
    max_holes: [f64; 2],
) {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let models = CloudAndReference::open(&dir.join(file), triangulation).unwrap();
    let run = |settings: &Settings| {
        measure(
            common::renderer(),
            &models,
            (4, 1.6, 512),
            settings,
            &mut |_, _| {},
        )
        .unwrap()
    };
    let figures = run(&Settings::leaves());
    let flip = median(&figures, |f| f.splat_flip);
    let lod_flip = median(&run(&Settings::default()), |f| f.splat_flip);
    let holes = median(&figures, |f| f.hole_rate);
    let worst = figures.iter().map(|f| f.hole_rate).fold(0.0, f64::max);
    let mesh = median(&figures, |f| f.mesh_flip);
    eprintln!(
        "{file}: splat FLIP {flip:.4} (triangulation at 1x {mesh:.4}; ε = 1 px {lod_flip:.4}), \
         holes {:.3} % (worst view {:.3} %)",
        100.0 * holes,
        100.0 * worst
    );
    assert!(
        mesh > 0.0 && mesh < 0.1,
        "{file}: the reference's own aliasing {mesh}"
    );
    assert!(flip <= max_flip, "{file}: FLIP {flip} over {max_flip}");
    assert!(
        lod_flip <= lod_cost * flip,
        "{file}: FLIP {lod_flip} at ε = 1 px, {flip} for the leaves"
    );
    assert!(
        holes <= max_holes[0],
        "{file}: holes {holes} over {max_holes:?}"
    );
    assert!(
        worst <= max_holes[1],
        "{file}: holes {worst} over {max_holes:?}"
    );
}

#[test]
fn kinect_frame_against_its_sensor_grid() {
    let grid = Triangulation::Grid {
        width: 640,
        height: 480,
    };
    check("kinect_rgb.ply", grid, (0.12, LOD_COST), [0.0025, 0.0045]);
}

/// The reference drapes each tree in a tent of triangles down to the ground; the
/// splats draw the tile's vegetation apart (`spt::surfel::layers`), as foliage over
/// open ground: that difference, at the trees, takes FLIP from 0.119 (draped) to 0.172.
#[test]
fn terrain_tile_against_its_delaunay_terrain() {
    check(
        "terrain_utm.ply",
        Triangulation::Terrain,
        (0.175, LOD_COST),
        [0.0015, 0.003],
    );
}

/// Autzen's river, sampled by a few returns off the water, is where its reference leaves
/// gaps and its splats once closed them with one sheet; its TIN drops the triangles
/// across them (`spt::io::triangulate::height_field`). Its trees, draped by the
/// reference and drawn apart by the splats, take FLIP from 0.112 to 0.163 and leave
/// the reference's tents as holes (0.10 %, 0.20 % in the worst view).
#[test]
fn lidar_tile_with_a_sparse_river_against_its_delaunay_terrain() {
    check(
        "autzen_trim.laz",
        Triangulation::Terrain,
        (0.165, LOD_COST),
        [0.002, 0.004],
    );
}

#[test]
fn edl_darkens_and_elevation_colours_the_tile() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let scene = spt::tree::scene::Scene::open(&dir.join("terrain_utm.ply")).unwrap();
    let r = common::renderer();
    let gpu = r.upload(&scene);
    let camera = Camera::orbit(scene.meta(), 30.0, 35.0, 1.6, 45f64.to_radians());
    let image = |mode| {
        let settings = Settings {
            mode,
            ..Settings::default()
        };
        r.render(&scene, &gpu, &camera, &settings, 256, 256)
            .unwrap()
            .0
    };
    let (shaded, edl, elevation) = (
        image(Mode::Shaded),
        image(Mode::Edl),
        image(Mode::Elevation),
    );
    let covered = |img: &spt::render::Image| img.covered.iter().filter(|c| **c).count();
    assert!(covered(&shaded) > 256 * 256 / 8);
    assert_eq!(
        covered(&edl),
        covered(&shaded),
        "EDL covers what shading does"
    );
    let mean = |img: &spt::render::Image, channel: usize| {
        let px: Vec<f64> = (0..img.covered.len())
            .filter(|&i| img.covered[i])
            .map(|i| img.rgba[4 * i + channel] as f64)
            .collect();
        px.iter().sum::<f64>() / px.len() as f64
    };
    // The tile is grey: EDL darkens it where depth steps; elevation gives it hues.
    assert!(
        mean(&edl, 1) < mean(&shaded, 1) - 5.0,
        "EDL does not darken"
    );
    let hue_spread = (0..3).map(|c| mean(&elevation, c)).fold(f64::NAN, f64::max)
        - (0..3).map(|c| mean(&elevation, c)).fold(f64::NAN, f64::min);
    assert!(hue_spread > 20.0, "elevation is not coloured: {hue_spread}");
}
