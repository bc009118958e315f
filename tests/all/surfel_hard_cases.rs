//! Leaf surfels on hard inputs: finite everywhere, unit normals, radii > 0, and on a
//! mesh every sampled point of every triangle inside the disk of one of its vertices.

use crate::common;

use glam::Vec3;
use spt::io::Geometry;
use spt::io::ply::{Encoding, FaceList, PolyMesh, read_ply};
use spt::surfel::{LeafSurfels, leaf_surfels, mesh_surfels_of};

fn load(mesh: &PolyMesh, name: &str) -> (Geometry, LeafSurfels) {
    common::mesh_leaves(mesh, name)
}

/// A bumpy 8 × 8 grid of quads (two triangles each).
fn grid() -> PolyMesh {
    let n = 8u32;
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let z = 0.3 * ((i as f64 * 0.9).sin() + (j as f64 * 1.3).cos());
            positions.push([i as f64 + 0.2 * (j % 2) as f64, j as f64, z]);
        }
    }
    let mut faces = FaceList::default();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            faces.push(&[at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            faces.push(&[at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    PolyMesh {
        positions,
        faces,
        ..PolyMesh::default()
    }
}

#[test]
fn default_model_disks_cover_every_triangle() {
    let g = read_ply(&common::default_model()).unwrap().geometry;
    let leaves = leaf_surfels(&g);
    common::assert_sane(&leaves, "torus knot");
    let checked = common::assert_covers(&g, &leaves, "torus knot");
    assert!(checked > 100_000 * 28);
    assert!(leaves.oriented_normals && leaves.has_colors);
    // The knot is a closed tube: normals point away from its centre line, so they agree
    // in sign with the direction from the bounding-box centre for most vertices on the
    // outer side; here simply check that neighbouring normals agree (no flipped ones).
    for t in &g.triangles {
        let n = t.map(|i| leaves.surfels[i as usize].normal);
        assert!(
            n[0].dot(n[1]) > 0.5 && n[1].dot(n[2]) > 0.5,
            "normals disagree on {t:?}"
        );
    }
}

#[test]
fn duplicated_vertices() {
    let mut m = grid();
    // Every vertex of the first row duplicated, the copy used by the faces of row 0.
    let row: Vec<[f64; 3]> = m.positions[..9].to_vec();
    m.positions.extend(row);
    for (k, i) in m.faces.indices.iter_mut().enumerate() {
        if k < 8 * 6 && *i < 9 {
            *i += 81;
        }
    }
    let (g, leaves) = load(&m, "duplicated.ply");
    common::assert_covers(&g, &leaves, "duplicated");
}

#[test]
fn zero_area_faces_are_skipped_and_counted() {
    let mut m = grid();
    let n = m.positions.len() as u32;
    m.positions.push([20.0, 20.0, 0.0]);
    m.positions.push([21.0, 21.0, 0.0]);
    m.positions.push([22.0, 22.0, 0.0]);
    m.faces.push(&[n, n + 1, n + 2]); // collinear
    m.faces.push(&[3, 3, 4]); // repeated index
    m.faces.push(&[5, 5, 5]); // a point
    let (g, leaves) = load(&m, "zero_area.ply");
    assert_eq!(leaves.stats.degenerate_triangles, 3);
    common::assert_covers(&g, &leaves, "zero area");
    // The collinear triangle's vertices still cover its segment: half the longest edge.
    let r = leaves.surfels[n as usize].radius as f64;
    assert!(r >= 2f64.sqrt() - 1e-6, "radius {r}");
}

/// Isolated vertices off the surface keep a disk from their neighbours; one on it,
/// within a held vertex's splat, is left out of the tree.
#[test]
fn isolated_vertices_get_disks_from_their_neighbours() {
    let mut m = grid();
    m.positions.push([3.5, 3.5, 2.0]);
    m.positions.push([100.0, 100.0, 100.0]);
    let on_surface = m.positions[4 * 9 + 4];
    m.positions
        .push([on_surface[0] + 0.1, on_surface[1], on_surface[2]]);
    let (g, leaves) = load(&m, "isolated.ply");
    assert_eq!(leaves.stats.isolated_vertices, 3);
    assert_eq!(leaves.redundant, vec![83]);
    common::assert_covers(&g, &leaves, "isolated");
    let far = leaves.surfels[82];
    assert!(far.radius > 0.0 && far.radius.is_finite());
    let list = spt::tree::build_sequential_list(leaves);
    assert_eq!(list.meta.leaf_count, 83);
}

#[test]
fn faces_back_to_back_do_not_cancel_to_nan() {
    let m = PolyMesh {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        faces: FaceList::triangles(&[[0, 1, 2], [0, 2, 1]]),
        ..PolyMesh::default()
    };
    let (g, leaves) = load(&m, "back_to_back.ply");
    assert_eq!(leaves.stats.cancelled_normals, 3);
    for s in &leaves.surfels {
        assert!(
            (s.normal.z.abs() - 1.0).abs() < 1e-6,
            "normal {:?}",
            s.normal
        );
    }
    common::assert_covers(&g, &leaves, "back to back");
}

/// The default model moved by `offset` and scaled by `scale` gives the same surfels
/// up to that scale.
fn same_surfels_after(offset: f64, scale: f64) {
    let base = read_ply(&common::default_model()).unwrap().geometry;
    let mut m = common::to_mesh(&base);
    for p in &mut m.positions {
        *p = p.map(|c| c * scale + offset);
    }
    let what = format!("offset {offset:e}, scale {scale:e}");
    let (g, leaves) = load(&m, "moved.ply");
    let reference = leaf_surfels(&base);
    assert_eq!(g.triangles, base.triangles);
    let extent = base.bounds.extent().max_element();
    for (i, (a, b)) in leaves.surfels.iter().zip(&reference.surfels).enumerate() {
        let pos_err = (a.position.as_dvec3() / scale - b.position.as_dvec3()).length() / extent;
        assert!(
            pos_err < 1e-6,
            "{what}: surfel {i} position off by {pos_err:e} of the extent"
        );
        let r = a.radius as f64 / scale;
        assert!(
            (r / b.radius as f64 - 1.0).abs() < 1e-4,
            "{what}: surfel {i} radius {r} vs {}",
            b.radius
        );
        assert!(
            a.normal.dot(b.normal) > 1.0 - 1e-5,
            "{what}: surfel {i} normal {} vs {}",
            a.normal,
            b.normal
        );
    }
    common::assert_covers(&g, &leaves, &what);
}

#[test]
fn offset_by_1e7_gives_the_same_surfels() {
    same_surfels_after(1e7, 1.0);
}

#[test]
fn scaled_by_1e_minus_7_gives_the_same_surfels_up_to_scale() {
    same_surfels_after(0.0, 1e-7);
}

#[test]
fn scaled_by_1e7_and_offset_gives_the_same_surfels_up_to_scale() {
    same_surfels_after(3e7, 1e7);
}

#[test]
fn identical_points_as_a_cloud() {
    let m = PolyMesh {
        positions: vec![[12.5, -3.0, 7.0]; 100_000],
        ..PolyMesh::default()
    };
    let (g, leaves) = load(&m, "identical.ply");
    assert_eq!(leaves.surfels.len(), 100_000);
    assert_eq!(g.bounds.min, [12.5, -3.0, 7.0]);
    assert_eq!(leaves.stats.fallback_radii, 100_000);
    assert!(!leaves.oriented_normals);
}

#[test]
fn single_point_and_two_points() {
    for n in [1, 2] {
        let m = PolyMesh {
            positions: (0..n).map(|i| [i as f64, 0.0, 0.0]).collect(),
            ..PolyMesh::default()
        };
        let (_, leaves) = load(&m, "few.ply");
        assert_eq!(leaves.surfels.len(), n);
        if n == 2 {
            assert_eq!(leaves.surfels[0].radius, 1.0, "two points one unit apart");
        }
    }
}

#[test]
fn collinear_cloud_and_plane_cloud() {
    let line = PolyMesh {
        positions: (0..1000)
            .map(|i| [i as f64 * 0.01, i as f64 * 0.02, 5.0])
            .collect(),
        ..PolyMesh::default()
    };
    let (_, leaves) = load(&line, "line.ply");
    let dir = Vec3::new(1.0, 2.0, 0.0).normalize();
    for s in &leaves.surfels {
        assert!(
            s.normal.dot(dir).abs() < 1e-3,
            "normal {:?} not across the line",
            s.normal
        );
    }
    let (_, leaves) = load(&sheet(false), "plane.ply");
    // A level sheet is a terrain (spt::surfel::terrain): each sample's ellipse covers
    // the triangles of its one-ring in the sheet's TIN, √2/2 (the circumradius of its
    // right triangles) inside a unit grid, up to 1 at a corner.
    for s in &leaves.surfels {
        assert!(s.normal.z.abs() > 0.999, "normal {:?}", s.normal);
        assert!(
            s.radius >= 0.5f32.sqrt() - 1e-5 && s.radius <= 1.0 + 1e-5,
            "radius {}",
            s.radius
        );
    }
}

/// A 20 × 20 grid of spacing 1 at height `z` (x, y in 0..20), or standing up at y = 2.
fn sheet(standing: bool) -> PolyMesh {
    PolyMesh {
        positions: (0..400)
            .map(|i| {
                let (a, b) = ((i % 20) as f64, (i / 20) as f64);
                if standing { [a, 2.0, b] } else { [a, b, 1.0] }
            })
            .collect(),
        ..PolyMesh::default()
    }
}

#[test]
fn a_frame_s_and_a_terrain_s_border_splats_end_at_their_border() {
    // Standing, the sheet is a sensor frame seen from the file's origin; lying flat, a
    // terrain (with no drop, so no walls). Either way its border splats are clipped at
    // their samples, keeping the sheet's side.
    for (standing, name) in [(true, "frame.ply"), (false, "tile.ply")] {
        let (_, leaves) = load(&sheet(standing), name);
        assert_eq!(leaves.surfels.len(), 400, "{name}: one surfel a sample");
        check_border_clips(&leaves, if standing { [0, 2] } else { [0, 1] });
    }
}

/// Every splat of `leaves` (a [`sheet`] across the `axes`) on the sheet's border is
/// clipped at its sample, keeping the sheet's side; no other splat is clipped.
fn check_border_clips(leaves: &spt::surfel::LeafSurfels, axes: [usize; 2]) {
    for s in &leaves.surfels {
        let shape = s.shape.unpack(s.normal.as_dvec3());
        let p = s.position.as_dvec3() + leaves.origin;
        let out = |c: f64| {
            if c == 0.0 {
                -1.0
            } else if c == 19.0 {
                1.0
            } else {
                0.0
            }
        };
        let mut outward = glam::DVec3::ZERO;
        for axis in axes {
            outward[axis] = out(p[axis]);
        }
        let Some(outward) = outward.try_normalize() else {
            assert_eq!(shape.clip, None, "inner splat at {p} clipped");
            continue;
        };
        let clip = shape
            .clip
            .unwrap_or_else(|| panic!("border splat at {p} unclipped"));
        let plane = |d: glam::DVec3| {
            glam::DVec2::new(
                d.dot(shape.axis),
                d.dot(shape.minor_axis(s.normal.as_dvec3())),
            )
        };
        assert!(clip.keeps(plane(-outward * 0.5)), "{p}: {clip:?}");
        assert!(!clip.keeps(plane(outward * 0.5)), "{p}: {clip:?}");
    }
}

#[test]
fn given_normals_are_honoured_and_zero_ones_recomputed() {
    let mut m = grid();
    let mut normals = vec![[0.0f32, 0.0, 2.0]; m.positions.len()];
    normals[5] = [0.0, 0.0, 0.0];
    m.normals = Some(normals);
    let dir = common::temp_dir();
    let path = dir.path().join("normals.ply");
    common::write_standard(&path, &m, Encoding::Ascii);
    let g = read_ply(&path).unwrap().geometry;
    let leaves = leaf_surfels(&g);
    common::assert_sane(&leaves, "given normals");
    assert_eq!(leaves.stats.given_normals, m.positions.len() as u64 - 1);
    assert_eq!(leaves.surfels[0].normal, Vec3::Z);
    assert_ne!(
        leaves.surfels[5].normal,
        Vec3::Z,
        "the zero normal is recomputed from faces"
    );
}

/// A closed surface: the 8 faces of an octahedron around (5, −2, 1), each wound
/// counter-clockwise seen from outside, or all reversed.
fn octahedron(inward: bool) -> PolyMesh {
    let c = [5.0, -2.0, 1.0];
    let mut positions = Vec::new();
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut p = c;
            p[axis] += sign * (1.0 + axis as f64);
            positions.push(p);
        }
    }
    let mut faces = FaceList::default();
    // Each edge (a, b) of the equator with the apex +z (vertex 4) and −z (vertex 5).
    for (a, b) in [(0, 2), (2, 1), (1, 3), (3, 0)] {
        for f in [[a, b, 4], [b, a, 5]] {
            faces.push(&if inward { [f[0], f[2], f[1]] } else { f });
        }
    }
    PolyMesh {
        positions,
        faces,
        ..PolyMesh::default()
    }
}

#[test]
fn normals_of_a_closed_mesh_face_outward_whichever_way_it_winds() {
    for inward in [false, true] {
        let (g, leaves) = load(&octahedron(inward), "octahedron.ply");
        assert_eq!(leaves.stats.sides.turned, inward as u64);
        let centre = g.positions.iter().sum::<Vec3>() / g.positions.len() as f32;
        for (p, s) in g.positions.iter().zip(&leaves.surfels) {
            assert!(
                (*p - centre).dot(s.normal) > 0.0,
                "inward {inward}: the normal {} at {p} faces in",
                s.normal
            );
        }
    }
}

/// A tile with a 5 m roof edge on a 1 m grid, built as a whole cloud and as the one
/// piece of an out-of-core mesh build that has no triangles (a PLY with an empty face
/// element; the fuzzer's find): both keep every sample's surfel and the same splats of
/// the wall's long triangles (spt::surfel::terrain), two per square of the 29 the edge
/// runs along.
#[test]
fn a_piece_without_triangles_keeps_its_samples_and_walls() {
    let points: Vec<[f64; 3]> = (0..30 * 30)
        .map(|i| {
            let (x, y) = ((i % 30) as f64, (i / 30) as f64);
            [x, y, if x < 15.0 { 5.0 } else { 0.0 }]
        })
        .collect();
    let g = common::geometry_of(&points);
    let whole = leaf_surfels(&g);
    let walls = whole.stats.added_splats() as usize;
    assert_eq!(walls, 29 * 2, "the wall's triangles");
    assert_eq!(whole.surfels.len(), points.len() + walls);
    let (piece, _) = mesh_surfels_of(&g, points.len(), (false, glam::DVec3::ZERO));
    assert_eq!(piece.stats.added_splats() as usize, walls);
    assert_eq!(piece.surfels.len(), points.len() + walls);
}

/// A bush as airborne LiDAR samples it: `clumps` leaves of 4 returns within 3 cm,
/// scattered in a 4 × 6 × 5 m box, sparser toward its top; a deterministic LCG.
fn bush(clumps: usize) -> Vec<[f64; 3]> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut points = Vec::new();
    for _ in 0..clumps {
        let z = 5.0 * next().sqrt();
        let centre = [4.0 * next(), 6.0 * next(), z];
        for _ in 0..4 {
            points.push(std::array::from_fn(|k| centre[k] + 0.03 * next()));
        }
    }
    points
}

