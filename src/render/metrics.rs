//! Image error against a reference (DESIGN.md §9): PSNR over the pixels either image
//! covers, hole rate (covered by the reference, not by the test image) and spill rate
//! (the reverse), both relative to the reference's covered pixels.

use serde::Serialize;

use super::Image;

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    /// Peak signal-to-noise ratio in dB over the union of both masks (RGB, 8-bit);
    /// +∞ for identical images.
    pub psnr_db: f64,
    /// PSNR over the pixels both images cover: shading alone, without silhouettes.
    pub psnr_both_db: f64,
    pub hole_rate: f64,
    pub spill_rate: f64,
    /// Pixels in the union of both masks.
    pub union_pixels: usize,
}

/// Compares `test` with `reference` (same size).
pub fn compare(test: &Image, reference: &Image) -> Comparison {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height),
        "image sizes differ"
    );
    let (mut sse, mut union, mut holes, mut spills, mut covered) =
        (0.0f64, 0usize, 0usize, 0usize, 0usize);
    let (mut sse_both, mut both) = (0.0f64, 0usize);
    for i in 0..test.covered.len() {
        let (a, b) = (test.covered[i], reference.covered[i]);
        covered += b as usize;
        holes += (b && !a) as usize;
        spills += (a && !b) as usize;
        if a || b {
            union += 1;
            let mut e = 0.0;
            for c in 0..3 {
                let d = test.rgba[i * 4 + c] as f64 - reference.rgba[i * 4 + c] as f64;
                e += d * d;
            }
            sse += e;
            if a && b {
                sse_both += e;
                both += 1;
            }
        }
    }
    let psnr = |sse: f64, n: usize| {
        let mse = sse / (3 * n.max(1)) as f64;
        if mse == 0.0 {
            f64::INFINITY
        } else {
            10.0 * (255.0f64 * 255.0 / mse).log10()
        }
    };
    Comparison {
        psnr_db: psnr(sse, union),
        psnr_both_db: psnr(sse_both, both),
        hole_rate: holes as f64 / covered.max(1) as f64,
        spill_rate: spills as f64 / covered.max(1) as f64,
        union_pixels: union,
    }
}

impl Image {
    /// Writes the image as PNG, atomically.
    pub fn save_png(&self, path: &std::path::Path) -> anyhow::Result<()> {
        let img = image::RgbaImage::from_raw(self.width, self.height, self.rgba.clone())
            .ok_or_else(|| anyhow::anyhow!("image buffer of the wrong size"))?;
        crate::io::atomic::write_atomically(path, |w| {
            let mut bytes = Vec::new();
            img.write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .map_err(std::io::Error::other)?;
            w.write_all(&bytes)
        })
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))
    }
}
