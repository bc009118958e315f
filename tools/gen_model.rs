//! Generates the project's test models: a bumpy, coloured (2,3) torus knot tube.
//!
//! ```text
//! cargo run --release --example gen_model                  # data/torus_knot.ply, 50,000 vertices
//! cargo run --release --example gen_model -- --preset lucy # 14,028,800 vertices / 28,057,600 faces
//! cargo run --release --example gen_model -- --preset lucy --no-faces \
//!     -o data/large/lucy_cloud.ply --las data/large/lucy_cloud.las  # the vertices as a cloud, also as LAS
//! ```
//!
//! The model itself is `spt::io::torus_knot`.

use std::io::Cursor;
use std::path::PathBuf;

use clap::{Parser, ValueEnum};
use glam::{DVec3, Vec3};
use spt::io::ply::{Encoding, FaceList, PlyLayout, write_ply};
use spt::io::torus_knot::torus_knot;

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
    /// Also write the vertices (and colours) as this LAS file, for peers that read only
    /// LAS (PotreeConverter): the PLY's points, each axis quantised to 2⁻³⁰ of the
    /// model's extent.
    #[arg(long)]
    las: Option<PathBuf>,
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
    // The knot winds about z: say so, for readers that would take a PLY as y-up.
    layout.comments = vec![
        format!("spt gen_model: bumpy (2,3) torus knot, {segments} segments x {sides} sides"),
        "up_axis z".to_owned(),
    ];
    write_ply(&output, &mesh, &layout)?;
    println!(
        "wrote {} ({} vertices, {} triangles, {} bytes)",
        output.display(),
        mesh.positions.len(),
        mesh.faces.sizes.len(),
        std::fs::metadata(&output)?.len()
    );
    if let Some(path) = &args.las {
        let bytes = las_bytes(&mesh.positions, mesh.colors.as_deref())?;
        spt::io::atomic::write_atomically(path, |w| w.write_all(&bytes))?;
        println!("wrote {} ({} bytes)", path.display(), bytes.len());
    }
    Ok(())
}

/// The points at `positions` as the PLY stores them (f32), with `colors` if any, as a
/// LAS 1.2 file (point format 2 with colours, 0 without), each axis offset by its least
/// coordinate and scaled by 2⁻³⁰ of its extent (at least 10⁻⁹).
fn las_bytes(positions: &[[f64; 3]], colors: Option<&[[u8; 3]]>) -> anyhow::Result<Vec<u8>> {
    let stored = |p: &[f64; 3]| Vec3::from(p.map(|v| v as f32)).as_dvec3();
    let lo = positions
        .iter()
        .fold(DVec3::INFINITY, |m, p| m.min(stored(p)));
    let hi = positions
        .iter()
        .fold(DVec3::NEG_INFINITY, |m, p| m.max(stored(p)));
    let mut builder = las::Builder::from((1, 2));
    builder.point_format = las::point::Format::new(if colors.is_some() { 2 } else { 0 })?;
    let transforms = [
        &mut builder.transforms.x,
        &mut builder.transforms.y,
        &mut builder.transforms.z,
    ];
    for (axis, t) in transforms.into_iter().enumerate() {
        t.offset = lo[axis];
        t.scale = ((hi[axis] - lo[axis]) / f64::from(1u32 << 30)).max(1e-9);
    }
    let mut writer = las::Writer::new(Cursor::new(Vec::new()), builder.into_header()?)?;
    for (k, p) in positions.iter().enumerate() {
        let color = colors.map(|c| {
            let [r, g, b] = c[k].map(|v| u16::from(v) * 257);
            las::Color::new(r, g, b)
        });
        let DVec3 { x, y, z } = stored(p);
        writer.write_point(las::Point {
            x,
            y,
            z,
            color,
            ..Default::default()
        })?;
    }
    Ok(writer.into_inner()?.into_inner())
}