#[test]
fn a_sparse_bush_gets_no_splat_near_its_own_size() {
    let points = bush(1500);
    let (geometry, _) = Geometry::from_points(&points).unwrap();
    let leaves = leaf_surfels(&geometry);
    let radii: Vec<f32> = leaves.surfels.iter().map(|s| s.radius).collect();
    let largest = radii.iter().copied().fold(0.0, f32::max);
    let mut sorted = radii.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    eprintln!(
        "bush of {} returns: radius median {median:.3} m, largest {largest:.3} m, capped {}",
        points.len(),
        leaves.stats.capped_radii
    );
    // The bush is 4 m across at its narrowest: no splat reaches a tenth of that.
    assert!(largest < 0.4, "largest radius {largest} m");
    assert!(leaves.stats.capped_radii > 0);
}

/// A tile 50 m square as an airborne scanner returns it: ground on a 0.5 m grid (class
/// 2) and, 7 m over it, the top of a crown 3 m in radius (class 5, or 1 when
/// `classified` is false), no ground returns under the crown.
fn tile_with_a_tree(classified: bool) -> Geometry {
    let mut points = Vec::new();
    let mut classes = Vec::new();
    for i in 0..100 {
        for j in 0..100 {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            let (dx, dy) = (x - 25.0, y - 25.0);
            let r2 = dx * dx + dy * dy;
            if r2 < 9.0 {
                points.push([x, y, 7.0 + (9.0 - r2).sqrt()]);
                classes.push(if classified { 5 } else { 1 });
            } else {
                points.push([x, y, 0.0]);
                classes.push(2);
            }
        }
    }
    let (mut g, _) = Geometry::from_points(&points).unwrap();
    g.attributes = Some(
        classes
            .iter()
            .map(|&c| spt::io::PointAttributes::new(0, c, 1, 1))
            .collect(),
    );
    g
}

