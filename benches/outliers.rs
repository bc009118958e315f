//! One outlier must not change the time of the surfels: the shared bunny as
//! a mesh and as a cloud, plain and with one vertex moved far away (x = 3.4e38 for the
//! mesh; 1e36 and 1e10 for the cloud), load and leaf surfels timed on the same machine
//! in one run.
//!
//! `cargo bench --bench outliers` (the bunny from `SPT_DATA`, default `../shared/data`).

use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use spt::io::ply::{Encoding, FaceList, PlyLayout, PolyMesh, read_ply, write_ply};
use spt::io::scalar::Scalar;
use spt::surfel::leaf_surfels;

/// The vertex moved: an inner one of the bunny.
const MOVED: usize = 1000;

fn bunny() -> Option<PathBuf> {
    let dir = std::env::var("SPT_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|_| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let path = dir.join("bunny.ply");
    path.is_file().then_some(path)
}

/// The bunny as written by spt (double coordinates), with or without its faces.
fn variant(dir: &Path, name: &str, faces: bool, moved_x: Option<f64>) -> PathBuf {
    let g = read_ply(&bunny().expect("the bunny")).unwrap().geometry;
    let mut mesh = PolyMesh {
        positions: g
            .positions
            .iter()
            .map(|p| (p.as_dvec3() + g.origin).to_array())
            .collect(),
        faces: if faces {
            FaceList::triangles(&g.triangles)
        } else {
            FaceList::default()
        },
        ..PolyMesh::default()
    };
    if let Some(x) = moved_x {
        mesh.positions[MOVED][0] = x;
    }
    let mut layout = PlyLayout::standard(Encoding::BinaryLittleEndian, &mesh);
    for p in layout.vertex_properties.iter_mut().take(3) {
        p.1 = Scalar::F64;
    }
    let path = dir.join(format!("{name}.ply"));
    write_ply(&path, &mesh, &layout).unwrap();
    path
}

fn outliers(c: &mut Criterion) {
    if bunny().is_none() {
        eprintln!("no bunny.ply in SPT_DATA: nothing to measure");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("mesh-plain", true, None),
        ("mesh-x-3p4e38", true, Some(3.4e38)),
        ("cloud-plain", false, None),
        ("cloud-x-1e36", false, Some(1e36)),
        ("cloud-x-1e10", false, Some(1e10)),
    ];
    let mut group = c.benchmark_group("outliers/bunny");
    group.sample_size(20);
    for (i, (name, faces, x)) in cases.into_iter().enumerate() {
        let path = variant(dir.path(), &format!("case{i}"), faces, x);
        let model = read_ply(&path).unwrap();
        group.bench_function(format!("surfels/{name}"), |b| {
            b.iter(|| leaf_surfels(&model.geometry))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // Criterion's plots need system fonts that a bare machine lacks.
    config = Criterion::default().without_plots();
    targets = outliers
}
criterion_main!(benches);
