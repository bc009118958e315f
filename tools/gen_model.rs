//! Generates the project's test models: a bumpy, coloured (2,3) torus knot tube.
//!
//! ```text
//! cargo run --release --example gen_model                  # data/torus_knot.ply, 50,000 vertices
//! cargo run --release --example gen_model -- --preset lucy # 14,028,800 vertices / 28,057,600 faces
//! ```
//!
//! The model itself is `spt::io::torus_knot`.

use std::path::PathBuf;

use clap::{Parser, ValueEnum};
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
    Ok(())
}
