//! Image error against a reference (docs/design.md §9): PSNR over the pixels either image
//! covers, hole rate (covered by the reference, not by the test image) and spill rate
//! (the reverse), both relative to the reference's covered pixels.

use serde::Serialize;

use crate::render::Image;

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    /// Peak signal-to-noise ratio in dB over the union of both masks (RGB, 8-bit);
    /// +∞ for identical images.
    pub psnr_db: f64,
    /// PSNR over the pixels both images cover.
    pub psnr_both_db: f64,
    /// PSNR over the pixels both cover that lie more than [`EDGE_PX`] from an edge of the
    /// reference: its silhouette, or a depth step of more than [`DEPTH_STEP`] (relative)
    /// between neighbours. Separates shading error from edge placement.
    pub psnr_interior_db: f64,
    pub hole_rate: f64,
    pub spill_rate: f64,
    /// Pixels in the union of both masks.
    pub union_pixels: usize,
    /// Pixels the interior PSNR was taken over.
    pub interior_pixels: usize,
}

/// Pixels around an edge left out of the interior PSNR.
pub const EDGE_PX: i64 = 2;
/// A relative depth difference between neighbouring pixels that makes an occlusion edge.
pub const DEPTH_STEP: f32 = 0.02;

/// Pixels of `reference` within [`EDGE_PX`] of a silhouette or depth step.
fn near_edges(reference: &Image) -> Vec<bool> {
    let (w, h) = (reference.width as i64, reference.height as i64);
    let at = |x: i64, y: i64| (y * w + x) as usize;
    let mut edge = vec![false; reference.covered.len()];
    for y in 0..h {
        for x in 0..w {
            let i = at(x, y);
            let steps = [(1, 0), (0, 1)].iter().any(|&(dx, dy)| {
                let (nx, ny) = (x + dx, y + dy);
                if nx >= w || ny >= h {
                    return false;
                }
                let j = at(nx, ny);
                let (a, b) = (reference.depth[i], reference.depth[j]);
                reference.covered[i] != reference.covered[j]
                    || (reference.covered[i] && (a - b).abs() > DEPTH_STEP * a.min(b))
            });
            if steps {
                for yy in (y - EDGE_PX).max(0)..=(y + EDGE_PX + 1).min(h - 1) {
                    for xx in (x - EDGE_PX).max(0)..=(x + EDGE_PX + 1).min(w - 1) {
                        edge[at(xx, yy)] = true;
                    }
                }
            }
        }
    }
    edge
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
    let (mut sse_interior, mut interior) = (0.0f64, 0usize);
    let edges = near_edges(reference);
    for (i, &near_edge) in edges.iter().enumerate() {
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
                if !near_edge {
                    sse_interior += e;
                    interior += 1;
                }
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
        psnr_interior_db: psnr(sse_interior, interior),
        hole_rate: holes as f64 / covered.max(1) as f64,
        spill_rate: spills as f64 / covered.max(1) as f64,
        union_pixels: union,
        interior_pixels: interior,
    }
}
