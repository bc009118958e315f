//! The per-point cost of a cloud's leaf surfels (neighbour search, normal, covering
//! radius, clipping, shape), on a fixed generated scan, so that it can be tracked:
//! 200,000 samples of a bumpy closed surface about the origin (a cloud of unknown
//! orientation, the path of an object scan), jittered as a scanner's are. Criterion
//! reports the time per leaf build and its throughput in points per second.
//!
//! `cargo bench --bench cloud_surfels`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use spt::io::Geometry;
use spt::surfel::leaf_surfels;

/// Samples of the scan.
const POINTS: usize = 200_000;

/// A deterministic uniform variate in [0, 1) (xorshift64*).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` samples of the surface r(θ, φ) = 1 + 0.15 sin 5θ cos 4φ (about 1 m across), on
/// a jittered grid of directions, each with 1 mm of noise along its ray.
fn scan(n: usize) -> Vec<[f64; 3]> {
    let mut uniform = Uniform(0x9E37_79B9_7F4A_7C15);
    let side = (n as f64).sqrt().ceil() as usize;
    (0..n)
        .map(|k| {
            let (i, j) = ((k % side) as f64, (k / side) as f64);
            let z = 1.0 - 2.0 * (j + uniform.next()) / side as f64;
            let phi = std::f64::consts::TAU * (i + uniform.next()) / side as f64;
            let theta = z.clamp(-1.0, 1.0).acos();
            let r = 1.0
                + 0.15 * (5.0 * theta).sin() * (4.0 * phi).cos()
                + 1e-3 * (uniform.next() - 0.5);
            let s = theta.sin();
            [r * s * phi.cos(), r * s * phi.sin(), r * z]
        })
        .collect()
}

fn cloud_surfels(c: &mut Criterion) {
    let (g, _): (Geometry, _) = Geometry::from_points(&scan(POINTS)).expect("a finite scan");
    let mut group = c.benchmark_group("cloud_surfels");
    group.sample_size(10);
    group.measurement_time(std::time::Duration::from_secs(15));
    group.throughput(Throughput::Elements(POINTS as u64));
    group.bench_function("bumpy_sphere_200k", |b| b.iter(|| leaf_surfels(&g)));
    group.finish();
}

criterion_group! {
    name = benches;
    // Criterion's plots need system fonts that a bare machine lacks.
    config = Criterion::default().without_plots();
    targets = cloud_surfels
}
criterion_main!(benches);