#[test]
fn a_classified_crown_hangs_no_curtain_to_the_ground() {
    let (draped, apart) = (
        leaf_surfels(&tile_with_a_tree(false)),
        leaf_surfels(&tile_with_a_tree(true)),
    );
    let crown = tile_with_a_tree(true)
        .attributes
        .unwrap()
        .iter()
        .filter(|a| a.class == 5)
        .count() as u64;
    // A splat that reaches down from the crown (7 m up) to within 3 m of the ground.
    let hanging = |leaves: &LeafSurfels| spanning(leaves, 6.5, 3.0);
    eprintln!(
        "crown of {crown} returns: splats hanging to the ground {} unclassified, {} classified",
        hanging(&draped),
        hanging(&apart)
    );
    assert!(
        hanging(&draped) > 10,
        "the TIN drapes an unclassified crown"
    );
    assert_eq!(hanging(&apart), 0);
    assert_eq!(apart.stats.vegetation, crown);
    assert_eq!(
        apart.surfels.len() as u64,
        10_000 + apart.stats.added_splats()
    );
}

/// A hash of `k` in [0, 1): the same tile on every run, without a generator.
fn unit_hash(k: u64) -> f64 {
    let h = k.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (k >> 7);
    (h.wrapping_mul(0xbf58_476d_1ce4_e5b9) >> 11) as f64 / (1u64 << 53) as f64
}

