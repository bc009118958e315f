//! The k nearest neighbours of a cloud's samples, among its distinct positions, from a
//! uniform grid over them ([`Cells`]).

use std::num::NonZero;

use glam::Vec3;
use rayon::prelude::*;

use super::K;
use super::cells::Cells;
use crate::surfel::progress::Progress;

/// The distinct positions of a cloud, unit-scaled and sorted by cell, and the grid
/// its neighbourhoods are searched in.
pub(super) struct Search {
    pub coords: Vec<[f32; 3]>,
    cells: Cells,
    /// [`K`], or fewer when the cloud has fewer distinct positions.
    k: NonZero<usize>,
}

/// A position's sort key: its coordinates' bits, −0 counted as +0.
fn position_key(c: &[f32; 3]) -> [u32; 3] {
    c.map(|x| if x == 0.0 { 0 } else { x.to_bits() })
}

impl Search {
    /// The distinct positions among `points`, scaled by `scale`. Searching among
    /// distinct positions keeps each neighbourhood's size however many samples
    /// coincide (10⁵ copies of one point would otherwise fill one cell), and coinciding
    /// samples add nothing to a neighbourhood's shape.
    pub fn new(points: &[Vec3], scale: f32) -> Search {
        // Scaled coordinates stay within ±2⁶⁰ (`super::unit_scale`): squared distances fit f32.
        let scaled: Vec<[f32; 3]> = points.par_iter().map(|p| (*p * scale).to_array()).collect();
        let mut cells = Cells::over(&scaled);
        let mut keyed: Vec<(u64, [u32; 3], [f32; 3])> = (scaled.into_par_iter())
            .map(|c| (cells.key(Vec3::from(c)), position_key(&c), c))
            .collect();
        keyed.par_sort_unstable_by_key(|&(cell, position, _)| (cell, position));
        keyed.dedup_by_key(|&mut (cell, position, _)| (cell, position));
        let keys: Vec<u64> = keyed.par_iter().map(|k| k.0).collect();
        cells.index(&keys);
        let coords: Vec<[f32; 3]> = keyed.par_iter().map(|k| k.2).collect();
        let k = NonZero::new(K.min(coords.len())).unwrap_or(NonZero::<usize>::MIN);
        Search { coords, cells, k }
    }

    /// Whether the cloud has no position to search.
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// The index among the distinct positions of the scaled position `p`.
    pub fn index_of(&self, p: Vec3) -> Option<u32> {
        let key = position_key(&p.to_array());
        let members = self.cells.members(p);
        let start = members.start;
        let found = self.coords[members]
            .iter()
            .position(|c| position_key(c) == key);
        found.map(|i| (start + i) as u32)
    }

    pub fn point(&self, i: u32) -> Vec3 {
        Vec3::from(self.coords[i as usize])
    }

    /// `f` of each of `queries` and its neighbourhood (nearest first), in the queries'
    /// order: written in place, block by block ([`query_block`]), each block's queries
    /// told to `progress` when done. Collecting the
    /// blocks' results instead copies them once more: on the Lucy-size cloud, peak
    /// memory 0.25 GiB higher.
    pub fn map_neighbourhoods<Q: Sync, T: Send + Default>(
        &self,
        queries: &[Q],
        position: &(dyn Fn(&Q) -> Vec3 + Sync),
        f: &(dyn Fn(&Q, &[u32]) -> T + Sync),
        progress: Progress,
    ) -> Vec<T> {
        let mut out: Vec<T> = Vec::with_capacity(queries.len());
        out.par_extend((0..queries.len()).into_par_iter().map(|_| T::default()));
        if self.is_empty() {
            return out;
        }
        // One block per job: split adaptively, one of two threads ran its last share
        // alone for 0.5 s on the Lucy-size cloud while the other one waited.
        let block = query_block(queries.len());
        (out.par_chunks_mut(block).zip(queries.par_chunks(block)))
            .with_max_len(1)
            .for_each(|(slots, block)| {
                let positions: Vec<Vec3> = block.iter().map(position).collect();
                let found = self.cells.nearest(&self.coords, self.k, &positions);
                for ((slot, q), found) in slots.iter_mut().zip(block).zip(found) {
                    *slot = f(q, &found);
                }
                progress.done(block.len());
            });
        out
    }
}

/// How many of `count` queries are answered together, in one block: the queries of one
/// cell within a block share its candidates, gathered once. Consecutive samples of a
/// scan's or a generator's order lie near each other, so a block's queries fall in few
/// cells, and the larger the block, the fewer cells it splits with its neighbours. A
/// block is at most [`MAX_QUERY_BLOCK`], and small enough that each thread gets 32
/// (down to [`MIN_QUERY_BLOCK`]). On the Lucy-size cloud, on 2 cores, the surfels took
/// 13.9–14.9 s in blocks of 2,048, 13.4–13.7 s of 8,192 and 13.2–13.3 s of 32,768
/// (2026-11-29, alternated).
fn query_block(count: usize) -> usize {
    (count / (32 * rayon::current_num_threads())).clamp(MIN_QUERY_BLOCK, MAX_QUERY_BLOCK)
}

/// Most queries in a block ([`query_block`]).
const MAX_QUERY_BLOCK: usize = 32_768;
/// Fewest queries in a block, where there are as many.
const MIN_QUERY_BLOCK: usize = 2048;

#[cfg(test)]
mod tests {
    use super::*;
    use arrayvec::ArrayVec;
    use kiddo::{ImmutableKdTree, SquaredEuclidean};

    #[test]
    fn the_grid_finds_the_k_d_tree_s_neighbourhoods() {
        // A wavy sheet on a jittered grid (proptest's seeded generator) with a few
        // stray samples far off it, queried in its own order and in a shuffled one.
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let mut next = || rng.random::<f32>();
        let mut points: Vec<Vec3> = (0..4096)
            .map(|i| {
                let (x, y) = ((i % 64) as f32 + next(), (i / 64) as f32 + next());
                Vec3::new(x / 64.0, y / 64.0, 0.05 * (x * 0.3).sin() * (y * 0.2).cos())
            })
            .collect();
        points.extend([
            Vec3::splat(3.0),
            Vec3::new(-5.0, 0.5, 0.0),
            Vec3::new(0.5, 0.5, 9.0),
            // Beyond the grid's 2²¹ cells along an axis: searched apart.
            Vec3::new(4.0e6, 0.5, 0.0),
            Vec3::new(0.5, 3.0e6, 1.0),
        ]);
        let search = Search::new(&points, 1.0);
        let tree = ImmutableKdTree::<f32, 3>::new_from_slice(&search.coords).unwrap();
        let k = NonZero::new(K).unwrap();
        let distances = |p: Vec3, found: &[u32]| -> Vec<f32> {
            found.iter().map(|&f| p.distance(search.point(f))).collect()
        };
        let shuffled: Vec<Vec3> = (0..points.len())
            .map(|i| points[i * 1237 % points.len()])
            .collect();
        for queries in [&points, &shuffled] {
            let found = search.map_neighbourhoods(
                queries,
                &|p| *p,
                &|p, found| (*p, ArrayVec::<u32, K>::try_from(found).unwrap()),
                Progress::NONE,
            );
            for (p, found) in &found {
                let all = tree
                    .query(&p.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                let plain: Vec<u32> = all.iter().map(|f| f.item).collect();
                assert_eq!(distances(*p, found), distances(*p, &plain), "at {p}");
                assert_eq!(search.point(found[0]), *p);
            }
        }
        for (i, p) in search.coords.iter().enumerate() {
            assert_eq!(search.index_of(Vec3::from(*p)), Some(i as u32));
        }
    }
}
