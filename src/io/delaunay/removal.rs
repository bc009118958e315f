//! The Delaunay triangulation (in x–y) of a sample set less some of its samples, made
//! from the triangulation of the whole: a terrain's ground is triangulated once for
//! `surfel::free_roofs`, which takes the slabs and lone returns out of it, and the
//! TIN that draws what is left is this one, not a second triangulation of the rest.
//!
//! Taking samples out keeps every triangle that none of them is a corner of: its
//! circumcircle held no sample before, and holds none of fewer. The triangles that
//! have a removed corner make cavities (a removed sample's star is closed where it is
//! not on the hull), and the new triangles fill them. Their corners are the kept
//! samples in the cavities: the kept corners B of the cavities' triangles (on their
//! borders, and inside them where a kept sample had only removed ones around). Each
//! new triangle is Delaunay among all the kept samples, hence among B alone; and the
//! new triangles tile the cavities, so they are exactly the triangles of B's own
//! triangulation that lie inside them. Those are found from the border edges, each an
//! edge of B's triangulation wound as the cavity's triangle wound it (delaunator winds
//! every triangle the same way), by flooding across every edge that is not a border.
//! B is a few samples around each cavity, so this costs a fraction of a new
//! triangulation ([`super::fill`]).
//!
//! Under ties (four samples on one circle) B's triangulation may pick another diagonal
//! than the whole's did, so that a border edge is missing from it: then, and where a
//! removed sample lies on the hull, or a sample the first triangulation skipped as a
//! duplicate shares a removed one's x–y, [`without`] gives None and the caller
//! triangulates anew.

use glam::Vec3;
use rayon::prelude::*;

use super::fill::{AtHull, fill};
use super::{doubled_areas, edge_key, ends, same_area, xy_key};

/// The Delaunay triangulation of the `points` that `removed` does not mark, from
/// `triangles`, the triangulation of all of them as delaunator made it (indices into
/// `points`, long triangles not dropped): the triangles without a removed corner in
/// their order, then the cavities' new ones. None where the module doc says.
pub fn without(
    points: &[Vec3],
    mut triangles: Vec<[u32; 3]>,
    removed: &[bool],
) -> Option<Vec<[u32; 3]>> {
    let has_removed = |t: &[u32; 3]| t.iter().any(|&v| removed[v as usize]);
    let cavities: Vec<[u32; 3]> = (triangles.par_iter())
        .filter(|t| has_removed(t))
        .copied()
        .collect();
    if cavities.is_empty() {
        return Some(triangles);
    }
    if skipped_twin_of_removed(points, &triangles, removed) {
        return None;
    }
    triangles.retain(|t| !has_removed(t));
    let border = cavity_borders(&cavities, removed)?;
    let mut corners: Vec<u32> = (cavities.iter().flatten())
        .filter(|&&v| !removed[v as usize])
        .copied()
        .collect();
    corners.par_sort_unstable();
    corners.dedup();
    let filled = fill(points, &corners, &border, AtHull::Fails)?;
    if !same_area(
        doubled_areas(points, &cavities),
        doubled_areas(points, &filled),
    ) {
        return None;
    }
    triangles.extend(filled);
    Some(triangles)
}

/// The cavities' border edges, sorted, each wound as its cavity triangle winds it;
/// None where a removed sample lies on the hull (an edge from it that no other
/// triangle shares).
fn cavity_borders(cavities: &[[u32; 3]], removed: &[bool]) -> Option<Vec<u64>> {
    let mut sides: Vec<u64> = (cavities.iter())
        .flat_map(|t| (0..3).map(move |k| edge_key(t[k], t[(k + 1) % 3])))
        .collect();
    sides.par_sort_unstable();
    let mut border = Vec::new();
    for &side in &sides {
        let (a, b) = ends(side);
        if sides.binary_search(&edge_key(b, a)).is_ok() {
            continue;
        }
        if removed[a as usize] || removed[b as usize] {
            return None;
        }
        border.push(side);
    }
    Some(border)
}