/// A tile 40 m square of unclassified returns (class 1): ground on a 0.5 m grid, and
/// where a crown 3 m in radius stands 4 m over it, first returns inside the crown at a
/// random depth below its top (foliage), a return in four passing through to the ground.
fn tile_with_a_porous_crown() -> Geometry {
    let mut points = Vec::new();
    for i in 0..80 {
        for j in 0..80 {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            let (dx, dy) = (x - 20.0, y - 20.0);
            let r2 = dx * dx + dy * dy;
            let k = (i * 80 + j) as u64;
            if r2 < 9.0 && unit_hash(k) > 0.25 {
                let top = 7.0 + (9.0 - r2).sqrt();
                let depth = 2.0 * (9.0 - r2).sqrt() * unit_hash(k + 7919);
                points.push([x, y, top - depth]);
            } else {
                points.push([x, y, 0.0]);
            }
        }
    }
    let (mut g, _) = Geometry::from_points(&points).unwrap();
    g.attributes = Some(vec![
        spt::io::PointAttributes::new(0, 1, 1, 1);
        points.len()
    ]);
    g
}

/// The splats that reach from over `top` down to under `bottom` (height z).
fn spanning(leaves: &LeafSurfels, top: f64, bottom: f64) -> usize {
    leaves
        .surfels
        .iter()
        .filter(|s| {
            let reach = (s.radius * (1.0 - s.normal.z * s.normal.z).max(0.0).sqrt()) as f64;
            let z = at(leaves, s).z;
            z + reach > top && z - reach < bottom
        })
        .count()
}

