//! The surfels step's progress: on each path (a mesh's rings, a cloud's
//! neighbourhoods, a terrain's TIN, a sensor frame's grid) the counts told add up to
//! the model's samples and come block by block as the fits go, not all at the end.

use std::sync::Mutex;

use spt::io::Geometry;
use spt::surfel::progress::Progress;
use spt::surfel::{LeafSurfels, NormalsTurned, leaf_surfels_with_progress};

const W: usize = 128;
const H: usize = 96;

/// Points on a `W` × `H` grid, (x, y) ↦ `at(x, y)`, row by row.
fn grid(at: impl Fn(f64, f64) -> [f64; 3]) -> Vec<[f64; 3]> {
    (0..W * H)
        .map(|i| at((i % W) as f64, (i / W) as f64))
        .collect()
}

/// The counts told while `g`'s leaf surfels are made, in order.
fn told(g: &Geometry) -> (Vec<u64>, LeafSurfels) {
    let counts = Mutex::new(Vec::new());
    let listener = |n: u64| counts.lock().unwrap().push(n);
    let leaves = leaf_surfels_with_progress(g, Progress::to(&listener));
    (counts.into_inner().unwrap(), leaves)
}

fn cloud(points: &[[f64; 3]]) -> Geometry {
    Geometry::from_points(points).unwrap().0
}

#[test]
fn every_path_tells_its_samples_as_it_fits_them() {
    let wave = |x: f64, y: f64| 0.02 * (x * 0.3).sin() * (y * 0.2).cos();
    // A mesh: a wavy sheet triangulated on its grid.
    let mut mesh = cloud(&grid(|x, y| [x * 0.01, y * 0.01, wave(x, y)]));
    mesh.triangles = (0..(W - 1) * (H - 1))
        .flat_map(|c| {
            let (v, w) = ((c % (W - 1) + c / (W - 1) * W) as u32, W as u32);
            [[v, v + 1, v + w + 1], [v, v + w + 1, v + w]]
        })
        .collect();
    // A cloud: a cylinder about the origin (neither a terrain nor a sensor frame).
    let cylinder = grid(|x, y| {
        let a = x / W as f64 * std::f64::consts::TAU;
        [a.cos(), a.sin(), y * 0.03 - 1.5]
    });
    // A terrain: the sheet, stretched, without triangles.
    let terrain = grid(|x, y| [x, y, 10.0 * wave(x, y)]);
    // A sensor frame: a wall 1 m away on the left half of the rays, 2 m on the right.
    let frame = grid(|x, y| {
        let depth = if x < W as f64 / 2.0 { 1.0 } else { 2.0 };
        let (u, v) = ((x - W as f64 / 2.0) * 0.002, (y - H as f64 / 2.0) * 0.002);
        [u * depth, v * depth, depth]
    });
    let paths = [
        ("mesh", mesh, NormalsTurned::No),
        ("cloud", cloud(&cylinder), NormalsTurned::No),
        ("terrain", cloud(&terrain), NormalsTurned::Up),
        ("frame", cloud(&frame), NormalsTurned::TowardOrigin),
    ];
    for (name, g, turned) in paths {
        let (counts, leaves) = told(&g);
        // Each model takes the path it stands for.
        assert_eq!(leaves.normals_turned, turned, "{name}");
        assert_eq!(leaves.stats.pixel_grid.is_some(), name == "frame", "{name}");
        let n = g.positions.len() as u64;
        assert_eq!(counts.iter().sum::<u64>(), n, "{name}: {counts:?}");
        // Told block by block as the fits go: no count holds half the samples.
        assert!(counts.len() >= 3, "{name}: {counts:?}");
        assert!(counts.iter().all(|&c| c <= n / 2), "{name}: {counts:?}");
    }
}
