//! One model written as ASCII, binary little-endian and binary big-endian, with
//! shuffled property orders, mixed scalar types, filler properties and elements,
//! triangles, quads and pentagons, reads back as identical geometry every time.

use crate::common;

use spt::io::ply::{Encoding, FaceList, PlyLayout, PlyStream, PolyMesh, read_ply, write_ply};
use spt::io::scalar::Scalar;

/// A wavy grid of 12 × 9 vertices whose coordinates are exact in f32 (so float and
/// double files hold the same values), far from the origin, with colours, and faces
/// that mix triangles, quads and pentagons.
fn model() -> PolyMesh {
    let (nx, ny) = (12u32, 9u32);
    let mut positions = Vec::new();
    let mut colors = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let z = ((i * 7 + j * 3) % 5) as f64 * 0.125;
            positions.push([1000.0 + i as f64 * 0.5, -250.0 + j as f64 * 0.75, z]);
            colors.push([(i * 20) as u8, (j * 25) as u8, ((i + j) * 9) as u8]);
        }
    }
    let at = |i: u32, j: u32| j * nx + i;
    let mut faces = FaceList::default();
    for j in 0..ny - 1 {
        let mut i = 0;
        while i < nx - 1 {
            match (i + j) % 3 {
                // a pentagon over two cells
                0 if i + 2 < nx => {
                    faces.push(&[
                        at(i, j),
                        at(i + 1, j),
                        at(i + 2, j),
                        at(i + 2, j + 1),
                        at(i, j + 1),
                    ]);
                    faces.push(&[at(i + 1, j + 1), at(i, j + 1), at(i + 2, j + 1)]);
                    i += 2;
                }
                1 => {
                    faces.push(&[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                    i += 1;
                }
                _ => {
                    faces.push(&[at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                    faces.push(&[at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                    i += 1;
                }
            }
        }
    }
    PolyMesh {
        positions,
        normals: None,
        colors: Some(colors),
        faces,
    }
}

/// Fan triangulation, as the reader must do it.
fn expected_triangles(m: &PolyMesh) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    let mut at = 0;
    for &n in &m.faces.sizes {
        let f = &m.faces.indices[at..at + n as usize];
        for k in 1..f.len() - 1 {
            out.push([f[0], f[k], f[k + 1]]);
        }
        at += n as usize;
    }
    out
}

struct Variant {
    name: &'static str,
    layout: PlyLayout,
}

fn variants(m: &PolyMesh) -> Vec<Variant> {
    let props = |list: &[(&str, Scalar)]| {
        list.iter()
            .map(|(n, s)| (n.to_string(), *s))
            .collect::<Vec<_>>()
    };
    let mut out = Vec::new();
    for encoding in [
        Encoding::Ascii,
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
    ] {
        out.push(Variant {
            name: "standard",
            layout: PlyLayout::standard(encoding, m),
        });
        out.push(Variant {
            name: "shuffled, double x, float colours, uint lists, fillers",
            layout: PlyLayout {
                encoding,
                vertex_properties: props(&[
                    ("blue", Scalar::F32),
                    ("quality", Scalar::F32),
                    ("z", Scalar::F32),
                    ("x", Scalar::F64),
                    ("red", Scalar::F32),
                    ("flags", Scalar::U8),
                    ("y", Scalar::F32),
                    ("green", Scalar::F32),
                ]),
                face_count: Scalar::U32,
                face_index: Scalar::U32,
                face_list_name: "vertex_index".into(),
                face_extra: Some(("texnumber".into(), Scalar::I32)),
                extra_element: Some(("material".into(), 3)),
                comments: vec!["round trip".into()],
            },
        });
        out.push(Variant {
            name: "int counts and indices, double y z, uchar colours first",
            layout: PlyLayout {
                encoding,
                vertex_properties: props(&[
                    ("red", Scalar::U8),
                    ("green", Scalar::U8),
                    ("blue", Scalar::U8),
                    ("y", Scalar::F64),
                    ("x", Scalar::F32),
                    ("z", Scalar::F64),
                    ("confidence", Scalar::I16),
                ]),
                face_count: Scalar::I32,
                face_index: Scalar::I32,
                face_list_name: "vertex_indices".into(),
                face_extra: None,
                extra_element: None,
                comments: vec![],
            },
        });
    }
    out
}

#[test]
fn every_encoding_and_layout_reads_back_identical_geometry() {
    let m = model();
    let dir = common::temp_dir();
    let want_triangles = expected_triangles(&m);
    assert!(m.faces.sizes.contains(&4) && m.faces.sizes.contains(&5) && m.faces.sizes.contains(&3));
    let mut reference = None;
    for (k, v) in variants(&m).iter().enumerate() {
        let path = dir.path().join(format!("model{k}.ply"));
        write_ply(&path, &m, &v.layout).unwrap();
        let what = format!("{} / {}", v.layout.encoding.name(), v.name);
        let read = read_ply(&path).unwrap_or_else(|e| panic!("{what}: {e}"));
        let g = read.geometry;
        assert_eq!(g.triangles, want_triangles, "{what}: triangles");
        assert_eq!(
            read.stats.faces_in_file,
            m.faces.sizes.len() as u64,
            "{what}"
        );
        let colors: Vec<[u8; 3]> = g
            .colors
            .as_ref()
            .unwrap()
            .iter()
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        assert_eq!(Some(&colors), m.colors.as_ref(), "{what}: colours");
        // Positions back in file coordinates are the written ones (the offsets from the
        // origin are exact here: the model's coordinates are multiples of 1/8).
        for (i, p) in g.positions.iter().enumerate() {
            let back = (p.as_dvec3() + g.origin).to_array();
            assert_eq!(back, m.positions[i], "{what}: vertex {i}");
        }
        match &reference {
            None => reference = Some(g),
            Some(r) => assert_eq!(&g, r, "{what}: differs from the first variant"),
        }
        streamed_matches(&path, &m, &want_triangles, &what);
        // ply-rs-bw, an independent reader, agrees on the counts: the files are standard.
        let mut f = std::fs::File::open(&path).unwrap();
        let other = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new()
            .read_ply(&mut f)
            .unwrap_or_else(|e| panic!("{what}: ply-rs-bw cannot read it: {e}"));
        assert_eq!(other.payload["vertex"].len(), m.positions.len(), "{what}");
        assert_eq!(other.payload["face"].len(), m.faces.sizes.len(), "{what}");
    }
}

/// The file read a window at a time (windows of 7 rows, so that rows and polygons
/// straddle them) gives the written positions and colours and the same triangles.
fn streamed_matches(path: &std::path::Path, m: &PolyMesh, triangles: &[[u32; 3]], what: &str) {
    let stream = PlyStream::open(path).unwrap().with_window(7);
    assert_eq!(stream.vertex_count(), m.positions.len() as u64, "{what}");
    let (mut xyz, mut colors, mut windows) = (Vec::new(), Vec::new(), 0);
    stream
        .vertices(|b| {
            xyz.extend_from_slice(&b.xyz);
            colors.extend(b.colors.iter().map(|c| [c[0], c[1], c[2]]));
            windows += 1;
        })
        .unwrap();
    assert_eq!(xyz, m.positions, "{what}: streamed positions");
    assert_eq!(Some(&colors), m.colors.as_ref(), "{what}: streamed colours");
    assert_eq!(windows, m.positions.len().div_ceil(7), "{what}: windows");
    let mut streamed = Vec::new();
    stream.triangles(|t| streamed.extend_from_slice(t)).unwrap();
    assert_eq!(streamed, triangles, "{what}: streamed triangles");
}

#[test]
fn crlf_header_and_obj_info_are_accepted() {
    let m = model();
    let dir = common::temp_dir();
    let path = dir.path().join("lf.ply");
    common::write_standard(&path, &m, Encoding::Ascii);
    let text = std::fs::read_to_string(&path).unwrap();
    let (head, body) = text.split_once("end_header\n").unwrap();
    let head = head
        .replace("format", "obj_info scanned by hand\nformat")
        .replace('\n', "\r\n");
    let crlf = dir.path().join("crlf.ply");
    std::fs::write(&crlf, format!("{head}end_header\r\n{body}")).unwrap();
    let a = read_ply(&path).unwrap();
    let b = read_ply(&crlf).unwrap();
    assert_eq!(a.geometry, b.geometry);
    assert_eq!(b.header.obj_info, vec!["scanned by hand".to_string()]);
}
