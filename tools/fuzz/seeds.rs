//! The fuzzer's seeds, made by the project's own writers: small meshes and clouds in
//! every encoding, the inputs of the defects in tests/all/hostile_inputs.rs, `.spt` files built from them, and
//! small LAS and LAZ tiles written by the `las` crate (the tests' fixtures).

use std::path::Path;

use glam::{DQuat, DVec3};
use spt::io::ply::{Encoding, PlyLayout, PolyMesh, read_ply, write_ply};
use spt::io::scalar::Scalar;
use spt::surfel::leaf_surfels;
use spt::tree::build_sequential_list;
use spt::tree::instances::Instance;
use spt::tree::instances::table::write_instances;
use spt::tree::spt_file::write_to;

/// Which reader an input is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Ply = 0,
    Spt = 1,
    Las = 2,
    Laz = 3,
    /// A scene file (JSON), naming `seed.instances` beside it.
    Scene = 4,
    /// An instance PLY (one vertex per instance).
    Instances = 5,
}

impl Kind {
    pub fn extension(self) -> &'static str {
        match self {
            Kind::Ply => "ply",
            Kind::Spt => "spt",
            Kind::Las => "las",
            Kind::Laz => "laz",
            Kind::Scene => "json",
            Kind::Instances => "instances",
        }
    }

    pub const ALL: [Kind; 6] = [
        Kind::Ply,
        Kind::Spt,
        Kind::Las,
        Kind::Laz,
        Kind::Scene,
        Kind::Instances,
    ];

    /// The kind of a saved input, by its extension (PLY when it has none known).
    pub fn of(path: &Path) -> Kind {
        match path.extension().and_then(|e| e.to_str()) {
            Some("spt") => Kind::Spt,
            Some("las") => Kind::Las,
            Some("laz") => Kind::Laz,
            Some("json") => Kind::Scene,
            Some("instances") => Kind::Instances,
            _ => Kind::Ply,
        }
    }

    /// Names for the report, in `Kind as usize` order.
    pub const NAMES: [&'static str; 6] = ["PLY", ".spt", "LAS", "LAZ", "scene", "instances"];
}

pub struct Seed {
    pub name: String,
    pub kind: Kind,
    pub bytes: Vec<u8>,
}

fn grid(n: u32, quads: bool) -> PolyMesh {
    let mut m = PolyMesh::default();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64, j as f64);
            m.positions
                .push([x, y, 0.1 * (x * 0.7).sin() * (y * 0.5).cos()]);
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = j * n + i;
            let quad = [v, v + 1, v + n + 1, v + n];
            if quads {
                m.faces.push(&quad);
            } else {
                m.faces.push(&[quad[0], quad[1], quad[2]]);
                m.faces.push(&[quad[0], quad[2], quad[3]]);
            }
        }
    }
    m
}

fn cloud(n: usize) -> PolyMesh {
    let positions: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let t = i as f64 * 0.61803;
            let (u, v) = (t.fract() * 4.0, (i as f64 / n as f64) * 4.0);
            [u, v, 0.2 * (u * 1.3).sin()]
        })
        .collect();
    let colors = (0..n)
        .map(|i| [(i * 7) as u8, (i * 13) as u8, 200])
        .collect();
    PolyMesh {
        positions,
        colors: Some(colors),
        ..PolyMesh::default()
    }
}

fn with_normals(mut m: PolyMesh) -> PolyMesh {
    let n = m.positions.len();
    m.normals = Some(
        (0..n)
            .map(|i| {
                if i % 5 == 0 {
                    [0.0; 3]
                } else {
                    [0.0, 0.0, 1.0]
                }
            })
            .collect(),
    );
    m
}

/// `m` with every colour zero (a writer's empty fields).
fn black(mut m: PolyMesh) -> PolyMesh {
    let n = m.positions.len();
    m.colors = Some(vec![[0; 3]; n]);
    m
}

/// An ASCII cloud whose vertices have x and y only.
fn no_z() -> Vec<u8> {
    b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
      property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n\
      0 0 1 2 3\n1 0 4 5 6\n0 1 7 8 9\n1 1 1 1 1\n"
        .to_vec()
}

fn ply_bytes(dir: &Path, m: &PolyMesh, layout: &PlyLayout) -> Vec<u8> {
    let path = dir.join("seed.ply");
    write_ply(&path, m, layout).expect("write a seed");
    std::fs::read(&path).expect("read a seed back")
}

fn standard(dir: &Path, m: &PolyMesh, e: Encoding) -> Vec<u8> {
    ply_bytes(dir, m, &PlyLayout::standard(e, m))
}

