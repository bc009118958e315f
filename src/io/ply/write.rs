//! PLY out: any encoding, property types and property order, so that the generator in
//! `tools/` and the round-trip tests can write what real tools write. The file is
//! written atomically ([`crate::io::atomic`]).

use std::io::Write;
use std::path::Path;

use super::header::Encoding;
use crate::io::scalar::Scalar;

/// Polygons as one flat index array plus the size of each polygon.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FaceList {
    pub indices: Vec<u32>,
    pub sizes: Vec<u8>,
}

impl FaceList {
    pub fn triangles(tris: &[[u32; 3]]) -> Self {
        FaceList {
            indices: tris.iter().flatten().copied().collect(),
            sizes: vec![3; tris.len()],
        }
    }

    pub fn push(&mut self, polygon: &[u32]) {
        self.indices.extend_from_slice(polygon);
        self.sizes.push(polygon.len() as u8);
    }
}

/// A polygon mesh or point cloud to write, in the file's own coordinates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PolyMesh {
    pub positions: Vec<[f64; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub colors: Option<Vec<[u8; 3]>>,
    pub faces: FaceList,
}

/// How to lay the mesh out in the file. Vertex properties are written in the order of
/// `vertex_properties`, by name: `x y z nx ny nz red green blue` take the mesh's values
/// (colours scaled to 0–1 for float types); any other name is written as a filler value
/// that readers must skip.
#[derive(Debug, Clone)]
pub struct PlyLayout {
    pub encoding: Encoding,
    pub vertex_properties: Vec<(String, Scalar)>,
    /// Count and index types of the face list.
    pub face_count: Scalar,
    pub face_index: Scalar,
    /// Name of the face list (`vertex_indices` or `vertex_index`).
    pub face_list_name: String,
    /// A filler scalar property written before the face list, if any.
    pub face_extra: Option<(String, Scalar)>,
    /// An element of filler rows written before the vertices, if any (name, rows).
    pub extra_element: Option<(String, u64)>,
    pub comments: Vec<String>,
}

impl PlyLayout {
    /// The usual layout: float x y z, [float nx ny nz], [uchar red green blue], and
    /// `list uchar int vertex_indices`.
    pub fn standard(encoding: Encoding, mesh: &PolyMesh) -> Self {
        let mut vertex_properties: Vec<(String, Scalar)> = ["x", "y", "z"]
            .iter()
            .map(|n| (n.to_string(), Scalar::F32))
            .collect();
        if mesh.normals.is_some() {
            vertex_properties.extend(
                ["nx", "ny", "nz"]
                    .iter()
                    .map(|n| (n.to_string(), Scalar::F32)),
            );
        }
        if mesh.colors.is_some() {
            vertex_properties.extend(
                ["red", "green", "blue"]
                    .iter()
                    .map(|n| (n.to_string(), Scalar::U8)),
            );
        }
        PlyLayout {
            encoding,
            vertex_properties,
            face_count: Scalar::U8,
            face_index: Scalar::I32,
            face_list_name: "vertex_indices".into(),
            face_extra: None,
            extra_element: None,
            comments: Vec::new(),
        }
    }
}

fn vertex_value(mesh: &PolyMesh, name: &str, ty: Scalar, i: usize) -> f64 {
    let color = |k: usize| {
        let c = mesh.colors.as_ref().map_or(0, |c| c[i][k]) as f64;
        if ty.is_float() { c / 255.0 } else { c }
    };
    let normal = |k: usize| mesh.normals.as_ref().map_or(0.0, |n| n[i][k] as f64);
    match name {
        "x" => mesh.positions[i][0],
        "y" => mesh.positions[i][1],
        "z" => mesh.positions[i][2],
        "nx" => normal(0),
        "ny" => normal(1),
        "nz" => normal(2),
        "red" => color(0),
        "green" => color(1),
        "blue" => color(2),
        _ => (i % 7) as f64,
    }
}

/// Appends one value in the layout's encoding (ASCII values are followed by a space).
fn put(out: &mut Vec<u8>, enc: Encoding, ty: Scalar, v: f64) {
    match enc {
        Encoding::Ascii => {
            // Shortest representation that reads back to the same value of type `ty`.
            let text = match ty {
                Scalar::F32 => format!("{} ", v as f32),
                Scalar::F64 => format!("{v} "),
                _ => format!("{} ", v as i64),
            };
            out.extend_from_slice(text.as_bytes());
        }
        Encoding::BinaryLittleEndian => ty.write(out, v, false),
        Encoding::BinaryBigEndian => ty.write(out, v, true),
    }
}

fn end_row(out: &mut Vec<u8>, enc: Encoding) {
    if enc == Encoding::Ascii {
        out.pop();
        out.push(b'\n');
    }
}

/// Writes `mesh` to `path` atomically (temporary file, then rename).
pub fn write_ply(path: &Path, mesh: &PolyMesh, layout: &PlyLayout) -> std::io::Result<()> {
    let enc = layout.encoding;
    let mut header = format!("ply\nformat {} 1.0\n", enc.name());
    for c in &layout.comments {
        header += &format!("comment {c}\n");
    }
    if let Some((name, rows)) = &layout.extra_element {
        header += &format!(
            "element {name} {rows}\nproperty uchar id\nproperty list uchar float values\n"
        );
    }
    header += &format!("element vertex {}\n", mesh.positions.len());
    for (name, ty) in &layout.vertex_properties {
        header += &format!("property {} {name}\n", ty.name());
    }
    let has_faces = !mesh.faces.sizes.is_empty();
    if has_faces {
        header += &format!("element face {}\n", mesh.faces.sizes.len());
        if let Some((name, ty)) = &layout.face_extra {
            header += &format!("property {} {name}\n", ty.name());
        }
        header += &format!(
            "property list {} {} {}\n",
            layout.face_count.name(),
            layout.face_index.name(),
            layout.face_list_name
        );
    }
    header += "end_header\n";

    crate::io::atomic::write_atomically(path, |w| {
        w.write_all(header.as_bytes())?;
        write_rows(w, mesh, layout)
    })
}

fn write_rows(w: &mut dyn Write, mesh: &PolyMesh, layout: &PlyLayout) -> std::io::Result<()> {
    let enc = layout.encoding;
    let mut row = Vec::with_capacity(256);
    let flush = |row: &mut Vec<u8>, w: &mut dyn Write| {
        end_row(row, enc);
        let r = w.write_all(row);
        row.clear();
        r
    };
    if let Some((_, rows)) = &layout.extra_element {
        for r in 0..*rows {
            put(&mut row, enc, Scalar::U8, (r % 200) as f64);
            put(&mut row, enc, Scalar::U8, 2.0);
            put(&mut row, enc, Scalar::F32, 0.5);
            put(&mut row, enc, Scalar::F32, -1.25);
            flush(&mut row, w)?;
        }
    }
    for i in 0..mesh.positions.len() {
        for (name, ty) in &layout.vertex_properties {
            put(&mut row, enc, *ty, vertex_value(mesh, name, *ty, i));
        }
        flush(&mut row, w)?;
    }
    let mut at = 0;
    for (f, &n) in mesh.faces.sizes.iter().enumerate() {
        if let Some((_, ty)) = &layout.face_extra {
            put(&mut row, enc, *ty, (f % 5) as f64);
        }
        put(&mut row, enc, layout.face_count, n as f64);
        for &i in &mesh.faces.indices[at..at + n as usize] {
            put(&mut row, enc, layout.face_index, i as f64);
        }
        at += n as usize;
        flush(&mut row, w)?;
    }
    Ok(())
}
