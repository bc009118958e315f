//! Bad files the project makes itself: each is refused with an error that names the
//! file and the problem, `spt info` exits 1 without a panic, and no allocation grows
//! with a header count that the file cannot hold.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use spt::io::ply::{Encoding, FaceList, PolyMesh, read_ply};

/// Counts the largest single allocation made while a check runs.
struct Largest;
static LARGEST: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only records sizes.
unsafe impl GlobalAlloc for Largest {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), Ordering::Relaxed);
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        LARGEST.fetch_max(n, Ordering::Relaxed);
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static ALLOC: Largest = Largest;

fn square() -> PolyMesh {
    PolyMesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        normals: None,
        colors: None,
        faces: FaceList::triangles(&[[0, 1, 2], [0, 2, 3]]),
    }
}

/// A fixture: its file name, its bytes, and words the error must contain.
struct Fixture {
    name: &'static str,
    bytes: Vec<u8>,
    expect: &'static [&'static str],
}

fn fixtures(dir: &Path) -> Vec<Fixture> {
    let good = dir.join("good.ply");
    common::write_standard(&good, &square(), Encoding::BinaryLittleEndian);
    let good = std::fs::read(&good).unwrap();
    let ascii = dir.join("good_ascii.ply");
    common::write_standard(&ascii, &square(), Encoding::Ascii);
    let ascii = std::fs::read_to_string(&ascii).unwrap();

    let mut huge = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    huge.resize(200, 7);
    let mut huge_faces = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1000000000\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    huge_faces.extend_from_slice(&[0u8; 36]);
    for _ in 0..2 {
        huge_faces.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    }
    let mut huge_ascii = "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_string();
    huge_ascii.push_str("1 1 1\n");
    let mut bad_index = good.clone();
    let n = bad_index.len();
    bad_index[n - 4..].copy_from_slice(&99i32.to_le_bytes());
    let mut negative_index = good.clone();
    negative_index[n - 4..].copy_from_slice(&(-5i32).to_le_bytes());
    let noise: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();

    vec![
        Fixture { name: "truncated.ply", bytes: good[..good.len() - 7].to_vec(), expect: &["element 'face', row 1", "ends inside this row"] },
        Fixture { name: "truncated_vertices.ply", bytes: good[..good.len() - 40].to_vec(), expect: &["element 'vertex', row", "ends inside this row"] },
        Fixture { name: "billion_vertices.ply", bytes: huge, expect: &["element 'vertex'", "1000000000 rows"] },
        Fixture { name: "billion_faces.ply", bytes: huge_faces, expect: &["element 'face', row 2", "1000000000 rows"] },
        Fixture { name: "billion_ascii.ply", bytes: huge_ascii.into_bytes(), expect: &["element 'vertex', row 2", "line 10", "ends inside this row"] },
        Fixture { name: "index_out_of_range.ply", bytes: bad_index, expect: &["element 'face', row 1", "vertex index 99 is out of range", "4 vertices"] },
        Fixture { name: "negative_index.ply", bytes: negative_index, expect: &["element 'face', row 1", "vertex index -5"] },
        Fixture { name: "ascii_index_out_of_range.ply", bytes: ascii.replace("3 0 2 3", "3 0 2 7").into_bytes(), expect: &["element 'face', row 1", "line", "vertex index 7"] },
        Fixture { name: "ascii_not_a_number.ply", bytes: ascii.replacen("1 0 0", "1 zero 0", 1).into_bytes(), expect: &["element 'vertex', row 1", "expected a float value, found 'zero'"] },
        Fixture { name: "noise.ply", bytes: noise, expect: &["not a PLY file"] },
        Fixture { name: "empty.ply", bytes: vec![], expect: &["empty"] },
        Fixture { name: "no_end_header.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(), expect: &["no 'end_header'"] },
        Fixture { name: "bad_header_line.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n".to_vec(), expect: &["header line 4"] },
        Fixture { name: "no_vertex_rows.ply", bytes: b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(), expect: &["no vertex"] },
        Fixture { name: "no_vertex_element.ply", bytes: b"ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n".to_vec(), expect: &["no 'vertex' element"] },
        Fixture { name: "no_z.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n".to_vec(), expect: &["no property 'z'"] },
        Fixture { name: "all_nan.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\nnan 0 0\n0 inf 0\n".to_vec(), expect: &["none of the 2 vertices has finite coordinates"] },
    ]
}

#[test]
fn bad_files_are_refused_with_a_clear_error_and_no_large_allocation() {
    let dir = common::temp_dir();
    for f in fixtures(dir.path()) {
        let path = dir.path().join(f.name);
        std::fs::write(&path, &f.bytes).unwrap();
        LARGEST.store(0, Ordering::Relaxed);
        let err = read_ply(&path).expect_err(f.name).to_string();
        let largest = LARGEST.load(Ordering::Relaxed);
        assert!(
            err.contains(f.name),
            "{}: error does not name the file: {err}",
            f.name
        );
        for word in f.expect {
            assert!(
                err.contains(word),
                "{}: expected '{word}' in: {err}",
                f.name
            );
        }
        // The test harness itself allocates a few KiB; a header count would take GBs.
        assert!(
            largest < 1 << 20,
            "{}: an allocation of {largest} bytes",
            f.name
        );
    }
}

#[test]
fn spt_info_exits_1_with_the_message_and_never_panics() {
    let dir = common::temp_dir();
    for f in fixtures(dir.path()) {
        let path = dir.path().join(f.name);
        std::fs::write(&path, &f.bytes).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_spt"))
            .arg("info")
            .arg(&path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{}: {stderr}", f.name);
        assert!(
            stderr.starts_with("error: ") && stderr.contains(f.name),
            "{}: {stderr}",
            f.name
        );
        assert!(!stderr.contains("panicked"), "{}: {stderr}", f.name);
        assert!(out.stdout.is_empty(), "{}: printed a report", f.name);
    }
    let missing = dir.path().join("missing.ply");
    let out = Command::new(env!("CARGO_BIN_EXE_spt"))
        .arg("info")
        .arg(&missing)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.ply: cannot read"));
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