/// Where splat `s` of `leaves` stands in the file's coordinates.
fn at(leaves: &LeafSurfels, s: &spt::surfel::Surfel) -> glam::DVec3 {
    s.position.as_dvec3() + leaves.origin
}

#[test]
fn an_unclassified_porous_crown_is_found_by_its_geometry_and_hangs_no_curtain() {
    let g = tile_with_a_porous_crown();
    let crown = (g.positions.iter())
        .filter(|p| p.z as f64 + g.origin.z > 0.5)
        .count() as u64;
    let leaves = leaf_surfels(&g);
    let found = leaves.stats.vegetation;
    // A splat from the crown's lower half (7 m up at most) down to within 2 m of the ground.
    let hanging = spanning(&leaves, 6.0, 2.0);
    eprintln!("crown of {crown} returns: {found} found as vegetation, {hanging} splats hanging");
    assert!(
        found >= crown * 9 / 10 && found <= crown + 20,
        "{found} of {crown}"
    );
    assert_eq!(hanging, 0);
    // The ground runs on under the crown: each point of a 0.25 m grid within 2.5 m of
    // the trunk lies within the radius of a ground splat (one under 0.5 m).
    let ground: Vec<glam::DVec3> = (leaves.surfels.iter())
        .filter(|s| at(&leaves, s).z < 0.5)
        .map(|s| at(&leaves, s).with_z(s.radius as f64))
        .collect();
    let open = (0..400)
        .map(|k| glam::DVec2::new(17.5 + 0.25 * (k % 20) as f64, 17.5 + 0.25 * (k / 20) as f64))
        .filter(|p| p.distance(glam::DVec2::splat(20.0)) < 2.5)
        .filter(|p| !ground.iter().any(|g| g.truncate().distance(*p) < g.z))
        .count();
    eprintln!("ground under the crown: {open} points of the grid uncovered");
    assert_eq!(open, 0);
    // A class that says what a sample is (here a building's) is trusted.
    let mut classified = g;
    for a in classified.attributes.as_mut().unwrap() {
        a.class = 6;
    }
    assert_eq!(leaf_surfels(&classified).stats.vegetation, 0);
}

