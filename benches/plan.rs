//! The CPU's plan of a frame (`src/render/plan.rs`) without the GPU: each chunk's
//! prefix for the model's default view (45° field) over 1920×1080 at ε = 1 px, ended
//! at its block (`--prefix-cut block`, what a GPU adapter gets: the index alone) and at
//! its node (`--prefix-cut node`, a CPU adapter: a search of each prefix's last block
//! of nodes too).
//!
//! `cargo bench --bench plan -- --noplot` on the default model; `SPT_BENCH_SPT=FILE`
//! adds an `.spt` file of your choice, opened as the viewer streams it (its nodes
//! memory-mapped), such as the 200 M-point tile of `tools/gen_cloud.rs`. With only the
//! list's first tenth loaded, a frame first finds the least ε that fits and the slices
//! the asked one wants ([`spt::tree::select::PrefixIndex::fit`]), then searches the
//! prefixes at that ε. Threads:
//! `RAYON_NUM_THREADS`.

use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use spt::render::Camera;
use spt::tree::report::Silent;
use spt::tree::scene::Scene;
use spt::tree::select::error_per_distance;

const SIZE: (u32, u32) = (1920, 1080);

fn models() -> Vec<PathBuf> {
    let mut models = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("data/torus_knot.ply")];
    models.extend(std::env::var("SPT_BENCH_SPT").ok().map(PathBuf::from));
    models
}

fn plan(c: &mut Criterion) {
    for path in models() {
        let scene = Scene::open_for_streaming(&path, &Silent).expect("bench model");
        let (meta, index) = (scene.meta(), &scene.index);
        let aspect = SIZE.0 as f64 / SIZE.1 as f64;
        let fov = 45f64.to_radians();
        let camera = Camera::framed(meta, index.chunks(), fov, aspect);
        let cone = camera.view_cone(meta, aspect);
        let eps = error_per_distance(1.0, fov, SIZE.1);
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let mut group = c.benchmark_group(format!("plan/{name}"));
        group.sample_size(20);
        group.bench_function("cut at the block", |b| {
            b.iter(|| index.prefixes(cone.eye, eps, Some(&cone)).bounds())
        });
        group.bench_function("cut at the node", |b| {
            b.iter(|| index.ranges_refined(scene.nodes(), cone.eye, eps, Some(&cone), |_| true))
        });
        // Under a GPU memory budget: the list's first tenth loaded, in slices of 2¹⁹
        // nodes (about what a 2 GiB budget gives the 200 M-point tile).
        let tenth = scene.nodes().len() / 10;
        let loaded = |start: usize, count: usize| tenth.saturating_sub(start).min(count);
        group.bench_function("first tenth loaded, cut at the block", |b| {
            b.iter(|| {
                let fit = index.fit(cone.eye, eps, Some(&cone), 1 << 19, loaded);
                (index.prefixes(cone.eye, fit.eps, Some(&cone)).bounds(), fit)
            })
        });
        group.finish();
    }
}

criterion_group!(benches, plan);
criterion_main!(benches);
