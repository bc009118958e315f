//! A mesh's isolated vertices: those no triangle holds (a zippered scan such as the
//! Stanford bunny leaves about 3 % of its vertices so, where overlapping scans were
//! merged). The mesh's surface is its triangles; such a vertex is drawn only where it
//! adds surface that the triangles lack.
//!
//! An isolated vertex p is *redundant* when a vertex q that a triangle holds has p in
//! reach of its splat, |p − q| ≤ r(q) (r the major semi-axis): the triangles' splats
//! already draw its place, and its own disk, whose normal comes from a handful of
//! neighbours, could only stick out of that surface (on the bunny's base, a disk of a
//! few radii past the silhouette). Redundant vertices stay in [`super::LeafSurfels`]
//! (the mesh keeps its indices) and are left out of the tree; the others keep the disk
//! their neighbours give them, as a cloud's points do.

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZero;

use super::Surfel;

/// Held vertices searched around each isolated one: the nearest need not be the one
/// whose splat reaches farthest.
const CANDIDATES: usize = 8;

/// The vertices of `isolated` (ascending) that lie within reach of a held vertex's
/// splat (see the module doc); `points` unit-scaled by `scale` for the search.
pub fn redundant(points: &[Vec3], scale: f32, isolated: &[u32], surfels: &[Surfel]) -> Vec<u32> {
    if isolated.is_empty() {
        return Vec::new();
    }
    let held: Vec<u32> = (0..points.len() as u32)
        .into_par_iter()
        .filter(|v| isolated.binary_search(v).is_err())
        .collect();
    let coords: Vec<[f32; 3]> = held
        .iter()
        .map(|&v| (points[v as usize] * scale).to_array())
        .collect();
    let Ok(tree) = ImmutableKdTree::<f32, 3>::new_from_slice(&coords) else {
        return Vec::new();
    };
    let k = NonZero::new(CANDIDATES.min(coords.len())).unwrap_or(NonZero::<usize>::MIN);
    isolated
        .par_iter()
        .copied()
        .filter(|&v| {
            let p = points[v as usize] * scale;
            let found = tree
                .query(&p.to_array())
                .nearest_n::<SquaredEuclidean<f32>>(k)
                .execute();
            found.iter().any(|f| {
                let r = surfels[held[f.item as usize] as usize].radius * scale;
                f.distance <= r * r
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;

    /// Held vertices on a unit grid with radius 0.75; an isolated vertex inside a cell
    /// is redundant, one two cells beyond the grid is not.
    #[test]
    fn only_isolated_vertices_within_a_splat_are_redundant() {
        let mut points: Vec<Vec3> = (0..16)
            .map(|i| Vec3::new((i % 4) as f32, (i / 4) as f32, 0.0))
            .collect();
        points.push(Vec3::new(1.4, 1.6, 0.1));
        points.push(Vec3::new(5.0, 1.0, 0.0));
        let surfels: Vec<Surfel> = points
            .iter()
            .map(|&position| Surfel {
                position,
                radius: 0.75,
                ..Surfel::zeroed()
            })
            .collect();
        assert_eq!(redundant(&points, 0.25, &[16, 17], &surfels), vec![16]);
        assert!(redundant(&points, 0.25, &[], &surfels).is_empty());
    }
}
