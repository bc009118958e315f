//! Which side of a mesh faces out (`spt::surfel::outward`): closed pieces vote by the
//! divergence theorem, open ones keep the file's winding and are drawn two-sided.

use crate::common;

use glam::DVec3;
use spt::io::formats::read_model;
use spt::io::ply::{FaceList, PolyMesh};
use spt::io::triangulate::sensor_grid;
use spt::surfel::outward::Sides;
use spt::surfel::{NormalsTurned, leaf_surfels};

/// Centre of the quarter sphere.
const CENTRE: [f64; 3] = [3.0, -1.0, 2.0];

/// A quarter sphere of radius 2 about [`CENTRE`] (longitudes 0–90°, latitudes
/// 10–170°), 24 × 24 quads, each triangle wound to face the centre (a viewer inside,
/// on its concave side) or away from it.
fn quarter_sphere(toward_centre: bool) -> PolyMesh {
    let n = 24;
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let lon = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
            let lat = (10.0 + 160.0 * j as f64 / n as f64).to_radians();
            let d = DVec3::new(lat.sin() * lon.cos(), lat.sin() * lon.sin(), lat.cos());
            positions.push((DVec3::from(CENTRE) + 2.0 * d).to_array());
        }
    }
    let at = |i: u32, j: u32| i * (n + 1) + j;
    let mut faces = FaceList::default();
    for i in 0..n {
        for j in 0..n {
            // South (latitude up) then east: (b − a) × (c − a) points out of the
            // sphere; reversed, in.
            for t in [
                [at(i, j), at(i, j + 1), at(i + 1, j)],
                [at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)],
            ] {
                faces.push(&if toward_centre { [t[0], t[2], t[1]] } else { t });
            }
        }
    }
    PolyMesh {
        positions,
        faces,
        ..PolyMesh::default()
    }
}

/// The open quarter sphere, a concave sheet: the flux vote about its mean vertex says
/// "inward" whichever way it winds. Kept as written both ways, and drawn two-sided.
#[test]
fn a_concave_open_sheet_keeps_the_side_it_is_wound_to_face() {
    let open = Sides {
        open: 1,
        two_sided: true,
        ..Sides::default()
    };
    for toward_centre in [true, false] {
        let (g, leaves) = common::mesh_leaves(&quarter_sphere(toward_centre), "quarter.ply");
        assert_eq!(
            leaves.stats.sides, open,
            "toward the centre: {toward_centre}"
        );
        assert!(leaves.two_sided, "an open sheet's front is not known");
        // Positions are relative to the model's origin; the centre too, then.
        let centre = (DVec3::from(CENTRE) - leaves.origin).as_vec3();
        for (p, s) in g.positions.iter().zip(&leaves.surfels) {
            let facing = (centre - *p).dot(s.normal);
            assert!(
                (facing > 0.0) == toward_centre,
                "toward the centre {toward_centre}: the normal {} at {p} turned",
                s.normal
            );
        }
    }
}

/// The default model, the generated torus knot, is closed and wound inward: still
/// turned outward.
#[test]
fn the_knot_wound_inward_is_still_turned_outward() {
    let model = read_model(&common::default_model()).unwrap();
    let leaves = leaf_surfels(&model.geometry);
    let turned = Sides {
        turned: 1,
        ..Sides::default()
    };
    assert_eq!(leaves.stats.sides, turned);
    assert!(leaves.oriented_normals && !leaves.two_sided);
}

/// Bunny, open at its base: closed enough to vote (its holes' vector area is 0.0085 of
/// its area), and it faces outward as wound.
#[test]
fn bunny_open_at_its_base_votes_and_keeps_its_normals() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let model = read_model(&dir.join("bunny.ply")).unwrap();
    let leaves = leaf_surfels(&model.geometry);
    let kept = Sides {
        kept: 1,
        ..Sides::default()
    };
    assert_eq!(leaves.stats.sides, kept);
    assert!(leaves.oriented_normals && !leaves.two_sided);
}

/// The shared kinect frame triangulated on its sensor grid, its triangles wound to
/// face the sensor (at the file's origin) or away: either way drawn as the frame's
/// cloud is, on the cloud's pixel grid, its normals facing the sensor.
#[test]
fn a_depth_frame_meshed_on_its_grid_faces_its_sensor_as_its_cloud_does() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let cloud = read_model(&dir.join("kinect_rgb.ply")).unwrap().geometry;
    let grid = leaf_surfels(&cloud).stats.pixel_grid;
    assert!(grid.is_some(), "the cloud is a frame");
    for away in [false, true] {
        let mut g = cloud.clone();
        g.triangles = sensor_grid(&g, 640, 480).unwrap();
        if away {
            g.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        }
        let leaves = leaf_surfels(&g);
        assert_eq!(leaves.stats.pixel_grid, grid, "wound away: {away}");
        assert_eq!(leaves.normals_turned, NormalsTurned::TowardOrigin);
        let sensor = (-leaves.origin).as_vec3();
        let facing = (g.positions.iter().zip(&leaves.surfels))
            .filter(|(p, s)| (sensor - **p).dot(s.normal) > 0.0)
            .count();
        let all = g.positions.len();
        assert!(
            facing as f64 > 0.95 * all as f64,
            "wound away {away}: {facing} of {all} normals face the sensor"
        );
    }
}