fn doubles(dir: &Path, m: &PolyMesh, e: Encoding) -> Vec<u8> {
    let mut layout = PlyLayout::standard(e, m);
    for p in layout.vertex_properties.iter_mut().take(3) {
        p.1 = Scalar::F64;
    }
    ply_bytes(dir, m, &layout)
}

fn ascii_points(header_extra: &str, rows: &[&str]) -> Vec<u8> {
    let mut s = format!(
        "ply\nformat ascii 1.0\ncomment made by the spt fuzzer\n{header_extra}element vertex {}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
        rows.len()
    );
    for r in rows {
        s.push_str(r);
        s.push('\n');
    }
    s.into_bytes()
}

#[path = "../../tests/all/common/las_files.rs"]
#[allow(dead_code)]
mod las_files;

/// LAS and LAZ tiles of 0, 1, 70 and 500 points (a grid of rows of 64) in point format
/// 3, and of 70 points in formats 1, 6 and 8 (LAS 1.4's extended records); a tile whose
/// colours are zero everywhere; a LAZ of LASzip 1's point-wise compressor.
fn las_seeds() -> Vec<Seed> {
    let mut seeds = Vec::new();
    let tiles = [(0, 3), (1, 3), (70, 3), (500, 3), (70, 1), (70, 6), (70, 8)];
    for (n, format) in tiles {
        for (kind, compressed) in [(Kind::Las, false), (Kind::Laz, true)] {
            seeds.push(Seed {
                name: format!("tile{n}_format{format}_{}", kind.extension()),
                kind,
                bytes: las_files::sample_of_format(n, format, compressed),
            });
        }
    }
    // Point format 3: RGB in the record's last 6 of 34 bytes.
    let mut black = las_files::sample(70, false);
    let data = u32::from_le_bytes([black[96], black[97], black[98], black[99]]) as usize;
    black[data..]
        .chunks_exact_mut(34)
        .for_each(|r| r[28..].fill(0));
    seeds.push(Seed {
        name: "tile70_black_las".into(),
        kind: Kind::Las,
        bytes: black,
    });
    seeds.push(Seed {
        name: "tile70_point_wise_laz".into(),
        kind: Kind::Laz,
        bytes: las_files::point_wise(&las_files::sample(70, true)),
    });
    seeds
}

/// A PLY of triangle strips (a `tristrips` element, −1 restarts) over a 4 × 2 grid.
fn strips_seed() -> Vec<u8> {
    let mut s = ascii_points(
        "",
        &[
            "0 0 0", "1 0 0", "2 0 0", "3 0 0", "0 1 0", "1 1 0", "2 1 0", "3 1 0",
        ],
    );
    let at = s
        .windows(10)
        .position(|w| w == b"end_header")
        .expect("a header");
    s.splice(
        at..at,
        b"element tristrips 1\nproperty list int int vertex_indices\n"
            .iter()
            .copied(),
    );
    s.extend(b"11 0 4 1 5 -1 1 5 2 6 3 7\n");
    s
}

