//! Delaunay triangulations in x–y (a terrain's TIN), made by delaunator: of a large set
//! in vertical strips on all cores ([`strips`]), and of a set less some of its samples
//! from the set's own ([`removal`]). Both keep the triangles that stay Delaunay and
//! fill the rest of the plane from a small triangulation ([`fill`]).
//!
//! Of the samples that share an x–y a triangulation holds one: here always the least
//! ([`held_by_least_twins`]), so that how a triangulation was made shows only where
//! four samples lie on one circle (a tie, where Delaunay allows either diagonal).

mod fill;
mod removal;
mod strips;
mod twins;

use delaunator::Point;
use glam::{DVec2, Vec2, Vec3};
use rayon::prelude::*;

use super::heap;

pub use removal::without;
pub use twins::Unheld;

/// Samples per strip of [`delaunay_xy`]: sets of fewer than two strips' samples are
/// triangulated whole. A fixed count (not one per core) keeps the triangulation, ties
/// and all, the same on every machine.
pub const STRIP_SAMPLES: usize = 250_000;

/// Most strips of [`delaunay_xy`].
pub const MAX_STRIPS: usize = 16;

/// The Delaunay triangulation of `positions` in x–y, every triangle wound as
/// delaunator winds them, long triangles kept; of the samples that share an x–y the
/// least is held. In [`strips`] where there are many.
pub fn delaunay_xy(positions: &[Vec3]) -> Vec<[u32; 3]> {
    delaunay_xy_telling(positions, &|_| {})
}

/// [`delaunay_xy`], telling `triangulated` how many more samples are triangulated as
/// each strip is (all of them at once where there is one), for a progress bar: the
/// counts add up to the samples, or to fewer where the strips do not tell the
/// triangulation and the set is triangulated whole.
pub fn delaunay_xy_telling(
    positions: &[Vec3],
    triangulated: &(dyn Fn(usize) + Sync),
) -> Vec<[u32; 3]> {
    let strips = positions.len().div_ceil(STRIP_SAMPLES).min(MAX_STRIPS);
    let mut triangles = match strips {
        0..=1 => {
            let whole = whole(positions);
            triangulated(positions.len());
            whole
        }
        _ => strips::in_strips(positions, strips, triangulated).unwrap_or_else(|| whole(positions)),
    };
    if strips > 1 {
        // glibc keeps what a thread frees in that thread's arena, where the threads
        // that build the rest cannot reuse it: on the generated city's 2 M samples, in
        // 7 strips on 2 cores, the convert's peak grew from 0.72 to 0.87 GiB without
        // this.
        heap::give_back_freed_memory();
    }
    held_by_least_twins(positions, &mut triangles);
    triangles
}

/// delaunator's triangulation of all of `positions` at once.
fn whole(positions: &[Vec3]) -> Vec<[u32; 3]> {
    let all: Vec<u32> = (0..positions.len() as u32).collect();
    let order = swept(positions, &all);
    drop(all);
    let points: Vec<Point> = order.iter().map(|&v| xy(&positions[v as usize])).collect();
    // Only the triangles are kept (their half-edges and hull would double the peak).
    let delaunator::Triangulation { triangles, .. } = delaunator::triangulate(&points);
    drop(points);
    (triangles.chunks_exact(3))
        .map(|t| [t[0], t[1], t[2]].map(|k| order[k]))
        .collect()
}

/// `samples` in the order delaunator adds them, nearly: by distance in x–y from the
/// centre of their box (delaunator sweeps outward from a seed triangle near it), ties
/// by index. Given so, each sample's coordinates and the triangles it makes lie in
/// memory beside those of the samples added just before it, which its triangles join;
/// given in any other order, each addition reads far apart. The triangulation is the
/// same but where four samples lie on one circle (a tie, where Delaunay allows either
/// diagonal). On a 3.1 M-point job of the generated city tile in 13 strips (one core,
/// 2026-12-02), delaunator took 1.59 and 1.83 s in all with each strip's samples in
/// the file's order, 1.44 and 1.61 s so; with them sorted by x, 2.47 and 2.60 s, and
/// 1.66 and 1.67 s so.
fn swept(positions: &[Vec3], samples: &[u32]) -> Vec<u32> {
    let at = |v: u32| positions[v as usize].truncate();
    let (lo, hi) = (samples.iter()).fold((Vec2::MAX, Vec2::MIN), |(lo, hi), &v| {
        (lo.min(at(v)), hi.max(at(v)))
    });
    let centre = 0.5 * (lo + hi);
    // The bits of a float ≥ 0 order as it does.
    let mut ranked: Vec<(u32, u32)> = (samples.iter())
        .map(|&v| (at(v).distance_squared(centre).to_bits(), v))
        .collect();
    ranked.sort_unstable();
    ranked.into_iter().map(|(_, v)| v).collect()
}

