//! Bad PLY files made by the tests: each with words its error message must contain.

use std::path::Path;

use spt::io::ply::{Encoding, FaceList, PolyMesh};

/// A unit square of two triangles.
pub fn square() -> PolyMesh {
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
pub struct Fixture {
    pub name: &'static str,
    pub bytes: Vec<u8>,
    pub expect: &'static [&'static str],
}

pub fn fixtures(dir: &Path) -> Vec<Fixture> {
    let good = dir.join("good.ply");
    super::write_standard(&good, &square(), Encoding::BinaryLittleEndian);
    let good = std::fs::read(&good).unwrap();
    let ascii = dir.join("good_ascii.ply");
    super::write_standard(&ascii, &square(), Encoding::Ascii);
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
    // ASCII rows end at their line: the line of vertex row 0, the first after the header.
    let row0_line = ascii[..ascii.find("end_header").unwrap()].lines().count() + 2;
    let row0_line: &'static str = Box::leak(format!("(line {row0_line})").into_boxed_str());
    let extra_value = ascii.replacen("0 0 0\n", "0 0 0 9\n", 1);
    let short_row = ascii.replacen("1 0 0\n", "1 0\n", 1);
    let face_extra = ascii.replacen("3 0 1 2\n", "3 0 1 2 0.5 0.5\n", 1);
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
        Fixture { name: "ascii_extra_value.ply", bytes: extra_value.into_bytes(), expect: Box::leak(Box::new(["element 'vertex', row 0", row0_line, "more values than the header declares", "(x y z)"])) },
        Fixture { name: "ascii_short_row.ply", bytes: short_row.into_bytes(), expect: &["element 'vertex', row 1", "fewer values than the header declares"] },
        Fixture { name: "ascii_face_extra.ply", bytes: face_extra.into_bytes(), expect: &["element 'face', row 0", "more values", "a list 'vertex_indices'"] },
        Fixture { name: "noise.ply", bytes: noise, expect: &["not a PLY file"] },
        Fixture { name: "empty.ply", bytes: vec![], expect: &["empty"] },
        Fixture { name: "no_end_header.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(), expect: &["no 'end_header'"] },
        Fixture { name: "bad_header_line.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n".to_vec(), expect: &["header line 4"] },
        Fixture { name: "no_vertex_element.ply", bytes: b"ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n".to_vec(), expect: &["no 'vertex' element"] },
        Fixture { name: "no_y.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float z\nend_header\n1 2\n".to_vec(), expect: &["no property 'y'"] },
        Fixture { name: "all_nan.ply", bytes: b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\nnan 0 0\n0 inf 0\n".to_vec(), expect: &["none of the 2 vertices has finite coordinates"] },
    ]
}

/// Asserts that the error `err` of the bad file `name` names it and holds every word of
/// `expect`, and that no allocation (`largest`, bytes) reached `limit`.
pub fn check_refusal(name: &str, err: &str, expect: &[&str], largest: usize, limit: usize) {
    assert!(
        err.contains(name),
        "{name}: error does not name the file: {err}"
    );
    for word in expect {
        assert!(err.contains(word), "{name}: expected '{word}' in: {err}");
    }
    assert!(largest < limit, "{name}: an allocation of {largest} bytes");
}
