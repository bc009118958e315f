//! Each path's stages before its main loop tell their shares of the samples first
//! ([`super::progress::Stages`]), with the weights each path declares.

use super::progress::Progress;

/// The counts told while the leaf surfels of a `W` × `H` grid of points, (x, y) ↦
/// `at(x, y)`, are made (triangulated on the grid where `mesh`).
fn told(at: impl Fn(f64, f64) -> [f64; 3], mesh: bool) -> (u64, Vec<u64>) {
    const W: usize = 96;
    const H: usize = 64;
    let points: Vec<[f64; 3]> = (0..W * H)
        .map(|i| at((i % W) as f64, (i / W) as f64))
        .collect();
    let mut g = crate::io::Geometry::from_points(&points).unwrap().0;
    if mesh {
        g.triangles = (0..(W - 1) * (H - 1))
            .flat_map(|c| {
                let (v, w) = ((c % (W - 1) + c / (W - 1) * W) as u32, W as u32);
                [[v, v + 1, v + w + 1], [v, v + w + 1, v + w]]
            })
            .collect();
    }
    let counts = std::sync::Mutex::new(Vec::new());
    let listener = |n: u64| counts.lock().unwrap().push(n);
    super::leaf_surfels_with_progress(&g, Progress::to(&listener));
    ((W * H) as u64, counts.into_inner().unwrap())
}

#[test]
fn the_stages_before_a_path_s_main_loop_tell_their_shares_first() {
    let wave = |x: f64, y: f64| 0.5 * (x * 0.3).sin() * (y * 0.2).cos();
    let (n, mesh) = told(|x, y| [x * 0.01, y * 0.01, 0.01 * wave(x, y)], true);
    let w = crate::surfel::mesh::WEIGHTS;
    let shares = [w.faces, w.orient, w.rings].map(|w| n * u64::from(w) / 100);
    assert_eq!(mesh[..3], shares, "mesh: {mesh:?}");
    // A cylinder: neither a terrain nor a sensor frame.
    let (n, cloud) = told(
        |x, y| {
            let a = x / 96.0 * std::f64::consts::TAU;
            [a.cos(), a.sin(), y * 0.05]
        },
        false,
    );
    let grid = u64::from(crate::surfel::cloud::GRID_WEIGHT);
    assert_eq!(cloud[0], n * grid / 100, "cloud: {cloud:?}");
    // A terrain without classes: the vegetation test runs first.
    let (n, terrain) = told(|x, y| [x, y, wave(x, y)], false);
    let w = crate::surfel::layers::WEIGHTS;
    let all = u64::from(w.scatter + w.first_tin + w.free_standing + w.ground_tin + w.layers);
    let shares = [w.first_tin, w.free_standing, w.ground_tin].map(|w| n * u64::from(w) / all);
    let after_test = terrain.windows(3).position(|c| c == shares);
    let tested: u64 = terrain[..after_test.unwrap_or(0)].iter().sum();
    assert!(after_test.is_some(), "terrain: {terrain:?}");
    assert_eq!(
        tested,
        n * u64::from(w.scatter) / all,
        "terrain: {terrain:?}"
    );
}
