//! The k nearest neighbours of a cloud's samples: a k-d tree (kiddo's) over its
//! distinct positions, searched in the samples' own order with each search bounded by
//! the last one's.

use std::num::NonZero;

use arrayvec::ArrayVec;
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::K;

/// The distinct positions of a cloud, unit-scaled and sorted by [`position_key`], and
/// the k-d tree its neighbourhoods are searched in.
pub(super) struct Search {
    pub coords: Vec<[f32; 3]>,
    /// `None` when no tree could be built: every disk is left to the fallbacks.
    pub tree: Option<ImmutableKdTree<f32, 3>>,
    /// [`K`], or fewer when the cloud has fewer distinct positions.
    k: NonZero<usize>,
}

/// A position's sort key: its coordinates' bits, −0 counted as +0.
fn position_key(c: &[f32; 3]) -> [u32; 3] {
    c.map(|x| if x == 0.0 { 0 } else { x.to_bits() })
}

impl Search {
    /// The distinct positions among `points`, scaled by `scale`. Searching among
    /// distinct positions keeps each query O(log n) however many samples coincide (10⁵
    /// copies of one point would otherwise make the search quadratic), and coinciding
    /// samples add nothing to a neighbourhood's shape.
    pub fn new(points: &[Vec3], scale: f32) -> Search {
        // Scaled coordinates stay within ±2⁶⁰ (`super::unit_scale`): squared distances fit f32.
        let mut coords: Vec<[f32; 3]> =
            points.par_iter().map(|p| (*p * scale).to_array()).collect();
        coords.par_sort_unstable_by_key(position_key);
        coords.dedup_by_key(|c| position_key(c));
        let tree = ImmutableKdTree::<f32, 3>::new_from_slice(&coords).ok();
        let k = NonZero::new(K.min(coords.len())).unwrap_or(NonZero::<usize>::MIN);
        Search { coords, tree, k }
    }

    /// The index among the distinct positions of the scaled position `p`.
    pub fn index_of(&self, p: Vec3) -> Option<u32> {
        let key = position_key(&p.to_array());
        let found = self.coords.binary_search_by_key(&key, position_key);
        found.ok().map(|i| i as u32)
    }

    pub fn point(&self, i: u32) -> Vec3 {
        Vec3::from(self.coords[i as usize])
    }

    /// The neighbourhoods of `queries` (nearest first), in blocks of [`QUERY_BLOCK`].
    pub fn neighbourhoods<'s, Q: Sync>(
        &'s self,
        queries: &'s [Q],
        position: &'s (dyn Fn(&Q) -> Vec3 + Sync),
    ) -> impl ParallelIterator<Item = (&'s Q, ArrayVec<u32, K>)> + 's {
        queries.par_chunks(QUERY_BLOCK).flat_map_iter(move |block| {
            let found = self
                .tree
                .as_ref()
                .map(|tree| nearest_in_order(tree, self.k, block.iter().map(position)));
            block.iter().zip(found.into_iter().flatten())
        })
    }
}

/// Queries walked in order, in blocks of this many: each block's first query searches
/// the whole tree, the others within the bound that their predecessor gives. Fixed
/// blocks keep the result independent of how rayon splits the work.
const QUERY_BLOCK: usize = 1024;

/// The k nearest positions' indices (nearest first) of each of `queries`, taken in
/// order. Consecutive queries of a scan's or a generator's order lie near each other:
/// by the triangle inequality the k-th neighbour of p lies within r + |p − q| of p,
/// where r is the k-th neighbour's distance from the previous query q, so each search
/// after the first prunes from its first step.
fn nearest_in_order<'t>(
    tree: &'t ImmutableKdTree<f32, 3>,
    k: NonZero<usize>,
    queries: impl Iterator<Item = Vec3> + 't,
) -> impl Iterator<Item = ArrayVec<u32, K>> + 't {
    let mut scratch = tree.create_scratch::<SquaredEuclidean<f32>>();
    let mut last: Option<(Vec3, f32)> = None;
    queries.map(move |p| {
        // The relative margin absorbs f32 rounding of the distances (unit-scaled model).
        let bound = last.map_or(f32::INFINITY, |(q, r)| (r + p.distance(q)) * (1.0 + 1e-5));
        let mut search = |bound: f32| {
            tree.query(&p.to_array())
                .nearest_n::<SquaredEuclidean<f32>>(k)
                .within(bound * bound)
                .with_scratch(&mut scratch)
                .execute()
        };
        let mut found = search(bound);
        if found.len() < k.get() {
            found = search(f32::INFINITY);
        }
        last = found.last().map(|f| (p, f.distance.sqrt()));
        found.iter().map(|f| f.item).take(K).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounded_queries_find_the_same_neighbourhoods_as_unbounded_ones() {
        // A wavy sheet on a jittered grid (proptest's seeded generator), queried in its
        // own order and in a shuffled one (far consecutive queries: loose bounds).
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let mut next = || rng.random::<f32>();
        let coords: Vec<[f32; 3]> = (0..4096)
            .map(|i| {
                let (x, y) = ((i % 64) as f32 + next(), (i / 64) as f32 + next());
                [x / 64.0, y / 64.0, 0.05 * (x * 0.3).sin() * (y * 0.2).cos()]
            })
            .collect();
        let tree = ImmutableKdTree::<f32, 3>::new_from_slice(&coords).unwrap();
        let k = NonZero::new(K).unwrap();
        let distances = |p: Vec3, found: &[u32]| -> Vec<f32> {
            found
                .iter()
                .map(|&f| p.distance(Vec3::from(coords[f as usize])))
                .collect()
        };
        let shuffled: Vec<usize> = (0..coords.len()).map(|i| i * 1237 % coords.len()).collect();
        for order in [(0..coords.len()).collect::<Vec<_>>(), shuffled] {
            let queries: Vec<Vec3> = order.iter().map(|&i| Vec3::from(coords[i])).collect();
            for (p, found) in
                queries
                    .iter()
                    .zip(nearest_in_order(&tree, k, queries.iter().copied()))
            {
                let all = tree
                    .query(&p.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                let plain: Vec<u32> = all.iter().map(|f| f.item).collect();
                assert_eq!(distances(*p, &found), distances(*p, &plain), "at {p}");
            }
        }
    }
}