/// A sample's x–y as delaunator takes it.
fn xy(p: &Vec3) -> Point {
    Point {
        x: p.x as f64,
        y: p.y as f64,
    }
}

/// Makes each corner of `triangles` the least of the samples that share its x–y
/// (delaunator holds one of them, which one depending on the order it met them).
fn held_by_least_twins(points: &[Vec3], triangles: &mut [[u32; 3]]) {
    let unheld = Unheld::of(points, triangles, xy_key);
    if unheld.is_empty() {
        return;
    }
    let least_twin = |v: &mut u32| {
        if let Some(twin) = unheld.twin(xy_key(points[*v as usize])) {
            *v = (*v).min(twin);
        }
    };
    // Triangle by triangle, as `Unheld::of` walks them.
    (triangles.par_iter_mut()).for_each(|t| t.iter_mut().for_each(least_twin));
}

/// A sample's x–y as one key, equal for equal coordinates (adding +0 makes −0 +0).
fn xy_key(p: Vec3) -> u64 {
    edge_key((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits())
}

/// A directed edge (a, b) as one sortable key.
fn edge_key(a: u32, b: u32) -> u64 {
    ((a as u64) << 32) | b as u64
}

/// The ends of an edge's key.
fn ends(key: u64) -> (u32, u32) {
    ((key >> 32) as u32, key as u32)
}

/// Twice the x–y area of triangle `t`, in f64.
fn doubled_area(points: &[Vec3], t: &[u32; 3]) -> f64 {
    doubled_area_xy(t.map(|v| points[v as usize].truncate().as_dvec2()))
}

/// Twice the area of the triangle of corners `[a, b, c]`.
fn doubled_area_xy([a, b, c]: [DVec2; 3]) -> f64 {
    (b - a).perp_dot(c - a).abs()
}

/// Twice the x–y area of `triangles`, in f64.
fn doubled_areas(points: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    (triangles.par_iter())
        .map(|t| doubled_area(points, t))
        .sum::<f64>()
}

/// Whether two sums of areas agree to rounding.
fn same_area(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::Rng;

    /// Each triangle turned to start at its least corner, sorted.
    pub fn canonical(triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        let mut out: Vec<[u32; 3]> = (triangles.iter())
            .map(|t| {
                let k = (0..3).min_by_key(|&k| t[k]).unwrap();
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// `n` samples uniform over 100 × 60.
    pub fn scattered(n: usize, seed: u8) -> Vec<Vec3> {
        let mut rng = proptest::test_runner::TestRng::from_seed(
            proptest::test_runner::RngAlgorithm::ChaCha,
            &[seed; 32],
        );
        (0..n)
            .map(|_| Vec3::new(rng.random::<f32>() * 100.0, rng.random::<f32>() * 60.0, 0.0))
            .collect()
    }

    #[test]
    fn the_swept_order_changes_no_triangle() {
        // Random samples (no four on a circle): the same triangles as delaunator's of
        // the samples in their own order.
        for seed in 1..4 {
            let points = scattered(5000, seed);
            let at: Vec<Point> = points.iter().map(xy).collect();
            let plain: Vec<[u32; 3]> = (delaunator::triangulate(&at).triangles.chunks_exact(3))
                .map(|t| [t[0], t[1], t[2]].map(|k| k as u32))
                .collect();
            let order = swept(&points, &(0..5000).collect::<Vec<u32>>());
            assert_ne!(order, (0..5000).collect::<Vec<u32>>());
            assert_eq!(canonical(&whole(&points)), canonical(&plain), "{seed}");
        }
    }

    #[test]
    fn the_least_of_twins_holds_their_corners() {
        // Every sample doubled, the copy first or last: the triangulation holds the
        // lesser index of each pair, whichever delaunator met first.
        let points = scattered(300, 5);
        let mut doubled = points.clone();
        doubled.extend(points.iter().map(|p| *p + Vec3::Z));
        let triangles = delaunay_xy(&doubled);
        assert!(
            triangles
                .iter()
                .flatten()
                .all(|&v| (v as usize) < points.len())
        );
        assert_eq!(canonical(&triangles), canonical(&whole(&points)));
    }
}
