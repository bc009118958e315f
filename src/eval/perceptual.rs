//! Perceptual image error (docs/design.md §9): NVIDIA FLIP (the `nv-flip` crate, which
//! wgpu's own tests use) and SSIM, each averaged over the pixels either image covers,
//! against an antialiased reference: a frame rendered at k×k the size with each k×k
//! block averaged in linear light ([`downsample`]).

use crate::render::Image;
use crate::render::linear_to_srgb;

/// Pixels per degree of visual angle FLIP assumes: a 0.7 m viewing distance from a
/// 24-inch 4K screen (FLIP's default, 67).
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

fn rgb(image: &Image) -> Vec<u8> {
    image
        .rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// The union of both images' coverage.
fn union(a: &Image, b: &Image) -> Vec<bool> {
    a.covered
        .iter()
        .zip(&b.covered)
        .map(|(x, y)| *x || *y)
        .collect()
}

/// Mean of `values` over the pixels `mask` keeps (0 when it keeps none).
fn masked_mean(values: &[f32], mask: &[bool]) -> f64 {
    let (sum, n) = values
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0f64, 0usize), |(s, n), (v, _)| (s + *v as f64, n + 1));
    sum / n.max(1) as f64
}

/// The FLIP error (0: identical … 1) of each pixel of `test` against `reference` (same
/// size), row-major.
pub fn flip_map(test: &Image, reference: &Image) -> Vec<f32> {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height)
    );
    let (w, h) = (test.width, test.height);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(test));
    nv_flip::flip(r, t, FLIP_PIXELS_PER_DEGREE).to_vec()
}

/// `test`'s FLIP error against `reference` as a picture, in the magma colours FLIP's own
/// tool uses (black: none … pale yellow: 1), white where neither image is covered.
pub fn flip_heat_map(test: &Image, reference: &Image) -> Image {
    let (w, h) = (test.width, test.height);
    let errors = nv_flip::FlipImageFloat::with_data(w, h, &flip_map(test, reference));
    let colours = errors.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let covered = union(test, reference);
    let rgba = colours
        .chunks_exact(3)
        .zip(&covered)
        .flat_map(|(c, &on)| {
            if on {
                [c[0], c[1], c[2], 255]
            } else {
                [255; 4]
            }
        })
        .collect();
    Image {
        width: w,
        height: h,
        rgba,
        covered,
        depth: vec![0.0; (w * h) as usize],
    }
}

/// Mean FLIP error of `test` against `reference` over the pixels either covers.
pub fn flip_mean(test: &Image, reference: &Image) -> f64 {
    masked_mean(&flip_map(test, reference), &union(test, reference))
}

/// 8-bit luma (Rec. 601 weights on the sRGB-encoded channels), as SSIM is usually taken.
fn luma(image: &Image) -> Vec<f32> {
    image
        .rgba
        .chunks_exact(4)
        .map(|p| 0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32)
        .collect()
}

/// Separable Gaussian blur (σ = 1.5, 11 taps, clamped at the borders).
fn blur(v: &[f32], w: usize, h: usize) -> Vec<f32> {
    let k: Vec<f32> = (-5i32..=5)
        .map(|i| (-(i * i) as f32 / (2.0 * 1.5 * 1.5)).exp())
        .collect();
    let norm: f32 = k.iter().sum();
    let pass = |src: &[f32], horizontal: bool| -> Vec<f32> {
        let mut out = vec![0.0; src.len()];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for (j, kj) in k.iter().enumerate() {
                    let d = j as i64 - 5;
                    let (xx, yy) = if horizontal {
                        ((x as i64 + d).clamp(0, w as i64 - 1) as usize, y)
                    } else {
                        (x, (y as i64 + d).clamp(0, h as i64 - 1) as usize)
                    };
                    s += kj * src[yy * w + xx];
                }
                out[y * w + x] = s / norm;
            }
        }
        out
    };
    pass(&pass(v, true), false)
}

