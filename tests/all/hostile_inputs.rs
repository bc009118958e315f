//! The four defects a fuzzer found, each on the input it was found with:
//! a header that made the ASCII reader loop for years, finite doubles that became
//! infinities, one outlier that broke every radius, and an isolated vertex with radius 0.
//! Every model here goes through surfels, tree, `.spt` write and reopen, and every
//! stage's invariants are checked.

use crate::common;

use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use spt::io::ply::{Encoding, read_ply};
use spt::io::rebase::MAX_OFFSET;
use spt::surfel::{LeafSurfels, leaf_surfels};
use spt::tree::build_sequential_list;
use spt::tree::spt_file::{SptFile, write_spt};
use spt::tree::validate::{check_meta, check_nodes, check_structure};

/// Surfels, tree, `.spt` and reopened file of the PLY at `path`, every invariant checked.
fn through_everything(path: &Path) -> LeafSurfels {
    let model = read_ply(path).unwrap_or_else(|e| panic!("{e}"));
    model.geometry.check().unwrap();
    let leaves = leaf_surfels(&model.geometry);
    leaves.check().unwrap();
    let list = build_sequential_list(leaves.clone());
    check_meta(&list.meta).unwrap();
    check_nodes(&list.meta, &list.nodes, &list.parents).unwrap();
    check_structure(&list.meta, &list.nodes, &list.parents, &list.chunks).unwrap();
    let spt = path.with_extension("spt");
    write_spt(&spt, &list).unwrap();
    let back = SptFile::open(&spt).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back.to_list(), list);
    leaves
}

/// ASCII PLY: `element e COUNT` with no property, then one vertex.
fn propertyless_element(count: &str) -> Vec<u8> {
    format!(
        "ply\nformat ascii 1.0\nelement e {count}\nelement vertex 1\nproperty float x\n\
         property float y\nproperty float z\nend_header\n1 2 3\n"
    )
    .into_bytes()
}

#[test]
fn rows_of_an_element_without_properties_cost_nothing() {
    let dir = common::temp_dir();
    for count in ["9999999999", "4294967296", "1000000000000000000"] {
        let path = dir.path().join(format!("empty_element_{count}.ply"));
        std::fs::write(&path, propertyless_element(count)).unwrap();
        // On a thread, so that a regression fails here instead of hanging the suite.
        let (send, receive) = mpsc::channel();
        let p = path.clone();
        let start = Instant::now();
        std::thread::spawn(move || send.send(read_ply(&p).map(|m| m.geometry.positions)));
        let positions = receive
            .recv_timeout(Duration::from_secs(5))
            .unwrap_or_else(|_| panic!("count {count}: still reading after 5 s"))
            .unwrap();
        let took = start.elapsed();
        assert!(took < Duration::from_millis(100), "count {count}: {took:?}");
        assert_eq!(positions.len(), 1);
        through_everything(&path);
    }
}

fn ascii_cloud(rows: &[&str]) -> Vec<u8> {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nend_header\n",
        rows.len()
    );
    for r in rows {
        s.push_str(r);
        s.push('\n');
    }
    s.into_bytes()
}

