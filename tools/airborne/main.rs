//! A simulated airborne LiDAR scan of a known 3D scene ([`scene`]), and the scene's true
//! surfaces ([`truth`]), to measure renders against: two overlapping strips flown along
//! y at `--altitude`, a mirror sweeping ±`--half-angle` across track, pulses `--spacing`
//! apart on the ground both ways, first returns with Gaussian range noise. Writes the
//! returns as LAS (point format 3: the class of what each hit, its colour) and as PLY,
//! and the truth mesh as PLY (`truth.ply`; `truth_regions.ply` the same with the
//! overhung ground marked), all at UTM-sized coordinates.
//!
//!   cargo run --release --example gen_airborne -- --out data/airborne

mod classes;
mod scene;
mod truth;

use std::path::{Path, PathBuf};

use clap::Parser;
use glam::DVec3;
use las::{Builder, Color, Point, Writer, point::Classification, point::Format};
use spt::io::ply::{Encoding, PlyLayout, PolyMesh, write_ply};
use spt::io::scalar::Scalar;

use scene::{Kind, Scene};

#[derive(Parser)]
struct Args {
    /// Folder for scan.las, scan.ply and truth.ply.
    #[arg(long, default_value = "data/airborne")]
    out: PathBuf,
    /// Flying height above the scene's origin, metres.
    #[arg(long, default_value_t = 300.0)]
    altitude: f64,
    /// Half the mirror's sweep, degrees.
    #[arg(long, default_value_t = 20.0)]
    half_angle: f64,
    /// Pulse spacing on the ground, along and across track, metres.
    #[arg(long, default_value_t = 0.5)]
    spacing: f64,
    /// Standard deviation of the range noise, metres.
    #[arg(long, default_value_t = 0.02)]
    noise: f64,
    /// Seed of the noise and of the foliage's free paths.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Where the scene's origin lies in the files (UTM-sized, as real tiles are).
const OFFSET: DVec3 = DVec3::new(500_000.0, 5_000_000.0, 100.0);

/// A return: where, and off what.
struct Return {
    at: DVec3,
    kind: Kind,
}

/// Uniform numbers in (0, 1) (xorshift64*).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// A standard normal number (Box–Muller).
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The returns of both strips that fall on the scene's square.
fn scan(scene: &Scene, args: &Args) -> Vec<Return> {
    let mut rng = Rng(args.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let half_angle = args.half_angle.to_radians();
    let step = (args.spacing / args.altitude).atan();
    let pulses = (2.0 * half_angle / step) as i64;
    let lines = (2.0 * scene.half / args.spacing) as i64;
    let mut returns = Vec::new();
    // Two strips 70 m apart: each sees the whole square, from either side.
    for strip_x in [-35.0, 35.0] {
        for line in 0..=lines {
            let y = -scene.half + line as f64 * args.spacing;
            let o = DVec3::new(strip_x, y, args.altitude);
            for k in 0..=pulses {
                let angle = -half_angle + k as f64 * step;
                let d = DVec3::new(angle.sin(), 0.0, -angle.cos());
                let hit = scene.first_hit(o, d, &mut || rng.uniform());
                let at = o + d * (hit.t + args.noise * rng.normal());
                if at.x.abs() <= scene.half && at.y.abs() <= scene.half {
                    returns.push(Return { at, kind: hit.kind });
                }
            }
        }
    }
    returns
}

fn write_las(path: &Path, returns: &[Return]) -> anyhow::Result<()> {
    let mut builder = Builder::from((1, 2));
    builder.point_format = Format::new(3)?;
    for (t, o) in [
        (&mut builder.transforms.x, OFFSET.x),
        (&mut builder.transforms.y, OFFSET.y),
        (&mut builder.transforms.z, OFFSET.z),
    ] {
        (t.scale, t.offset) = (0.001, o);
    }
    let mut writer = Writer::from_path(path, builder.into_header()?)?;
    for (k, r) in returns.iter().enumerate() {
        let p = r.at + OFFSET;
        let [red, green, blue] = r.kind.color().map(|c| u16::from(c) * 257);
        writer.write_point(Point {
            x: p.x,
            y: p.y,
            z: p.z,
            classification: Classification::new(r.kind as u8)?,
            return_number: 1,
            number_of_returns: 1,
            color: Some(Color::new(red, green, blue)),
            // Pulses 10 µs apart.
            gps_time: Some(k as f64 * 1e-5),
            ..Default::default()
        })?;
    }
    writer.close()?;
    Ok(())
}

/// `mesh` as binary PLY with double positions (UTM coordinates keep millimetres).
fn write_doubles(path: &Path, mesh: &PolyMesh) -> anyhow::Result<()> {
    let mut layout = PlyLayout::standard(Encoding::BinaryLittleEndian, mesh);
    for p in layout.vertex_properties.iter_mut().take(3) {
        p.1 = Scalar::F64;
    }
    layout.comments = vec!["spt gen_airborne".to_owned(), "up_axis z".to_owned()];
    write_ply(path, mesh, &layout)?;
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    std::fs::create_dir_all(&args.out)?;
    let scene = Scene::new();
    let returns = scan(&scene, &args);
    write_las(&args.out.join("scan.las"), &returns)?;
    let cloud = PolyMesh {
        positions: returns.iter().map(|r| (r.at + OFFSET).to_array()).collect(),
        colors: Some(returns.iter().map(|r| r.kind.color()).collect()),
        ..PolyMesh::default()
    };
    write_doubles(&args.out.join("scan.ply"), &cloud)?;
    let truth = truth::truth_mesh(&scene, OFFSET, false);
    write_doubles(&args.out.join("truth.ply"), &truth)?;
    let regions = truth::truth_mesh(&scene, OFFSET, true);
    write_doubles(&args.out.join("truth_regions.ply"), &regions)?;
    let counts: Vec<String> = Kind::ALL
        .iter()
        .map(|k| {
            let n = returns.iter().filter(|r| r.kind == *k).count();
            format!("{k:?} {n}")
        })
        .collect();
    println!(
        "wrote {}: {} returns ({}) and the truth mesh ({} triangles)",
        args.out.display(),
        returns.len(),
        counts.join(", "),
        truth.faces.sizes.len()
    );
    Ok(())
}