/// Whether a kept sample that `triangles` leaves out (delaunator keeps one of the
/// samples that share an x–y) shares its x–y with a removed one: the triangulation of
/// the rest would hold it.
fn skipped_twin_of_removed(points: &[Vec3], triangles: &[[u32; 3]], removed: &[bool]) -> bool {
    let mut held = vec![false; points.len()];
    for &v in triangles.iter().flatten() {
        held[v as usize] = true;
    }
    let xy = |v: usize| xy_key(points[v]);
    let mut removed_xy: Vec<u64> = (0..points.len()).filter(|&v| removed[v]).map(xy).collect();
    removed_xy.sort_unstable();
    (0..points.len())
        .filter(|&v| !held[v] && !removed[v])
        .any(|v| removed_xy.binary_search(&xy(v)).is_ok())
}

#[cfg(test)]
mod tests {
    use super::super::tests::{canonical, scattered};
    use super::super::{delaunay_xy, edge_key};
    use super::*;

    #[test]
    fn removing_samples_gives_the_triangulation_of_the_rest() {
        // Random samples, a scattered tenth and a 20 × 15 block taken out but for a
        // few samples, which only removed ones surrounded: the repaired triangulation
        // (renumbered) has the same triangles, wound the same, as delaunator's
        // triangulation of what is left.
        for seed in 1..4 {
            let points = scattered(4000, seed);
            let in_block = |p: &Vec3| p.x > 40.0 && p.x < 60.0 && p.y > 20.0 && p.y < 35.0;
            let removed: Vec<bool> = (points.iter().enumerate())
                .map(|(k, p)| k % 10 == 3 || (in_block(p) && k % 9 != 0))
                .collect();
            let whole = delaunay_xy(&points);
            let hull: Vec<bool> = hull_of(&whole, points.len());
            let removed: Vec<bool> = (0..points.len()).map(|k| removed[k] && !hull[k]).collect();
            let repaired = without(&points, whole, &removed).expect("no ties in random samples");
            let renumber = renumbering(&removed);
            let rest: Vec<Vec3> = (0..points.len())
                .filter(|&k| !removed[k])
                .map(|k| points[k])
                .collect();
            let repaired: Vec<[u32; 3]> = (repaired.iter())
                .map(|t| t.map(|v| renumber[v as usize]))
                .collect();
            assert_eq!(
                canonical(&repaired),
                canonical(&delaunay_xy(&rest)),
                "seed {seed}"
            );
        }
    }

    #[test]
    fn a_removed_hull_sample_asks_for_a_new_triangulation() {
        let points = scattered(500, 7);
        let whole = delaunay_xy(&points);
        let hull = hull_of(&whole, points.len());
        let on_hull = hull.iter().position(|&h| h).unwrap();
        let removed: Vec<bool> = (0..points.len()).map(|k| k == on_hull).collect();
        assert!(without(&points, whole, &removed).is_none());
    }

    #[test]
    fn a_kept_twin_of_a_removed_sample_asks_for_a_new_triangulation() {
        // Sample 0 doubled: delaunator holds one of the two. Removing the held one
        // would leave the other, which the first triangulation never joined.
        let mut points = scattered(500, 9);
        points.push(points[0] + Vec3::Z);
        let whole = delaunay_xy(&points);
        let held = |v: u32| whole.iter().flatten().any(|&w| w == v);
        let last = points.len() as u32 - 1;
        let twin = if held(0) { 0 } else { last };
        assert!(!(held(0) && held(last)));
        let removed: Vec<bool> = (0..points.len() as u32).map(|k| k == twin).collect();
        assert!(without(&points, whole, &removed).is_none());
    }

    /// Whether each sample lies on the triangulation's hull (an edge of one triangle).
    fn hull_of(triangles: &[[u32; 3]], n: usize) -> Vec<bool> {
        let mut sides: Vec<u64> = (triangles.iter())
            .flat_map(|t| (0..3).map(move |k| edge_key(t[k], t[(k + 1) % 3])))
            .collect();
        sides.sort_unstable();
        let mut hull = vec![false; n];
        for &s in &sides {
            let (a, b) = ends(s);
            if sides.binary_search(&edge_key(b, a)).is_err() {
                (hull[a as usize], hull[b as usize]) = (true, true);
            }
        }
        hull
    }

    /// Each kept sample's index among the kept.
    fn renumbering(removed: &[bool]) -> Vec<u32> {
        let mut next = 0;
        (removed.iter())
            .map(|&r| {
                let k = next;
                next += !r as u32;
                k
            })
            .collect()
    }
}
