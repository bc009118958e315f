//! Writes a large synthetic LiDAR tile as LAS (point format 2: RGB, intensity, class,
//! returns), streamed point by point so that any size fits in memory: a city-like
//! terrain of `--points` points over a square of `--size` metres at UTM coordinates,
//! rows of scan lines 0.5 m apart with jitter, rolling ground, boxes of buildings
//! (class 6) on a block grid, ground class 2, colours from height and block.
//!
//!   cargo run --release --example gen_cloud -- --points 200000000 --out data/large/city_200m.las

use std::io::BufWriter;
use std::path::PathBuf;

use clap::Parser;
use las::{Builder, Color, Point, Writer, point::Classification, point::Format};

#[derive(Parser)]
struct Args {
    /// Points to write.
    #[arg(long, default_value_t = 200_000_000)]
    points: u64,
    /// Side of the square tile, metres.
    #[arg(long, default_value_t = 4000.0)]
    size: f64,
    #[arg(long, default_value = "data/large/city_200m.las")]
    out: PathBuf,
}

/// Height of the ground and of buildings at (x, y), metres, and whether it is a roof.
fn height(x: f64, y: f64) -> (f64, bool) {
    let ground = 20.0 * (x / 700.0).sin() * (y / 900.0).cos() + 5.0 * (x / 130.0 + y / 170.0).sin();
    let (bx, by) = ((x / 60.0).floor(), (y / 60.0).floor());
    let (fx, fy) = (x / 60.0 - bx, y / 60.0 - by);
    let hash = ((bx * 73.0 + by * 151.0).sin() * 43758.5).fract().abs();
    let inside = (0.2..0.8).contains(&fx) && (0.25..0.75).contains(&fy) && hash > 0.35;
    if inside {
        (ground + 8.0 + 40.0 * hash, true)
    } else {
        (ground, false)
    }
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if let Some(dir) = args.out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut builder = Builder::from((1, 2));
    builder.point_format = Format::new(2)?;
    for t in [
        &mut builder.transforms.x,
        &mut builder.transforms.y,
        &mut builder.transforms.z,
    ] {
        t.scale = 0.001;
    }
    builder.transforms.x.offset = 500_000.0;
    builder.transforms.y.offset = 5_000_000.0;
    let header = builder.into_header()?;
    let file = BufWriter::with_capacity(8 << 20, std::fs::File::create(&args.out)?);
    let mut writer = Writer::new(file, header)?;
    // Scan lines 0.5 m apart along y; points along x spaced to reach the count.
    let lines = (args.size / 0.5).floor() as u64;
    let per_line = args.points.div_ceil(lines);
    let dx = args.size / per_line as f64;
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut jitter = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut written = 0u64;
    'lines: for line in 0..lines {
        let y = line as f64 * 0.5;
        for k in 0..per_line {
            if written == args.points {
                break 'lines;
            }
            let x = (k as f64 + 0.5 + 0.4 * jitter()) * dx;
            let y = y + 0.05 * jitter();
            let (z, roof) = height(x, y);
            let shade = ((z + 30.0) / 100.0).clamp(0.0, 1.0);
            let color = if roof {
                Color::new((120.0 + 100.0 * shade) as u16 * 256, 90 * 256, 80 * 256)
            } else {
                Color::new(70 * 256, (110.0 + 80.0 * shade) as u16 * 256, 60 * 256)
            };
            writer.write_point(Point {
                x: 500_000.0 + x,
                y: 5_000_000.0 + y,
                z: z + 0.02 * jitter(),
                intensity: (500.0 + 400.0 * shade) as u16,
                classification: if roof {
                    Classification::Building
                } else {
                    Classification::Ground
                },
                return_number: 1,
                number_of_returns: 1,
                color: Some(color),
                ..Default::default()
            })?;
            written += 1;
        }
    }
    writer.close()?;
    println!("wrote {} ({written} points)", args.out.display());
    Ok(())
}
