//! Bad files the project makes itself (`common::bad_files`): `spt info` refuses each
//! with exit code 1 and an error naming the file and the problem, never a panic.

use crate::common;

use crate::common::bad_files::{fixtures, square};
use spt::io::ply::{Encoding, read_ply};

#[test]
fn spt_info_exits_1_with_the_message_and_never_panics() {
    let dir = common::temp_dir();
    for f in fixtures(dir.path()) {
        let path = dir.path().join(f.name);
        std::fs::write(&path, &f.bytes).unwrap();
        let (code, stdout, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
        assert_eq!(code, Some(1), "{}: {stderr}", f.name);
        assert!(
            stderr.starts_with("error: ") && stderr.contains(f.name),
            "{}: {stderr}",
            f.name
        );
        assert!(!stderr.contains("panicked"), "{}: {stderr}", f.name);
        assert!(stdout.is_empty(), "{}: printed a report", f.name);
    }
    let missing = dir.path().join("missing.ply");
    let (code, _, stderr) = common::run_spt(&["info".as_ref(), missing.as_os_str()]);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("missing.ply: cannot read"));
}

#[test]
fn nonfinite_vertices_are_dropped_with_their_triangles_and_counted() {
    let dir = common::temp_dir();
    let mut m = square();
    m.positions.push([f64::NAN, 0.0, 0.0]);
    m.positions.push([0.5, 0.5, 1.0]);
    m.faces.push(&[1, 4, 2]);
    m.faces.push(&[2, 5, 3]);
    let path = dir.path().join("nan.ply");
    common::write_standard(&path, &m, Encoding::BinaryBigEndian);
    let read = read_ply(&path).unwrap();
    assert_eq!(read.stats.vertices_dropped_nonfinite, 1);
    assert_eq!(read.stats.triangles_dropped_nonfinite, 1);
    // Vertex 5 became 4 when vertex 4 was dropped.
    assert_eq!(
        read.geometry.triangles,
        vec![[0, 1, 2], [0, 2, 3], [2, 4, 3]]
    );
    assert_eq!(read.geometry.bounds.max, [1.0, 1.0, 1.0]);
}