/// Every seed, PLY first, then `.spt` files built from some of them, then LAS and LAZ.
pub fn all(dir: &Path) -> Vec<Seed> {
    let square = {
        let mut m = grid(2, false);
        m.colors = Some(vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]]);
        with_normals(m)
    };
    let mut isolated = grid(3, false);
    isolated.positions.push([1.0, 1.0, 0.5]);
    let isolated = with_normals(isolated);
    let mut outlier = grid(5, false);
    outlier.positions[7][0] = 1e10;
    let unknown = {
        let mut layout = PlyLayout::standard(Encoding::BinaryLittleEndian, &square);
        layout
            .vertex_properties
            .insert(1, ("confidence".into(), Scalar::U16));
        layout.extra_element = Some(("camera".into(), 2));
        layout.face_extra = Some(("flags".into(), Scalar::I16));
        layout.comments = vec!["a comment".into()];
        ply_bytes(dir, &square, &layout)
    };
    let ply: Vec<(&str, Vec<u8>)> = vec![
        (
            "square_le",
            standard(dir, &square, Encoding::BinaryLittleEndian),
        ),
        ("square_ascii", standard(dir, &square, Encoding::Ascii)),
        (
            "square_be_double",
            doubles(dir, &square, Encoding::BinaryBigEndian),
        ),
        (
            "grid_quads",
            standard(dir, &grid(6, true), Encoding::BinaryLittleEndian),
        ),
        (
            "grid_ascii_quads",
            standard(dir, &grid(4, true), Encoding::Ascii),
        ),
        ("cloud_ascii", standard(dir, &cloud(64), Encoding::Ascii)),
        (
            "cloud_normals_le",
            standard(dir, &with_normals(cloud(48)), Encoding::BinaryLittleEndian),
        ),
        ("unknown_property", unknown),
        (
            "isolated_with_normal",
            standard(dir, &isolated, Encoding::Ascii),
        ),
        (
            "outlier_1e10",
            doubles(dir, &outlier, Encoding::BinaryLittleEndian),
        ),
        (
            "propertyless_element",
            ascii_points("element e 9999999999\n", &["1 2 3"]),
        ),
        (
            "ascii_float_1e300",
            ascii_points("", &["0 0 0", "1 0 0", "0 1 0", "1e300 0 0"]),
        ),
        ("single_-1e308", ascii_points("", &["-1e308 -1e308 -1e308"])),
        ("tristrips", strips_seed()),
        (
            "obj_info",
            ascii_points("obj_info scanner 1\n", &["0 0 0", "0 0 1", "0 1 0"]),
        ),
        // Rows of the wrong length (refused, naming the row and line).
        (
            "ascii_extra_value",
            ascii_points("", &["0 0 0 9", "1 0 0", "0 1 0"]),
        ),
        (
            "ascii_short_row",
            ascii_points("", &["0 0 0", "1 0", "0 1 0"]),
        ),
        ("no_points", ascii_points("", &[])),
        (
            "black_cloud",
            standard(dir, &black(cloud(40)), Encoding::Ascii),
        ),
        ("no_z", no_z()),
        (
            "up_comment",
            ascii_points("comment up_axis -y\n", &["0 0 0", "0 0 1", "0 1 0"]),
        ),
    ];
    let mut seeds: Vec<Seed> = ply
        .into_iter()
        .map(|(name, bytes)| Seed {
            name: name.into(),
            kind: Kind::Ply,
            bytes,
        })
        .collect();
    for from in [
        "square_le",
        "grid_quads",
        "cloud_ascii",
        "cloud_normals_le",
        "outlier_1e10",
    ] {
        let bytes = &seeds.iter().find(|s| s.name == from).expect("a seed").bytes;
        let path = dir.join("from.ply");
        std::fs::write(&path, bytes).expect("write a seed");
        let model = read_ply(&path).expect("seeds are valid");
        let list = build_sequential_list(leaf_surfels(&model.geometry));
        let mut spt = Vec::new();
        write_to(&mut spt, &list).expect("write to memory");
        seeds.push(Seed {
            name: format!("{from}_tree"),
            kind: Kind::Spt,
            bytes: spt,
        });
    }
    seeds.extend(las_seeds());
    seeds.extend(scene_seeds());
    seeds
}

/// The instance file every scene seed names (written beside the inputs, as
/// `seed.instances`, by [`write_scene_files`]): three instances of two models.
fn instances_seed() -> Vec<u8> {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("seed.instances");
    let instances: Vec<Instance> = (0..3)
        .map(|k| {
            let q = DQuat::from_rotation_z(k as f64);
            Instance::checked(k % 2, DVec3::new(k as f64, 2.0, 3.0), q, 1.0 + k as f64, 2)
                .expect("a valid instance")
        })
        .collect();
    write_instances(&path, &instances).expect("write the instances");
    std::fs::read(&path).expect("read them back")
}

/// Scene files and instance files.
fn scene_seeds() -> Vec<Seed> {
    let scenes = [
        r#"{"models": ["a.ply", "b.spt"], "instances": [{"model": 0}, {"model": 1, "translation": [512000.5, 5403000.25, 200], "yaw": 30, "scale": 1.5}, {"file": "seed.instances"}]}"#,
        r#"{"models": ["a.ply"], "instances": [{"model": 0, "rotation": [0, 0, 0.7071, 0.7071]}]}"#,
    ];
    let ascii = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                 property float z\nproperty float yaw\nproperty uchar model\nend_header\n\
                 1 2 3 0.5 0\n4 5 6 1.5 1\n";
    let mut seeds: Vec<Seed> = scenes
        .iter()
        .enumerate()
        .map(|(k, text)| Seed {
            name: format!("scene_{k}"),
            kind: Kind::Scene,
            bytes: text.as_bytes().to_vec(),
        })
        .collect();
    seeds.push(Seed {
        name: "instances_le".into(),
        kind: Kind::Instances,
        bytes: instances_seed(),
    });
    seeds.push(Seed {
        name: "instances_ascii".into(),
        kind: Kind::Instances,
        bytes: ascii.as_bytes().to_vec(),
    });
    seeds
}

/// Writes the instance file the scene seeds name into `dir`, where inputs are run.
pub fn write_scene_files(dir: &Path) {
    std::fs::write(dir.join("seed.instances"), instances_seed()).expect("write seed.instances");
}
