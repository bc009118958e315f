//! FLIP and SSIM of one PNG against another of the same size (`spt::eval::perceptual`),
//! over the pixels that either covers: a pixel is covered where it is not the
//! background, white unless `--background R,G,B` (0–255) says otherwise.
//!
//! ```text
//! cargo run --release --example image_flip -- TEST.png REFERENCE.png [--background 0,0,0]
//! ```

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Parser;
use spt::eval::perceptual::{flip_mean, ssim_mean};
use spt::render::Image;

#[derive(Parser)]
struct Args {
    test: PathBuf,
    reference: PathBuf,
    /// The background colour, R,G,B in 0–255: pixels of it are not covered.
    #[arg(long, default_value = "255,255,255", value_parser = parse_rgb)]
    background: [u8; 3],
}

fn parse_rgb(s: &str) -> Result<[u8; 3], String> {
    let parts: Vec<u8> = (s.split(','))
        .map(|v| v.trim().parse::<u8>().map_err(|e| format!("{v}: {e}")))
        .collect::<Result<_, _>>()?;
    parts.try_into().map_err(|_| "expected R,G,B".to_owned())
}

/// The PNG at `path` as an image covered where it is not `background`.
fn read(path: &Path, background: [u8; 3]) -> anyhow::Result<Image> {
    let rgba = image::open(path)
        .with_context(|| format!("{}: cannot read as an image", path.display()))?
        .to_rgba8();
    let (width, height) = rgba.dimensions();
    let rgba = rgba.into_raw();
    let covered = rgba.chunks_exact(4).map(|p| p[..3] != background).collect();
    Ok(Image {
        width,
        height,
        covered,
        depth: vec![0.0; (width * height) as usize],
        rgba,
    })
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let test = read(&args.test, args.background)?;
    let reference = read(&args.reference, args.background)?;
    anyhow::ensure!(
        (test.width, test.height) == (reference.width, reference.height),
        "{} is {}×{}, {} is {}×{}",
        args.test.display(),
        test.width,
        test.height,
        args.reference.display(),
        reference.width,
        reference.height
    );
    let covered = (test.covered.iter().zip(&reference.covered))
        .filter(|(a, b)| **a || **b)
        .count();
    println!(
        "FLIP {:.4}  SSIM {:.3}  over {covered} pixels",
        flip_mean(&test, &reference),
        ssim_mean(&test, &reference)
    );
    Ok(())
}
