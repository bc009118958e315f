//! Where a model's f32 positions are measured from: an origin that outliers do not
//! move, and the range of offsets from it that the rest of the engine can hold.
//!
//! * **Core box.** Per axis, the quartiles `a`, `b` of the vertices (from an evenly
//!   strided sample of at most [`SAMPLE`] of them), and `w` = the largest `b − a` over
//!   the axes: robust to up to a quarter of the vertices anywhere, on any count. A
//!   vertex with a coordinate outside `[a − K·w, b + K·w]` (K = [`OUTLIER_SPANS`]) is
//!   an *outlier*; the core box is the bounding box of the others. On a model without outliers it is the bounding box
//!   itself. When `w` is 0 or not finite (most samples coincide, or the quantiles
//!   span more than f64 can hold) nothing is an outlier.
//! * **Origin** = centre of the core box, computed as `min/2 + max/2` so that it never
//!   overflows (it equals `(min + max)/2` whenever that does not).
//! * **Representable** vertices lie within [`MAX_OFFSET`] of the origin on every axis:
//!   beyond that, squared distances of f32 positions (k-d search, disk radii, the
//!   shaders' ray–disk tests) overflow. The others are dropped and counted like NaN
//!   rows. When some finite vertex lies further than `MAX_OFFSET / 2` from the origin
//!   taken over all of them, only those within `MAX_OFFSET / 2` of the sample's
//!   per-axis median are kept, and the boxes and origin are measured again over them:
//!   the new origin lies inside their box, so within `MAX_OFFSET` of each.

use glam::DVec3;
use rayon::prelude::*;

use super::bounds::Bounds;
use crate::io::rows::VertexRows;

/// Largest offset from the origin, per axis, that a kept vertex may have: 2⁶⁰ ≈ 1.15·10¹⁸
/// model units (the square of a distance between two such points still fits an f32).
pub const MAX_OFFSET: f64 = (1u64 << 60) as f64;
/// Fraction of the samples below the lower (above the upper) quantile of the core:
/// the quartiles.
pub const TAIL: f64 = 0.25;
/// How many interquartile spans beyond the quartiles a vertex must lie to be an
/// outlier (for a uniform box, 8 times the box's size beyond it).
pub const OUTLIER_SPANS: f64 = 16.0;
/// Most vertices sampled for the quantiles.
pub const SAMPLE: usize = 1 << 14;

const CHUNK: usize = 1 << 15;

/// Where positions are measured from, and which rows are kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub origin: DVec3,
    /// Bounding box of the kept vertices.
    pub bounds: Bounds,
    /// Bounding box of the kept vertices that are not outliers.
    pub core: Bounds,
    /// Kept vertices outside the core's window.
    pub outliers: u64,
    /// Rows dropped for a NaN or infinite coordinate.
    pub nonfinite: u64,
    /// Rows dropped for lying beyond [`MAX_OFFSET`] of the origin.
    pub out_of_range: u64,
    /// The kept rows in order; `None` when every row is kept.
    pub kept: Option<Vec<u32>>,
}

type Keep<'a> = &'a (dyn Fn([f64; 3]) -> bool + Sync);

