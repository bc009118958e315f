//! The real scans of the shared data folder (`SPT_DATA`, or ../shared/data): every
//! file loads, with the facts each is known for, checked against ply-rs-bw as an
//! independent reader.

use crate::common;

use ply_rs_bw::ply::{DefaultElement, Property};
use spt::io::ply::read_ply;
use spt::surfel::leaf_surfels;

fn other_reader(path: &std::path::Path) -> Vec<DefaultElement> {
    let mut f = std::fs::File::open(path).unwrap();
    let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut f)
        .unwrap();
    ply.payload["vertex"].clone()
}

fn number(e: &DefaultElement, name: &str) -> f64 {
    match &e[name] {
        Property::Float(v) => *v as f64,
        Property::Double(v) => *v,
        Property::UChar(v) => *v as f64,
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn every_shared_file_loads_into_sane_surfels() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 4,
        "expected the shared scans in {}",
        dir.display()
    );
    for path in files {
        let model = read_ply(&path).unwrap_or_else(|e| panic!("{e}"));
        let leaves = leaf_surfels(&model.geometry);
        let name = path.display().to_string();
        common::assert_sane(&leaves, &name);
        if !model.geometry.triangles.is_empty() {
            common::assert_covers(&model.geometry, &leaves, &name);
        }
    }
}

#[test]
fn kinect_frame_drops_its_nan_rows_and_keeps_colours() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let path = dir.join("kinect_rgb.ply");
    let model = read_ply(&path).unwrap();
    assert_eq!(model.stats.vertices_in_file, 307_200);
    assert_eq!(model.stats.vertices_dropped_nonfinite, 47_353);
    let leaves = leaf_surfels(&model.geometry);
    // Its samples, then its long triangles' own splats (`spt::surfel::long_triangles`).
    let samples = 307_200 - 47_353;
    let added = leaves.stats.triangle_splats as usize;
    assert!(added > 0);
    assert_eq!(leaves.surfels.len(), samples + added);
    assert!(leaves.has_colors);
    // Colours follow their rows: the k-th finite row of the file is the k-th surfel,
    // with its pixel's own colour (a frame's vertices have no colour fields,
    // `spt::surfel::grid::frame_disks`).
    let rows = other_reader(&path);
    let finite = rows.iter().filter(|r| number(r, "x").is_finite());
    let mut offsets = Vec::new();
    for (k, row) in finite.enumerate().step_by(997) {
        let want = ["red", "green", "blue"].map(|c| number(row, c) as i32);
        let got = leaves.surfels[k].color.map(i32::from);
        offsets.push((0..3).map(|c| (got[c] - want[c]).abs()).max().unwrap());
        let p = leaves.surfels[k].position.as_dvec3() + leaves.origin;
        assert!((p.x - number(row, "x")).abs() < 1e-6, "surfel {k} position");
    }
    assert!(offsets.iter().all(|d| *d == 0), "colours {offsets:?}");
}

#[test]
fn terrain_tile_bounding_box_is_exactly_the_files_doubles() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let path = dir.join("terrain_utm.ply");
    let model = read_ply(&path).unwrap();
    let rows = other_reader(&path);
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for r in &rows {
        for (a, c) in ["x", "y", "z"].iter().enumerate() {
            min[a] = min[a].min(number(r, c));
            max[a] = max[a].max(number(r, c));
        }
    }
    assert_eq!(model.geometry.bounds.min, min);
    assert_eq!(model.geometry.bounds.max, max);
    // Rebased f32 positions keep millimetres on UTM coordinates.
    let g = &model.geometry;
    for (k, r) in rows.iter().enumerate().step_by(1009) {
        let p = g.positions[k].as_dvec3() + g.origin;
        for (a, c) in ["x", "y", "z"].iter().enumerate() {
            assert!(
                (p[a] - number(r, c)).abs() < 1e-3,
                "row {k} {c}: {} vs {}",
                p[a],
                number(r, c)
            );
        }
    }
    // The report prints the same doubles (shortest round-trip decimal).
    let (code, stdout, _) =
        common::run_spt(&["info".as_ref(), "--json".as_ref(), path.as_os_str()]);
    assert_eq!(code, Some(0));
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let got: Vec<f64> = json["bounds"]["min"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(got, min.to_vec());
}

#[test]
fn every_shared_file_converts_and_reopens_with_the_same_nodes() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let tmp = common::temp_dir();
    for name in [
        "bunny.ply",
        "dragon40k.ply",
        "kinect_rgb.ply",
        "terrain_utm.ply",
    ] {
        let model = read_ply(&dir.join(name)).unwrap();
        let list = spt::tree::build_sequential_list(leaf_surfels(&model.geometry));
        common::assert_tree_invariants(&list, name);
        let out = tmp.path().join(name).with_extension("spt");
        spt::tree::spt_file::write_spt(&out, &list).unwrap();
        let file = spt::tree::spt_file::SptFile::open(&out).unwrap();
        assert_eq!(file.to_list(), list, "{name}");
        assert_eq!(file.meta.origin, model.geometry.origin.to_array(), "{name}");
    }
}