#[test]
fn finite_doubles_beyond_f32_offsets_are_dropped_and_counted_never_infinite() {
    let dir = common::temp_dir();
    let square = ["0 0 0", "1 0 0", "1 1 0", "0 1 0"];
    // (name, file, vertices kept, dropped out of range)
    let mut span = common::bad_files::square();
    span.positions.push([-1e300, 0.0, 0.0]);
    span.positions.push([1e300, 0.5, 0.0]);
    span.faces.push(&[0, 1, 4]);
    let span_path = dir.path().join("span_1e300.ply");
    common::write_double(&span_path, &span);
    let float_1e300 = dir.path().join("ascii_float_1e300.ply");
    let mut rows = square.to_vec();
    rows.push("1e300 0 0");
    std::fs::write(&float_1e300, ascii_cloud(&rows)).unwrap();
    let single = dir.path().join("single_at_-1e308.ply");
    std::fs::write(&single, ascii_cloud(&["-1e308 -1e308 -1e308"])).unwrap();

    for (path, kept, dropped) in [(&span_path, 4, 2), (&float_1e300, 4, 1), (&single, 1, 0)] {
        let model = read_ply(path).unwrap();
        assert_eq!(model.geometry.positions.len(), kept, "{}", path.display());
        assert_eq!(model.stats.vertices_dropped_out_of_range, dropped);
        let leaves = through_everything(path);
        assert_eq!(leaves.surfels.len(), kept);
    }
    // The triangle on a dropped vertex goes with it.
    assert_eq!(
        read_ply(&span_path)
            .unwrap()
            .stats
            .triangles_dropped_nonfinite,
        1
    );
    // One vertex at −1e308 is a model: its origin, not an overflowed centre.
    let g = read_ply(&single).unwrap().geometry;
    assert_eq!(g.origin.x, -1e308);
    // `spt info` prints such bounds as they read back, not as 309 digits.
    let (code, out, err) = common::run_spt(&["info".as_ref(), single.as_os_str()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("bbox min      -1e308 -1e308 -1e308"), "{out}");

    // ±1e308: no origin holds both as f32 offsets; the one at the median is kept.
    let both = dir.path().join("both_1e308.ply");
    std::fs::write(&both, ascii_cloud(&["-1e308 0 0", "1e308 0 0"])).unwrap();
    let model = read_ply(&both).unwrap();
    assert_eq!(model.geometry.positions.len(), 1);
    assert_eq!(model.stats.vertices_dropped_out_of_range, 1);
    through_everything(&both);
    // Three vertices 1e300 apart on three axes: none lies near the median (0, 0, 0).
    // Refused, with the reason.
    let apart = dir.path().join("apart_1e300.ply");
    std::fs::write(
        &apart,
        ascii_cloud(&["1e300 0 0", "0 1e300 0", "0 0 1e300"]),
    )
    .unwrap();
    let (code, _, err) = common::run_spt(&["info".as_ref(), apart.as_os_str()]);
    assert_eq!(code, Some(1));
    assert!(
        err.contains("apart_1e300.ply") && err.contains("cannot be stored"),
        "{err}"
    );
    assert!(MAX_OFFSET < f32::MAX as f64);
}

#[test]
fn an_isolated_vertex_with_a_given_normal_gets_a_radius_and_is_counted() {
    let dir = common::temp_dir();
    let mut m = common::bad_files::square();
    m.positions.push([0.5, 0.5, 0.25]);
    m.normals = Some(vec![[0.0, 0.0, 1.0]; 5]);
    let path = dir.path().join("isolated_with_normal.ply");
    common::write_standard(&path, &m, Encoding::Ascii);
    let leaves = through_everything(&path);
    assert_eq!(leaves.stats.isolated_vertices, 1);
    let isolated = leaves.surfels[4];
    assert!(isolated.radius > 0.0 && isolated.radius.is_finite());
    assert_eq!(isolated.normal, glam::Vec3::Z, "the given normal is kept");
}

/// Vertices within two triangles of vertex `k`: those whose one-ring holds a neighbour
/// of `k`, whose normal `k` changes (a vertex's shading field is fitted to its ring's
/// normals).
fn within_two_triangles(triangles: &[[u32; 3]], n: usize, k: u32) -> Vec<bool> {
    let mut near = vec![false; n];
    near[k as usize] = true;
    for _ in 0..2 {
        let ring = near.clone();
        for t in triangles
            .iter()
            .filter(|t| t.iter().any(|&v| ring[v as usize]))
        {
            for &v in t {
                near[v as usize] = true;
            }
        }
    }
    near
}

/// Vertices within `reach` of vertex `k` (whose neighbourhoods may hold it).
fn within(positions: &[[f64; 3]], k: u32, reach: f64) -> Vec<bool> {
    let c = glam::DVec3::from(positions[k as usize]);
    positions
        .iter()
        .map(|p| glam::DVec3::from(*p).distance(c) <= reach)
        .collect()
}

/// Surfels of `plain` and `moved` agree (radius and normal within 1e-4 relative) on
/// every vertex but those in `skip`; `moved` lacks vertex `dropped` if given.
fn assert_same_surfels(
    plain: &LeafSurfels,
    moved: &LeafSurfels,
    skip: &[bool],
    dropped: Option<usize>,
    what: &str,
) {
    let mut compared = 0;
    for (i, a) in plain.surfels.iter().enumerate() {
        if skip[i] || Some(i) == dropped {
            continue;
        }
        let j = match dropped {
            Some(d) if i > d => i - 1,
            _ => i,
        };
        let b = moved.surfels[j];
        let rel = (a.radius - b.radius).abs() / a.radius;
        assert!(
            rel <= 1e-4,
            "{what}: vertex {i} radius {} vs {}",
            a.radius,
            b.radius
        );
        let turn = (a.normal - b.normal).length();
        assert!(
            turn <= 1e-4,
            "{what}: vertex {i} normal {} vs {}",
            a.normal,
            b.normal
        );
        compared += 1;
    }
    assert!(
        compared * 100 >= plain.surfels.len() * 99,
        "{what}: compared only {compared}"
    );
}

#[test]
fn one_outlier_changes_neither_the_rest_of_the_bunny_nor_its_scale() {
    let Some(data) = common::shared_data() else {
        return;
    };
    let dir = common::temp_dir();
    let bunny = read_ply(&data.join("bunny.ply")).unwrap().geometry;
    let mesh = common::to_mesh(&bunny);
    let k = 1000u32; // an inner vertex, on no face of the bounding box
    let plain_path = dir.path().join("bunny.ply");
    common::write_standard(&plain_path, &mesh, Encoding::BinaryLittleEndian);
    let plain = through_everything(&plain_path);
    let plain_model = read_ply(&plain_path).unwrap();
    assert_eq!(plain_model.stats.outliers, 0);

    // A mesh vertex at x = 3.4e38: out of range, dropped with its triangles.
    let mut moved = mesh.clone();
    moved.positions[k as usize][0] = 3.4e38;
    let path = dir.path().join("bunny_outlier.ply");
    common::write_standard(&path, &moved, Encoding::BinaryLittleEndian);
    let model = read_ply(&path).unwrap();
    assert_eq!(model.stats.vertices_dropped_out_of_range, 1);
    assert_eq!(model.geometry.origin, plain_model.geometry.origin);
    let leaves = through_everything(&path);
    let skip = within_two_triangles(&bunny.triangles, mesh.positions.len(), k);
    assert_same_surfels(&plain, &leaves, &skip, Some(k as usize), "mesh, x = 3.4e38");

    // The same as clouds: one coordinate at 1e36 (dropped) and at 1e10 (kept, an outlier).
    let mut cloud = mesh.clone();
    cloud.faces = Default::default();
    let cloud_path = dir.path().join("bunny_cloud.ply");
    common::write_double(&cloud_path, &cloud);
    let plain = through_everything(&cloud_path);
    let plain_origin = read_ply(&cloud_path).unwrap().geometry.origin;
    // The plain cloud's points whose 12 neighbours may include vertex k: within 4
    // times the median radius (the 6th neighbour's distance) of it.
    let (_, median, _) = plain.radius_range().unwrap();
    let near_k = within(&cloud.positions, k, 4.0 * median as f64);
    for (x, dropped) in [(1e36, Some(k as usize)), (1e10, None)] {
        let mut c = cloud.clone();
        c.positions[k as usize][0] = x;
        let path = dir.path().join(format!("bunny_cloud_{x:e}.ply"));
        common::write_double(&path, &c);
        let model = read_ply(&path).unwrap();
        assert_eq!(model.stats.outliers, dropped.is_none() as u64, "x = {x:e}");
        assert_eq!(model.geometry.origin, plain_origin, "x = {x:e}");
        let leaves = through_everything(&path);
        assert_same_surfels(
            &plain,
            &leaves,
            &near_k,
            dropped,
            &format!("cloud, x = {x:e}"),
        );
        assert_eq!(leaves.stats.fallback_radii, 0, "x = {x:e}");
    }
}

#[test]
fn an_spt_whose_checksum_holds_but_whose_values_are_unusable_is_refused() {
    let dir = common::temp_dir();
    let ply = dir.path().join("square.ply");
    common::write_standard(
        &ply,
        &common::bad_files::square(),
        Encoding::BinaryLittleEndian,
    );
    through_everything(&ply);
    let good = std::fs::read(ply.with_extension("spt")).unwrap();
    // (what, byte offset, bytes): bounds min x = −∞; first node's radius = −1.
    let edits: [(&str, usize, Vec<u8>); 2] = [
        ("bounds", 64, f64::NEG_INFINITY.to_le_bytes().to_vec()),
        ("radius", 256 + 12, (-1.0f32).to_le_bytes().to_vec()),
    ];
    for (what, at, bytes) in edits {
        let mut b = good.clone();
        b[at..at + bytes.len()].copy_from_slice(&bytes);
        assert!(spt::tree::spt_file::reseal(&mut b));
        let path = dir.path().join(format!("bad_{what}.spt"));
        std::fs::write(&path, &b).unwrap();
        let err = SptFile::open(&path).err().expect(what).to_string();
        assert!(err.contains("invalid tree") && err.contains(what), "{err}");
        let (code, out, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
        assert_eq!(code, Some(1), "{what}: {out}");
        assert!(stderr.contains(what) && out.contains("INVALID"), "{stderr}");
    }
}