/// A gully 6 m deep across a tile 40 m square (ground, class 2, on a 0.5 m grid) under a
/// bridge deck 8 m wide at 3 m (class 17, when `deck_class`; else 6, a building's), seen
/// from straight above: no return under the deck. With `wall`, a sample 1.5 m under
/// each of the deck's samples on its south edge, as a pulse from the south would find
/// on a wall there.
fn tile_with_a_bridge(deck_class: u8, wall: bool) -> Geometry {
    let (mut points, mut classes) = (Vec::new(), Vec::new());
    for i in 0..80 {
        for j in 0..80 {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            let across = (x - 20.0) / 12.0;
            let floor = -6.0 * (1.0 - across * across).max(0.0);
            let on_deck = (16.0..24.0).contains(&y) && (4.0..36.0).contains(&x);
            points.push([x, y, if on_deck { 3.0 } else { floor }]);
            classes.push(if on_deck { deck_class } else { 2 });
            if wall && on_deck && y == 16.0 {
                points.push([x, y - 0.05, 1.5]);
                classes.push(deck_class);
            }
        }
    }
    let (mut g, _) = Geometry::from_points(&points).unwrap();
    let attributes = classes
        .iter()
        .map(|&c| spt::io::PointAttributes::new(0, c, 1, 1));
    g.attributes = Some(attributes.collect());
    g
}

#[test]
fn a_bridge_deck_and_a_roof_no_sample_shows_a_wall_under_stand_free() {
    let (deck, roof, walled) = (
        leaf_surfels(&tile_with_a_bridge(17, false)),
        leaf_surfels(&tile_with_a_bridge(6, false)),
        leaf_surfels(&tile_with_a_bridge(6, true)),
    );
    // Splats centred between the deck (3 m) and the floor where the gully is deep
    // (x 14–26, floor under −4 m): a wall's, from the deck's edge to the floor.
    let walls = |leaves: &LeafSurfels| {
        (leaves.surfels.iter())
            .map(|s| at(leaves, s))
            .filter(|p| (14.0..26.0).contains(&p.x) && (-3.0..1.0).contains(&p.z))
            .count()
    };
    // The gully floor's splats under the deck's middle.
    let under = |leaves: &LeafSurfels| {
        (leaves.surfels.iter())
            .filter(|s| at(leaves, s).z < -3.0 && (18.0..22.0).contains(&at(leaves, s).y))
            .count()
    };
    let seen = [&deck, &roof, &walled].map(|l| (walls(l), under(l), l.stats.decks));
    eprintln!(
        "(splats from the deck down to the floor, floor splats under it, samples drawn as a deck): as a deck {:?}, as a roof {:?}, as a roof on a sampled wall {:?}",
        seen[0], seen[1], seen[2]
    );
    assert!(
        walls(&walled) > 10,
        "a roof on a sampled wall stands on walls"
    );
    assert_eq!(under(&walled), 0);
    for free in [&deck, &roof] {
        assert_eq!(walls(free), 0);
        assert!(under(free) > 10);
    }
    // 16 rows of 64 samples.
    assert_eq!(seen.map(|s| s.2), [1024, 1024, 0]);
}
