//! A large set's Delaunay triangulation in vertical strips of equal counts, each strip
//! triangulated alone, on all cores.
//!
//! A strip's triangle whose circumcircle lies strictly within the strip's x range (from
//! the cut before it to the cut after it) holds no other strip's sample, so it is a
//! triangle of the whole's triangulation: kept, and that is nearly all of them. The
//! rest lie along the cuts and the hulls. The whole's triangles that fill what the kept
//! ones leave have as corners the corners of the rest and the strips' hull samples (a
//! sample inside its strip's hull whose triangles are all kept has its whole star kept,
//! and no new triangle reaches it). They are exactly the triangles of those samples'
//! own triangulation that lie outside the kept ones ([`super::fill`]), found by
//! flooding from the kept region's border out to the hull of the whole, which the
//! strips' hull samples span.
//!
//! The kept and the filled triangles must cover the whole's hull, no more and no less:
//! where they do not (a tie on a border, a strip whose samples lie on a line), None.

use delaunator::{EMPTY, next_halfedge};
use glam::{DVec2, Vec3};
use rayon::prelude::*;

use super::fill::{AtHull, fill};
use super::{doubled_area, doubled_area_xy, edge_key, same_area, swept, xy};
use crate::io::parallel;

/// One strip's share: its kept triangles, the border they leave (each edge wound as
/// the triangle beyond it winds it), and the samples of its triangles that were not
/// kept and of its hull.
struct Strip {
    kept: Vec<[u32; 3]>,
    border: Vec<u64>,
    loose: Vec<u32>,
    kept_area: f64,
}

/// The Delaunay triangulation of `positions` in x–y from `strips` strips (the module
/// doc); None where it cannot be told from them. Each strip's samples are told to
/// `triangulated` once it is triangulated.
pub fn in_strips(
    positions: &[Vec3],
    strips: usize,
    triangulated: &(dyn Fn(usize) + Sync),
) -> Option<Vec<[u32; 3]>> {
    let cuts = cuts(positions, strips);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); cuts.len() + 1];
    for (v, p) in positions.iter().enumerate() {
        members[cuts.partition_point(|&c| c <= p.x)].push(v as u32);
    }
    let range = |s: usize| {
        let lo = s
            .checked_sub(1)
            .map_or(f64::NEG_INFINITY, |k| cuts[k] as f64);
        (lo, cuts.get(s).map_or(f64::INFINITY, |&c| c as f64))
    };
    let parts: Option<Vec<Strip>> = (members.par_iter().enumerate())
        .map(|(s, members)| {
            let strip = strip(positions, members, range(s));
            triangulated(members.len());
            strip
        })
        .collect();
    let parts = parts?;
    drop(members);
    let mut loose: Vec<u32> = parts.iter().flat_map(|p| p.loose.iter().copied()).collect();
    loose.par_sort_unstable();
    loose.dedup();
    let mut border: Vec<u64> = parts
        .iter()
        .flat_map(|p| p.border.iter().copied())
        .collect();
    border.par_sort_unstable();
    let filled = fill(positions, &loose, &border, AtHull::Stops)?;
    let kept_area: f64 = parts.iter().map(|p| p.kept_area).sum();
    let filled_area: f64 = filled.iter().map(|t| doubled_area(positions, t)).sum();
    if !same_area(kept_area + filled_area, 2.0 * hull_area(positions, &loose)) {
        return None;
    }
    let mut pieces: Vec<Vec<[u32; 3]>> = parts.into_iter().map(|p| p.kept).collect();
    pieces.push(filled);
    Some(parallel::concat(&pieces))
}

/// The x values that cut `positions` into `strips` of about equal counts, ascending,
/// distinct, above the least x (no strip is empty): the x of ranks k n / `strips`
/// (k = 1, 2, …), each selected among the xs above the last rank's.
fn cuts(positions: &[Vec3], strips: usize) -> Vec<f32> {
    let mut xs: Vec<f32> = positions.par_iter().map(|p| p.x).collect();
    let Some(&least) = xs.iter().min_by(|a, b| a.total_cmp(b)) else {
        return Vec::new();
    };
    let (mut above, mut first) = (&mut xs[..], 0);
    let mut cuts = Vec::with_capacity(strips);
    for rank in (1..strips).map(|k| k * positions.len() / strips) {
        if rank < first {
            continue; // The last rank again (fewer samples than strips).
        }
        let (_, &mut cut, rest) = above.select_nth_unstable_by(rank - first, f32::total_cmp);
        cuts.push(cut);
        (above, first) = (rest, rank + 1);
    }
    cuts.retain(|&c| c > least);
    cuts.dedup();
    cuts
}

