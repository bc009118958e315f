//! Roofs that stand free: a building-class object (ASPRS 6) that no sample shows a
//! wall under, such as a carport's roof on its posts.
//!
//! A TIN joins a roof's outline to the street below it with a wall, and a wall is
//! what a building has. The scanner sees part of a building's walls (the sides that
//! face a strip, at the scan angle there) or its pitched roof: samples well below its
//! top. An object whose every sample lies within [`BAND_SPACINGS`] of its top shows
//! none: where the pulses passed its edges they reached the ground under them, or no
//! pulse looked at its sides. No sample says a wall is there, so it gets none: it is
//! drawn as a bridge deck is ([`super::layers`]), a TIN of its own, the ground's TIN
//! running on under it.
//!
//! The objects are the connected sets of building samples, two joined where they lie
//! within [`JOIN_SPACINGS`] of each other in x–y. Lengths count in s, the median over
//! the building samples of the horizontal distance to their [`K`]−1-th nearest other
//! (0.53 m on the simulated scan, whose pulses are 0.5 m apart: a roof's nearest
//! neighbours in x–y lie a fraction of that apart where two strips overlap, and a
//! wall's samples stand nearly on one x–y).

use std::num::NonZero;

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Neighbours looked at to join a sample to its object.
const K: usize = 9;

/// Two building samples this many spacings apart or less (in x–y) belong to one
/// object: a roof sampled on a square grid joins across a missed pulse; two buildings
/// a street apart stay apart.
pub const JOIN_SPACINGS: f32 = 2.5;

/// Depth under an object's top, in spacings, beyond which a sample shows a wall (or a
/// pitched roof): 1 m at the simulated scan's 0.5 m, over ten times its range noise.
pub const BAND_SPACINGS: f32 = 2.0;

/// Whether each of `which` (indices into `points`, building samples) belongs to an
/// object that stands free (the module doc).
pub fn free_standing(points: &[Vec3], which: &[u32]) -> Vec<bool> {
    let xy: Vec<[f32; 2]> = which.iter().map(|&i| points[i as usize].truncate().into()).collect();
    let Ok(tree) = ImmutableKdTree::<f32, 2>::new_from_slice(&xy) else {
        return vec![false; which.len()];
    };
    let n = NonZero::new(K.min(xy.len())).unwrap_or(NonZero::<usize>::MIN);
    let near: Vec<Vec<(u32, f32)>> = xy
        .par_iter()
        .map(|q| {
            let found = tree.query(q).nearest_n::<SquaredEuclidean<f32>>(n).execute();
            found.iter().map(|f| (f.item as u32, f.distance.sqrt())).collect()
        })
        .collect();
    let Some(spacing) = median_farthest(&near) else {
        return vec![false; which.len()];
    };
    let object = objects(&near, JOIN_SPACINGS * spacing);
    let mut top = vec![f32::NEG_INFINITY; which.len()];
    for (k, &i) in which.iter().enumerate() {
        top[object[k]] = top[object[k]].max(points[i as usize].z);
    }
    let mut walled = vec![false; which.len()];
    for (k, &i) in which.iter().enumerate() {
        walled[object[k]] |= points[i as usize].z < top[object[k]] - BAND_SPACINGS * spacing;
    }
    (0..which.len()).map(|k| !walled[object[k]]).collect()
}

/// The median over the samples of the distance to the farthest of their `near` ones;
/// None where there are none.
fn median_farthest(near: &[Vec<(u32, f32)>]) -> Option<f32> {
    let mut nearest: Vec<f32> = near
        .iter()
        .filter_map(|found| found.last().map(|f| f.1))
        .collect();
    let mid = nearest.len() / 2;
    (!nearest.is_empty()).then(|| *nearest.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// Each sample's object, named by one of its samples: the connected sets of the graph
/// that joins each sample to those of its `near` ones within `reach`.
fn objects(near: &[Vec<(u32, f32)>], reach: f32) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..near.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    for (k, found) in near.iter().enumerate() {
        for &(j, _) in found.iter().filter(|f| f.1 <= reach) {
            let (a, b) = (root(&mut parent, k), root(&mut parent, j as usize));
            parent[a.max(b)] = a.min(b);
        }
    }
    (0..near.len()).map(|k| root(&mut parent, k)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of `n`×`n` samples 0.5 apart from `(x, y)`, at height `z(i, j)`.
    fn roof(x: f32, y: f32, n: usize, z: impl Fn(usize, usize) -> f32) -> Vec<Vec3> {
        let at = |i: usize, j: usize| Vec3::new(x + i as f32 * 0.5, y + j as f32 * 0.5, z(i, j));
        (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| at(i, j)).collect()
    }

    #[test]
    fn a_flat_roof_stands_free_and_one_with_a_sampled_wall_does_not() {
        let carport = roof(0.0, 0.0, 12, |_, _| 2.6);
        // A building 10 m away: its west column of samples lies down its wall.
        let house = roof(16.0, 0.0, 12, |i, j| if i == 0 { 1.0 + j as f32 * 0.1 } else { 6.0 });
        let points: Vec<Vec3> = carport.iter().chain(&house).copied().collect();
        let which: Vec<u32> = (0..points.len() as u32).collect();
        let free = free_standing(&points, &which);
        assert!(free[..carport.len()].iter().all(|&f| f), "the carport stands free");
        assert!(free[carport.len()..].iter().all(|&f| !f), "the house is walled");
    }

    #[test]
    fn a_roof_a_gap_wider_than_the_join_apart_is_its_own_object() {
        // Two flat roofs 2 m apart (4 spacings), the second with a sample 3 m down.
        let a = roof(0.0, 0.0, 6, |_, _| 5.0);
        let b = roof(4.5, 0.0, 6, |i, j| if (i, j) == (0, 0) { 2.0 } else { 5.0 });
        let points: Vec<Vec3> = a.iter().chain(&b).copied().collect();
        let which: Vec<u32> = (0..points.len() as u32).collect();
        let free = free_standing(&points, &which);
        assert!(free[..a.len()].iter().all(|&f| f));
        assert!(free[a.len()..].iter().all(|&f| !f));
    }
}