fn is_finite(p: [f64; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}

/// The bounding box of the rows that `keep` accepts, and how many it accepts.
fn survey<R: VertexRows>(rows: &R, keep: Keep) -> (Bounds, u64) {
    (0..rows.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .fold(
            || (Bounds::empty(), 0u64),
            |(b, n), i| {
                let p = rows.position(i);
                if keep(p) { (b.grow(p), n + 1) } else { (b, n) }
            },
        )
        .reduce(|| (Bounds::empty(), 0), |a, b| (a.0.union(b.0), a.1 + b.1))
}

/// Per-axis quantiles of an evenly strided sample of the rows `keep` accepts.
struct Quantiles {
    low: [f64; 3],
    median: DVec3,
    high: [f64; 3],
}

impl Quantiles {
    fn of<R: VertexRows>(rows: &R, keep: Keep) -> Option<Quantiles> {
        let stride = rows.len().div_ceil(SAMPLE).max(1);
        let sample: Vec<[f64; 3]> = (0..rows.len())
            .step_by(stride)
            .map(|i| rows.position(i))
            .filter(|p| keep(*p))
            .collect();
        Quantiles::of_sample(&sample)
    }

    fn of_sample(sample: &[[f64; 3]]) -> Option<Quantiles> {
        let m = sample.len();
        if m == 0 {
            return None;
        }
        let rank = |q: f64| ((q * (m - 1) as f64).round() as usize).min(m - 1);
        let mut axis: Vec<f64> = Vec::with_capacity(m);
        let mut at = |k: usize, q: f64| {
            axis.clear();
            axis.extend(sample.iter().map(|p| p[k]));
            *axis.select_nth_unstable_by(rank(q), f64::total_cmp).1
        };
        Some(Quantiles {
            low: std::array::from_fn(|k| at(k, TAIL)),
            median: DVec3::from_array(std::array::from_fn(|k| at(k, 0.5))),
            high: std::array::from_fn(|k| at(k, 1.0 - TAIL)),
        })
    }

    /// The window outside which a row is an outlier (module doc), or `None` when
    /// nothing can be one.
    fn window(&self) -> Option<Bounds> {
        let span = (0..3)
            .map(|k| self.high[k] - self.low[k])
            .fold(0.0, f64::max);
        let margin = OUTLIER_SPANS * span;
        (margin > 0.0 && margin.is_finite()).then(|| Bounds {
            min: self.low.map(|x| x - margin),
            max: self.high.map(|x| x + margin),
        })
    }
}

/// What [`measure`] finds over the rows a filter accepts.
struct Measured {
    bounds: Bounds,
    core: Bounds,
    origin: DVec3,
    /// Per-axis median of the sample: where to look for rows in range when the
    /// origin is not such a place.
    median: DVec3,
    kept: u64,
    outliers: u64,
}

/// Bounds, core, origin and outlier count of the rows that `keep` accepts.
fn measure<R: VertexRows>(rows: &R, keep: Keep) -> Measured {
    let (bounds, kept) = survey(rows, keep);
    let quantiles = Quantiles::of(rows, keep);
    let (core, inliers) = match quantiles.as_ref().and_then(Quantiles::window) {
        // No row lies outside the window: no second pass.
        Some(w) if !(w.contains(bounds.min) && w.contains(bounds.max)) => {
            let (core, inliers) = survey(rows, &|p| keep(p) && w.contains(p));
            // The quantiles come from accepted rows, so the core is not empty.
            if inliers == 0 {
                (bounds, kept)
            } else {
                (core, inliers)
            }
        }
        _ => (bounds, kept),
    };
    Measured {
        bounds,
        core,
        origin: core.center(),
        median: quantiles.map_or(core.center(), |q| q.median),
        kept,
        outliers: kept - inliers,
    }
}

/// The quantiles' part of the rule for a model read a batch at a time (out of core),
/// from an evenly strided sample of the points a filter accepts (at most [`SAMPLE`],
/// strided over the file's rows as [`frame`] strides them): the sample's per-axis
/// median and the window outside which a point is an outlier (`None` when nothing
/// can be one). `None` for an empty sample.
pub fn sample_window(sample: &[[f64; 3]]) -> Option<(DVec3, Option<Bounds>)> {
    let q = Quantiles::of_sample(sample)?;
    Some((q.median, q.window()))
}

/// Whether `p` lies within `reach` of `origin` on every axis.
pub fn within(p: [f64; 3], origin: DVec3, reach: f64) -> bool {
    (0..3).all(|k| (p[k] - origin[k]).abs() <= reach)
}

/// Chooses the origin of `rows` and the rows kept. A file without rows has the empty
/// frame (origin zero, empty boxes); one with rows fails when none is kept.
pub(crate) fn frame<R: VertexRows>(rows: &R) -> Result<Frame, String> {
    let n = rows.len() as u64;
    if n == 0 {
        return Ok(Frame {
            origin: DVec3::ZERO,
            bounds: Bounds::empty(),
            core: Bounds::empty(),
            outliers: 0,
            nonfinite: 0,
            out_of_range: 0,
            kept: None,
        });
    }
    let m = measure(rows, &is_finite);
    let finite = m.kept;
    if finite == 0 {
        return Err(format!("none of the {n} vertices has finite coordinates"));
    }
    let reach = MAX_OFFSET / 2.0;
    let (m, kept) =
        if within(m.bounds.min, m.origin, reach) && within(m.bounds.max, m.origin, reach) {
            let kept = (finite < n).then(|| kept_rows(rows, &is_finite));
            (m, kept)
        } else {
            let anchor = m.median;
            let in_range = move |p: [f64; 3]| is_finite(p) && within(p, anchor, reach);
            let kept = kept_rows(rows, &in_range);
            if kept.is_empty() {
                return Err(format!(
                    "none of the {finite} finite vertices lies within {MAX_OFFSET:e} of their \
                 median: coordinates from ({:e}, {:e}, {:e}) to ({:e}, {:e}, {:e}) cannot be \
                 stored as offsets from one origin",
                    m.bounds.min[0],
                    m.bounds.min[1],
                    m.bounds.min[2],
                    m.bounds.max[0],
                    m.bounds.max[1],
                    m.bounds.max[2],
                ));
            }
            (measure(rows, &in_range), Some(kept))
        };
    Ok(Frame {
        origin: m.origin,
        bounds: m.bounds,
        core: m.core,
        outliers: m.outliers,
        nonfinite: n - finite,
        out_of_range: finite - m.kept,
        kept,
    })
}

/// The rows `keep` accepts, in order.
fn kept_rows<R: VertexRows>(rows: &R, keep: Keep) -> Vec<u32> {
    (0..rows.len() as u32)
        .into_par_iter()
        .with_min_len(CHUNK)
        .filter(|&i| keep(rows.position(i as usize)))
        .collect()
}
