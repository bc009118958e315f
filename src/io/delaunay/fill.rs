//! The triangles of a small triangulation that fill a region: where the triangles that
//! stay Delaunay in a larger set leave holes, the set's triangulation there is that of
//! the samples around and in the holes, cut to them.

use delaunator::{EMPTY, Point, next_halfedge};
use glam::Vec3;

use super::{edge_key, xy};

/// What a flood across `corners`' triangulation does at its hull.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum AtHull {
    /// The region lies inside the hull: reaching it means the border leaks.
    Fails,
    /// The region may reach the hull (it is the whole set's).
    Stops,
}

/// The triangles (indices into `points`) of the Delaunay triangulation of `corners`
/// that lie inside `border`, sorted directed edges each wound as a triangle inside
/// winds it: the triangles that hold a border edge, and those reached from them across
/// edges that are not border edges. None where a border edge is missing from that
/// triangulation while `at_hull` fails, or the flood reaches the hull where it fails.
pub fn fill(
    points: &[Vec3],
    corners: &[u32],
    border: &[u64],
    at_hull: AtHull,
) -> Option<Vec<[u32; 3]>> {
    let at: Vec<Point> = corners.iter().map(|&v| xy(&points[v as usize])).collect();
    let dt = delaunator::triangulate(&at);
    let corner = |h: usize| corners[dt.triangles[h]];
    let is_border = |h: usize| {
        let side = edge_key(corner(h), corner(next_halfedge(h)));
        border.binary_search(&side).is_ok()
    };
    let mut inside = vec![false; dt.triangles.len() / 3];
    let mut flood = Vec::new();
    let mut found = 0;
    for h in (0..dt.triangles.len()).filter(|&h| is_border(h)) {
        found += 1;
        if !std::mem::replace(&mut inside[h / 3], true) {
            flood.push(h / 3);
        }
    }
    if found != border.len() && at_hull == AtHull::Fails {
        return None;
    }
    while let Some(t) = flood.pop() {
        for h in (3 * t..3 * t + 3).filter(|&h| !is_border(h)) {
            let across = dt.halfedges[h];
            if across == EMPTY {
                if at_hull == AtHull::Fails {
                    return None;
                }
                continue;
            }
            if !std::mem::replace(&mut inside[across / 3], true) {
                flood.push(across / 3);
            }
        }
    }
    let filled = (0..inside.len()).filter(|&t| inside[t]);
    Some(
        filled
            .map(|t| [0, 1, 2].map(|k| corner(3 * t + k)))
            .collect(),
    )
}
