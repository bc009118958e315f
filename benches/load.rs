//! PLY loading throughput: spt's reader against ply-rs-bw's, on the same file, the
//! leaf surfel builder, and the errors stage (inner nodes' disks, ellipses and errors,
//! `build_records`, given the leaves and their hierarchy).
//!
//! `cargo bench --bench load -- --noplot` uses the default model (criterion's plots need
//! fonts a bare machine lacks); `SPT_BENCH_PLY=FILE` adds a file
//! of your choice (ply-rs-bw is skipped above 50 MB: it needs minutes and gigabytes).
//! The full-size numbers in the README come from `tools/bench_load.sh`.

use std::path::PathBuf;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use spt::io::ply::read_ply;
use spt::surfel::leaf_surfels;
use spt::tree::report::Silent;
use spt::tree::{build_hierarchy, build_records};

fn files() -> Vec<PathBuf> {
    let mut files = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/torus_knot.ply")];
    if let Ok(extra) = std::env::var("SPT_BENCH_PLY") {
        files.push(PathBuf::from(extra));
    }
    files
}

fn load(c: &mut Criterion) {
    for path in files() {
        let bytes = std::fs::metadata(&path).expect("bench file").len();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let mut group = c.benchmark_group(format!("load/{name}"));
        group.throughput(Throughput::Bytes(bytes));
        group.sample_size(10);
        group.bench_function("spt", |b| b.iter(|| read_ply(&path).unwrap()));
        if bytes < 50 << 20 {
            group.bench_function("ply-rs-bw", |b| {
                b.iter(|| {
                    let mut f = std::fs::File::open(&path).unwrap();
                    ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new()
                        .read_ply(&mut f)
                        .unwrap()
                })
            });
        }
        group.finish();

        let model = read_ply(&path).unwrap();
        let mut group = c.benchmark_group(format!("surfels/{name}"));
        group.throughput(Throughput::Elements(model.geometry.positions.len() as u64));
        group.sample_size(10);
        group.bench_function("leaf_surfels", |b| b.iter(|| leaf_surfels(&model.geometry)));
        group.finish();

        let leaves = leaf_surfels(&model.geometry);
        let hierarchy = build_hierarchy(&leaves, &Silent);
        let mut group = c.benchmark_group(format!("errors/{name}"));
        group.throughput(Throughput::Elements(hierarchy.internal.len() as u64));
        group.sample_size(10);
        group.bench_function("build_records", |b| {
            b.iter_batched(
                || (leaves.clone(), hierarchy.clone()),
                |(leaves, hierarchy)| build_records(leaves, hierarchy, &Silent),
                BatchSize::LargeInput,
            )
        });
        group.finish();
    }
}

criterion_group!(benches, load);
criterion_main!(benches);