/// Mean SSIM (Wang et al. 2004: Gaussian windows σ = 1.5, C₁ = (0.01·255)²,
/// C₂ = (0.03·255)², on luma) of `test` against `reference`, over the pixels either
/// covers; 1 for identical images.
pub fn ssim_mean(test: &Image, reference: &Image) -> f64 {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height)
    );
    let (w, h) = (test.width as usize, test.height as usize);
    let (x, y) = (luma(test), luma(reference));
    let product = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(p, q)| p * q).collect::<Vec<_>>();
    let (mx, my) = (blur(&x, w, h), blur(&y, w, h));
    let (xx, yy, xy) = (
        blur(&product(&x, &x), w, h),
        blur(&product(&y, &y), w, h),
        blur(&product(&x, &y), w, h),
    );
    let (c1, c2) = ((0.01f32 * 255.0).powi(2), (0.03f32 * 255.0).powi(2));
    let map: Vec<f32> = (0..w * h)
        .map(|i| {
            let (vx, vy, cov) = (
                xx[i] - mx[i] * mx[i],
                yy[i] - my[i] * my[i],
                xy[i] - mx[i] * my[i],
            );
            ((2.0 * mx[i] * my[i] + c1) * (2.0 * cov + c2))
                / ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2))
        })
        .collect();
    masked_mean(&map, &union(test, reference))
}

/// `image` reduced k times in each direction, each k×k block averaged in linear light
/// (the antialiased reference). A pixel is covered when any of its block is; its depth is
/// the mean over the covered ones.
pub fn downsample(image: &Image, k: u32) -> Image {
    let (w, h) = (image.width / k, image.height / k);
    let mut out = Image {
        width: w,
        height: h,
        rgba: vec![0; (w * h * 4) as usize],
        covered: vec![false; (w * h) as usize],
        depth: vec![0.0; (w * h) as usize],
    };
    let to_srgb = |c: f32| (linear_to_srgb(c) * 255.0).round().clamp(0.0, 255.0) as u8;
    for y in 0..h {
        for x in 0..w {
            let (mut sum, mut covered, mut depth) = ([0.0f32; 3], 0u32, 0.0f32);
            for dy in 0..k {
                for dx in 0..k {
                    let i = ((y * k + dy) * image.width + x * k + dx) as usize;
                    for (s, v) in sum.iter_mut().zip(image.linear_rgb(i)) {
                        *s += v;
                    }
                    if image.covered[i] {
                        covered += 1;
                        depth += image.depth[i];
                    }
                }
            }
            let o = (y * w + x) as usize;
            let n = (k * k) as f32;
            let [r, g, b] = sum.map(|v| to_srgb(v / n));
            out.rgba[4 * o..4 * o + 4].copy_from_slice(&[r, g, b, 255]);
            out.covered[o] = covered > 0;
            out.depth[o] = if covered > 0 {
                depth / covered as f32
            } else {
                0.0
            };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Image {
        let mut rgba = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let [r, g, b] = f(x, y);
                rgba.extend_from_slice(&[r, g, b, 255]);
            }
        }
        Image {
            width: w,
            height: h,
            rgba,
            covered: vec![true; (w * h) as usize],
            depth: vec![1.0; (w * h) as usize],
        }
    }

    #[test]
    fn identical_images_have_no_error_and_full_similarity() {
        let a = image(64, 48, |x, y| [(x * 4) as u8, (y * 5) as u8, 128]);
        assert_eq!(flip_mean(&a, &a), 0.0);
        assert!((ssim_mean(&a, &a) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn banding_raises_flip_and_lowers_ssim() {
        let smooth = image(64, 64, |x, _| [(x * 4) as u8; 3]);
        let banded = image(64, 64, |x, _| [((x / 8) * 32) as u8; 3]);
        let noisy = image(64, 64, |x, y| {
            [((x * 4) as u8) ^ (((x * 7 + y * 13) % 5) as u8); 3]
        });
        let (band, noise) = (flip_mean(&banded, &smooth), flip_mean(&noisy, &smooth));
        assert!(band > 0.05 && band > noise, "banding {band}, noise {noise}");
        assert!(ssim_mean(&banded, &smooth) < ssim_mean(&noisy, &smooth));
    }

    #[test]
    fn downsampling_averages_in_linear_light() {
        // Black and white in a checkerboard average to mid grey in linear light: sRGB 188.
        let fine = image(
            4,
            4,
            |x, y| if (x + y) % 2 == 0 { [0; 3] } else { [255; 3] },
        );
        let coarse = downsample(&fine, 2);
        assert_eq!((coarse.width, coarse.height), (2, 2));
        assert!(coarse.rgba.chunks(4).all(|p| p[0] == 188 && p[1] == 188));
    }
}