/// The triangulation of the strip of `members` between x = `lo` and `hi`
/// (the module doc); None where its samples make no triangle.
fn strip(positions: &[Vec3], members: &[u32], (lo, hi): (f64, f64)) -> Option<Strip> {
    let members = &swept(positions, members)[..];
    let at: Vec<_> = members
        .iter()
        .map(|&v| xy(&positions[v as usize]))
        .collect();
    let dt = delaunator::triangulate(&at);
    if dt.triangles.is_empty() {
        return None;
    }
    let corner = |h: usize| members[dt.triangles[h]];
    let corners = |t: usize| [0, 1, 2].map(|k| corner(3 * t + k));
    // A triangle's corners in x–y, read from delaunator's input (the strip's own
    // samples, together in memory) rather than from all the positions.
    let corners_xy = |t: usize| {
        [0, 1, 2].map(|k| {
            let p = &at[dt.triangles[3 * t + k]];
            DVec2::new(p.x, p.y)
        })
    };
    let within = |t: usize| {
        let [a, b, c] = corners_xy(t);
        circumcircle(a, b, c).is_some_and(|(centre, r)| {
            let margin = 1e-6 * (r + centre.x.abs());
            centre.x - r > lo + margin && centre.x + r < hi - margin
        })
    };
    let kept_flags: Vec<bool> = (0..dt.triangles.len() / 3).map(within).collect();
    let (mut kept, mut border, mut loose) = (Vec::new(), Vec::new(), Vec::new());
    let mut kept_area = 0.0;
    for t in 0..kept_flags.len() {
        if !kept_flags[t] {
            loose.extend(corners(t));
            continue;
        }
        kept.push(corners(t));
        kept_area += doubled_area_xy(corners_xy(t));
        for h in 3 * t..3 * t + 3 {
            let across = dt.halfedges[h];
            if across == EMPTY || !kept_flags[across / 3] {
                border.push(edge_key(corner(next_halfedge(h)), corner(h)));
            }
        }
    }
    loose.extend(dt.hull.iter().map(|&k| members[k]));
    Some(Strip {
        kept,
        border,
        loose,
        kept_area,
    })
}

/// The centre and radius of the circle through `a`, `b` and `c`; None where they lie
/// on a line.
fn circumcircle(a: DVec2, b: DVec2, c: DVec2) -> Option<(DVec2, f64)> {
    let (b, c) = (b - a, c - a);
    let d = 2.0 * b.perp_dot(c);
    if d == 0.0 {
        return None;
    }
    let (bb, cc) = (b.length_squared(), c.length_squared());
    let u = DVec2::new(c.y * bb - b.y * cc, b.x * cc - c.x * bb) / d;
    Some((a + u, u.length()))
}

/// The area of the convex hull of the `samples` of `positions` (Andrew's monotone
/// chain).
fn hull_area(positions: &[Vec3], samples: &[u32]) -> f64 {
    let mut at: Vec<DVec2> = (samples.iter())
        .map(|&v| positions[v as usize].truncate().as_dvec2())
        .collect();
    at.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * at.len());
    for pass in [&at[..], &at.iter().rev().copied().collect::<Vec<_>>()[..]] {
        let start = hull.len();
        for &p in pass {
            while hull.len() >= start + 2 {
                let (o, a) = (hull[hull.len() - 2], hull[hull.len() - 1]);
                if (a - o).perp_dot(p - o) > 0.0 {
                    break;
                }
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    let shoelace: f64 = (0..hull.len())
        .map(|k| hull[k].perp_dot(hull[(k + 1) % hull.len()]))
        .sum();
    0.5 * shoelace.abs()
}

#[cfg(test)]
mod tests {
    use super::super::tests::{canonical, scattered};
    use super::super::whole;
    use super::*;

    #[test]
    fn strips_give_the_whole_s_triangulation() {
        // Random samples triangulated in 2, 5 and 16 strips: the same triangles as
        // delaunator's triangulation of the whole.
        for seed in 1..3 {
            let points = scattered(6000, seed);
            for strips in [2, 5, 16] {
                let triangles =
                    in_strips(&points, strips, &|_| {}).expect("no ties in random samples");
                assert_eq!(
                    canonical(&triangles),
                    canonical(&whole(&points)),
                    "{strips}"
                );
            }
        }
    }

    #[test]
    fn the_cuts_are_the_sorted_xs_at_their_ranks() {
        // Whole xs (many ties) and fewer samples than strips too.
        for (n, strips) in [(6000, 16), (1000, 7), (5, 16)] {
            let points: Vec<Vec3> = (scattered(n, 4).iter())
                .map(|p| Vec3::new(p.x.round(), p.y, 0.0))
                .collect();
            let mut xs: Vec<f32> = points.iter().map(|p| p.x).collect();
            xs.sort_by(f32::total_cmp);
            let mut expected: Vec<f32> = (1..strips)
                .map(|k| xs[k * n / strips])
                .filter(|&c| c > xs[0])
                .collect();
            expected.dedup();
            assert_eq!(
                cuts(&points, strips),
                expected,
                "{n} samples, {strips} strips"
            );
        }
    }

    #[test]
    fn a_strip_on_a_line_asks_for_the_whole() {
        // Samples on one vertical line per strip: no strip makes a triangle.
        let points: Vec<Vec3> = (0..400)
            .map(|k| Vec3::new((k / 100) as f32, (k % 100) as f32, 0.0))
            .collect();
        assert!(in_strips(&points, 4, &|_| {}).is_none());
    }

    #[test]
    fn the_hull_area_is_the_square_s() {
        let mut points = scattered(500, 3);
        points.extend([0.0, 100.0].map(|x| Vec3::new(x, 0.0, 0.0)));
        points.extend([0.0, 100.0].map(|x| Vec3::new(x, 60.0, 0.0)));
        let all: Vec<u32> = (0..points.len() as u32).collect();
        assert!((hull_area(&points, &all) - 6000.0).abs() < 1e-9);
    }
}
