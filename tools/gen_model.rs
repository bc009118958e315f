//! Generates the project's test models: a bumpy, coloured (2,3) torus knot tube.
//!
//! ```text
//! cargo run --release --example gen_model                  # data/torus_knot.ply, 50,000 vertices
//! cargo run --release --example gen_model -- --preset lucy # 14,028,800 vertices / 28,057,600 faces
//! ```
//!
//! The tube has `segments` rings of `sides` vertices; each quad of the grid is split in
//! two triangles and the grid wraps both ways, so the mesh is closed:
//! vertices = segments · sides, triangles = 2 · vertices.

use std::f64::consts::TAU;
use std::path::PathBuf;

use clap::{Parser, ValueEnum};
use spt::io::ply::{Encoding, FaceList, PlyLayout, PolyMesh, write_ply};

#[derive(Clone, Copy, ValueEnum)]
enum Preset {
    /// 500 × 100 = 50,000 vertices with colours: the default model in data/.
    Default,
    /// 13,700 × 1,024 = 14,028,800 vertices / 28,057,600 triangles, no colours: the
    /// size of the Stanford Lucy (533 MB as binary PLY).
    Lucy,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Parser)]
#[command(about = "Writes a bumpy coloured torus knot mesh as PLY")]
struct Args {
    /// Size preset; --segments and --sides override it.
    #[arg(long, value_enum, default_value = "default")]
    preset: Preset,
    /// Rings along the knot.
    #[arg(long)]
    segments: Option<u32>,
    /// Vertices around the tube.
    #[arg(long)]
    sides: Option<u32>,
    /// Leave colours out (on by default for the default preset only).
    #[arg(long)]
    no_colors: bool,
    /// Write the vertices only: the same samples as a point cloud.
    #[arg(long)]
    no_faces: bool,
    #[arg(long, value_enum, default_value = "binary-little-endian")]
    format: Format,
    /// Output file (default: data/torus_knot.ply, or data/large/lucy_knot.ply for lucy).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// Centre line of the (p, q) = (2, 3) torus knot.
fn knot(t: f64) -> [f64; 3] {
    let r = 2.0 + (3.0 * t).cos();
    [r * (2.0 * t).cos(), r * (2.0 * t).sin(), -(3.0 * t).sin()]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// HSV (h in turns) to 8-bit RGB.
fn hsv(h: f64, s: f64, v: f64) -> [u8; 3] {
    let f = |n: f64| {
        let k = (n + h * 6.0).rem_euclid(6.0);
        v - v * s * k.min(4.0 - k).clamp(0.0, 1.0)
    };
    [f(5.0), f(3.0), f(1.0)].map(|c| (c * 255.0).round() as u8)
}

fn torus_knot(segments: u32, sides: u32, colors: bool) -> PolyMesh {
    let (nu, nv) = (segments as usize, sides as usize);
    let mut positions = Vec::with_capacity(nu * nv);
    let mut rgb = Vec::with_capacity(if colors { nu * nv } else { 0 });
    let h = 1e-4;
    for i in 0..nu {
        let u = i as f64 / nu as f64;
        let t = u * TAU;
        let c = knot(t);
        // Frenet frame from central differences: the knot's curvature never vanishes.
        let tangent = normalize(sub(knot(t + h), knot(t - h)));
        let accel = sub(sub(knot(t + h), c), sub(c, knot(t - h)));
        let binormal = normalize(cross(tangent, accel));
        let normal = cross(binormal, tangent);
        for j in 0..nv {
            let v = j as f64 / nv as f64;
            let a = v * TAU;
            // Tube radius with bumps: 12 × 60 bumps over the surface.
            let bump = (a * 6.0).sin() * (t * 60.0).sin();
            let radius = 0.45 * (1.0 + 0.12 * bump);
            let (ca, sa) = (a.cos(), a.sin());
            positions.push([0, 1, 2].map(|k| c[k] + radius * (ca * normal[k] + sa * binormal[k])));
            if colors {
                rgb.push(hsv(u * 3.0, 0.55 + 0.25 * bump, 0.75 + 0.2 * bump));
            }
        }
    }
    let mut faces = FaceList::default();
    for i in 0..nu {
        for j in 0..nv {
            let at = |di: usize, dj: usize| (((i + di) % nu) * nv + (j + dj) % nv) as u32;
            faces.push(&[at(0, 0), at(1, 0), at(1, 1)]);
            faces.push(&[at(0, 0), at(1, 1), at(0, 1)]);
        }
    }
    PolyMesh {
        positions,
        normals: None,
        colors: colors.then_some(rgb),
        faces,
    }
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let (segments, sides, colors, default_out) = match args.preset {
        Preset::Default => (500, 100, true, "data/torus_knot.ply"),
        Preset::Lucy => (13_700, 1_024, false, "data/large/lucy_knot.ply"),
    };
    let segments = args.segments.unwrap_or(segments).max(3);
    let sides = args.sides.unwrap_or(sides).max(3);
    let colors = colors && !args.no_colors;
    let output = args.output.unwrap_or_else(|| PathBuf::from(default_out));
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut mesh = torus_knot(segments, sides, colors);
    if args.no_faces {
        mesh.faces = FaceList::default();
    }
    let encoding = match args.format {
        Format::Ascii => Encoding::Ascii,
        Format::BinaryLittleEndian => Encoding::BinaryLittleEndian,
        Format::BinaryBigEndian => Encoding::BinaryBigEndian,
    };
    let mut layout = PlyLayout::standard(encoding, &mesh);
    layout.comments = vec![format!(
        "spt gen_model: bumpy (2,3) torus knot, {segments} segments x {sides} sides"
    )];
    write_ply(&output, &mesh, &layout)?;
    println!(
        "wrote {} ({} vertices, {} triangles, {} bytes)",
        output.display(),
        mesh.positions.len(),
        mesh.faces.sizes.len(),
        std::fs::metadata(&output)?.len()
    );
    Ok(())
}
