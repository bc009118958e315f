//! A uniform grid over a cloud's distinct positions, for its k-nearest-neighbour
//! queries.
//!
//! The positions are sorted by their cell's key (x, then y, then z), so a cell is a run
//! of them and the three cells (x, y, z − 1 … z + 1) are one. A query in cell (i, j, l)
//! takes its k nearest among the 3 × 3 × 3 cells around it: nine runs. That block holds
//! every position within the query's `margin` (its distance to the block's nearest
//! face, at least one cell edge), so the k found are the k nearest whenever the k-th
//! lies within the margin. Queries of one cell share their candidates, gathered once.
//! A query whose k-th lies further (a sparse region, a stray sample) is answered from
//! the 5 × 5 × 5 or 7 × 7 × 7 cells around it by the same test, and only beyond those
//! by a k-d tree over the same positions, built the first time one is needed.
//!
//! The edge is set so that the k-th neighbour usually lies within one edge
//! ([`cell_edge`]): a random eighth of the positions holds, within a given ball,
//! an eighth of the positions the whole set holds, whatever the sampling's dimension.

use std::num::NonZero;
use std::sync::OnceLock;

use arrayvec::ArrayVec;
use glam::{DVec3, Vec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::K;
use super::within::places_within;
use crate::surfel::{distance_rank, rank_parts};

/// Cells per axis: a cell index takes 21 bits, a key three of them.
const CELLS_PER_AXIS: i64 = 1 << 21;

/// The grid: its origin and edge, and the occupied cells.
pub(super) struct Cells {
    origin: DVec3,
    edge: f64,
    /// The occupied cells' keys, ascending.
    keys: Vec<u64>,
    /// Where each occupied cell's positions start in the sorted positions, then where
    /// those outside the grid start.
    starts: Vec<u32>,
    /// How many positions are sorted.
    count: usize,
    /// The fallback tree, over the same positions (`None` if it could not be built).
    tree: OnceLock<Option<ImmutableKdTree<f32, 3>>>,
}

/// A cell's integer coordinates.
type Cell = [i64; 3];

fn key_of(c: Cell) -> u64 {
    ((c[0] as u64) << 42) | ((c[1] as u64) << 21) | c[2] as u64
}

/// The cell of a key ([`key_of`]).
fn cell_of_key(key: u64) -> Cell {
    let axis = |shift: u32| ((key >> shift) & (CELLS_PER_AXIS as u64 - 1)) as i64;
    [axis(42), axis(21), axis(0)]
}

fn inside(c: Cell) -> bool {
    c.iter().all(|i| (0..CELLS_PER_AXIS).contains(i))
}

impl Cells {
    /// A grid of edge [`cell_edge`] over `coords`, its cells not yet recorded
    /// ([`Cells::index`]).
    pub fn over(coords: &[[f32; 3]]) -> Cells {
        let origin = (coords.par_iter())
            .map(|c| Vec3::from(*c).as_dvec3())
            .reduce(|| DVec3::splat(f64::INFINITY), DVec3::min);
        Cells {
            origin,
            edge: cell_edge(coords),
            keys: Vec::new(),
            starts: Vec::new(),
            count: 0,
            tree: OnceLock::new(),
        }
    }

    /// The key of the cell holding `p`; `u64::MAX` (after every cell) outside the
    /// grid's 2²¹ cells per axis.
    pub fn key(&self, p: Vec3) -> u64 {
        let cell = self.cell_of(p);
        if inside(cell) { key_of(cell) } else { u64::MAX }
    }

    /// Records the occupied cells from the sorted positions' `keys` (ascending): where
    /// each starts, found in parallel.
    pub fn index(&mut self, keys: &[u64]) {
        let first = |i: usize| keys[i] != u64::MAX && (i == 0 || keys[i - 1] != keys[i]);
        self.starts = (0..keys.len())
            .into_par_iter()
            .filter(|&i| first(i))
            .map(|i| i as u32)
            .collect();
        self.keys = self.starts.par_iter().map(|&i| keys[i as usize]).collect();
        let end = keys.partition_point(|&k| k != u64::MAX);
        self.starts.push(end as u32);
        self.count = keys.len();
    }

    /// The sorted positions that share the cell of `p` (those outside the grid, if it
    /// lies outside).
    pub fn members(&self, p: Vec3) -> std::ops::Range<usize> {
        match self.key(p) {
            u64::MAX => *self.starts.last().unwrap_or(&0) as usize..self.count,
            key => self.run(&mut 0, key, key),
        }
    }

    fn cell_of(&self, p: Vec3) -> Cell {
        let t = (p.as_dvec3() - self.origin) / self.edge;
        [t.x, t.y, t.z].map(|t| t.floor().clamp(-1.0, CELLS_PER_AXIS as f64) as i64)
    }

    /// The range of sorted positions whose cells' keys lie in `from..=to`, searched
    /// from `finger` (where the last search of this column began) and moving it.
    fn run(&self, finger: &mut usize, from: u64, to: u64) -> std::ops::Range<usize> {
        let a = first_at_least(&self.keys, finger, from);
        let mut end = a;
        let b = first_at_least(&self.keys, &mut end, to.saturating_add(1));
        self.starts[a] as usize..self.starts[b] as usize
    }

    /// The sorted positions' ranges of the cells within `reach` of `cell` ((2 reach + 1)³
    /// of them), one per column (x, y), each searched from its finger in `fingers` (one
    /// per column, (2 reach + 1)² of them).
    fn block<'a>(
        &'a self,
        (cell, reach): (Cell, i64),
        fingers: &'a mut [usize],
    ) -> impl Iterator<Item = std::ops::Range<usize>> + 'a {
        let last = CELLS_PER_AXIS - 1;
        let [i, j, l] = cell;
        let (l0, l1) = ((l - reach).max(0), (l + reach).min(last));
        let columns =
            (i - reach..=i + reach).flat_map(move |x| (j - reach..=j + reach).map(move |y| [x, y]));
        (columns.zip(fingers.iter_mut()))
            .filter(move |([x, y], _)| (0..=last).contains(x) && (0..=last).contains(y))
            .map(move |([x, y], finger)| self.run(finger, key_of([x, y, l0]), key_of([x, y, l1])))
    }

    /// The distance from `p` (in `cell`) to the faces of the block of the cells within
    /// `reach` of `cell`.
    fn margin(&self, p: Vec3, (cell, reach): (Cell, i64)) -> f32 {
        let low = self.origin
            + (DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) - reach as f64)
                * self.edge;
        let high = low + (2 * reach + 1) as f64 * self.edge;
        let p = p.as_dvec3();
        let m = (p - low).min(high - p).min_element();
        // Cells are assigned in f64 from f32 positions: a relative margin covers rounding.
        (m * (1.0 - 1e-6)) as f32
    }

    /// The `k` nearest of `coords` (sorted by cell, indexed by this grid) to each of
    /// `queries`, nearest first, in the queries' order. Queries of one cell are
    /// answered together from the candidates of its block.
    pub fn nearest(
        &self,
        coords: &[[f32; 3]],
        k: NonZero<usize>,
        queries: &[Vec3],
    ) -> Vec<ArrayVec<u32, K>> {
        // By cell key, then query: the cells in their keys' order, each cell's queries
        // together (those outside the grid last, under the largest key).
        let mut order: Vec<(u64, u32)> = (queries.iter().enumerate())
            .map(|(q, p)| (self.key(*p), q as u32))
            .collect();
        order.sort_unstable();
        let mut found = vec![ArrayVec::new(); queries.len()];
        let (mut candidates, mut far) = (Candidates::default(), Candidates::default());
        // Where each of the block's nine columns was last searched in the occupied cells'
        // keys: queries taken in their cells' order search each column at ascending keys.
        let mut fingers = [0; 9];
        let mut last: Option<f32> = None;
        for group in order.chunk_by(|a, b| a.0 == b.0) {
            if group[0].0 == u64::MAX {
                for &(_, q) in group {
                    let p = queries[q as usize];
                    found[q as usize] = self.searched(coords, k, (p, self.cell_of(p)), &mut far);
                }
                continue;
            }
            let cell = cell_of_key(group[0].0);
            candidates.gather(coords, self.block((cell, 1), &mut fingers));
            for &(_, q) in group {
                let p = queries[q as usize];
                let within = last.map_or(f32::INFINITY, |reach| reach * NEXT_REACH);
                let nearest = candidates.nearest(p, k.get(), within);
                last = nearest.last().map(|n| n.0.sqrt());
                found[q as usize] = if self.exact(&nearest, k, p, (cell, 1)) {
                    nearest.iter().map(|n| n.1).collect()
                } else {
                    self.searched(coords, k, (p, cell), &mut far)
                };
            }
        }
        found
    }

    /// Whether `nearest`, found among the cells within `reach` of `cell`, are the `k`
    /// nearest to `p`: k of them, the k-th within the block's margin.
    fn exact(
        &self,
        nearest: &[(f32, u32)],
        k: NonZero<usize>,
        p: Vec3,
        block: (Cell, i64),
    ) -> bool {
        inside(block.0)
            && nearest.len() == k.get()
            && (nearest.last()).is_some_and(|n| n.0 <= self.margin(p, block).powi(2))
    }

    /// The `k` nearest of `coords` to `p` (in `cell`) whose 3 × 3 × 3 block does not
    /// hold them: from blocks reaching up to [`FARTHEST_REACH`] cells out, gathered
    /// into `candidates` (the caller's buffer, kept between queries), then from the k-d
    /// tree.
    fn searched(
        &self,
        coords: &[[f32; 3]],
        k: NonZero<usize>,
        (p, cell): (Vec3, Cell),
        candidates: &mut Candidates,
    ) -> ArrayVec<u32, K> {
        for reach in 2..=FARTHEST_REACH {
            let mut fingers = [0; FARTHEST_COLUMNS];
            candidates.gather(coords, self.block((cell, reach), &mut fingers));
            let nearest = candidates.nearest(p, k.get(), f32::INFINITY);
            if self.exact(&nearest, k, p, (cell, reach)) {
                return nearest.iter().map(|n| n.1).collect();
            }
        }
        let tree = self
            .tree
            .get_or_init(|| ImmutableKdTree::<f32, 3>::new_from_slice(coords).ok());
        let Some(tree) = tree else {
            return ArrayVec::new();
        };
        let found = tree
            .query(&p.to_array())
            .nearest_n::<SquaredEuclidean<f32>>(k)
            .execute();
        found.iter().map(|f| f.item).take(K).collect()
    }
}

/// The farthest reach, in cells, of the blocks that answer a query its 3 × 3 × 3
/// block does not, before the k-d tree does. On the Lucy-size cloud the tree, built for
/// 0.5 % of the queries, took 1.7 s; the blocks answer all of them.
const FARTHEST_REACH: i64 = 3;
/// Columns (x, y) of the farthest block: its fingers' count.
const FARTHEST_COLUMNS: usize = (2 * FARTHEST_REACH as usize + 1).pow(2);

/// The reach within which a query's k nearest are first sought, in the last query's
/// k-th distance; a query with fewer than k candidates within it selects from them
/// all. On the Lucy-size cloud 38 of a block's 136 candidates lie within it on
/// average, and 0.5 % of the queries select from them all. Before the second bound
/// ([`narrower`]), the cloud_surfels bench took 318 ms at 1.25, 327 ms at 1.1 and
/// 348 ms at 1.5.
const NEXT_REACH: f32 = 1.25;

/// The first index of the ascending `keys` whose key is at least `key`, galloping
/// from `*finger` (or from the start if the key lies before it), and the finger moved
/// there.
fn first_at_least(keys: &[u64], finger: &mut usize, key: u64) -> usize {
    let mut low = *finger;
    if low > 0 && keys[low - 1] >= key {
        low = 0;
    }
    let mut step = 1;
    while low + step <= keys.len() && keys[low + step - 1] < key {
        low += step;
        step *= 2;
    }
    let high = (low + step).min(keys.len());
    *finger = low + keys[low..high].partition_point(|&k| k < key);
    *finger
}

/// A block's positions, gathered coordinate by coordinate for the distance loop.
#[derive(Default)]
struct Candidates {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    id: Vec<u32>,
    /// Every candidate's squared distance to the query, in gathered order.
    squared: Vec<f32>,
    /// The places of those within the query's bound (and garbage past their count).
    places: Vec<u32>,
    /// Their ranks, or every candidate's when no bound holds k.
    chosen: Vec<u64>,
}

impl Candidates {
    fn gather(&mut self, coords: &[[f32; 3]], runs: impl Iterator<Item = std::ops::Range<usize>>) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
        self.id.clear();
        for run in runs {
            let run_coords = &coords[run.clone()];
            self.x.extend(run_coords.iter().map(|c| c[0]));
            self.y.extend(run_coords.iter().map(|c| c[1]));
            self.z.extend(run_coords.iter().map(|c| c[2]));
            self.id.extend(run.map(|i| i as u32));
        }
    }

    /// The `k` nearest candidates to `p` as (squared distance, id), nearest first; of
    /// equally distant ones, the first gathered. Every squared distance is found in one
    /// pass of lane-wise arithmetic; those within a bound are ranked by one integer
    /// ([`distance_rank`]: the distance's bits above the candidate's place) and sorted.
    ///
    /// The bound holds at least `k` candidates, so the k least ranks of the whole block
    /// lie within it; it changes only how many are sorted. The first guess is `within`
    /// ([`NEXT_REACH`] times the last query's k-th distance); from the m candidates
    /// within it, the second ([`narrower`]) expects a little more than k. Each guess is
    /// only counted, lane-wise; the last one that holds k is taken, or none (every
    /// candidate) when neither does.
    fn nearest(&mut self, p: Vec3, k: usize, within: f32) -> ArrayVec<(f32, u32), K> {
        self.squared.resize(self.x.len(), 0.0);
        let columns = self.x.iter().zip(&self.y).zip(&self.z);
        for (d, ((x, y), z)) in self.squared.iter_mut().zip(columns) {
            *d = (x - p.x).powi(2) + (y - p.y).powi(2) + (z - p.z).powi(2);
        }
        let bound = within * within;
        let kept = count_within(&self.squared, bound);
        let narrow = narrower(bound, kept, k);
        let threshold = if kept < k {
            None
        } else if narrow < bound && count_within(&self.squared, narrow) >= k {
            Some(narrow)
        } else {
            Some(bound)
        };
        let rank = |i: usize| distance_rank(self.squared[i], i);
        self.chosen.clear();
        if let Some(threshold) = threshold {
            let count = places_within(&self.squared, threshold, &mut self.places);
            (self.chosen).extend(self.places[..count].iter().map(|&i| rank(i as usize)));
        } else {
            self.chosen.extend((0..self.squared.len()).map(rank));
        }
        let chosen = &mut self.chosen[..];
        let k = k.min(chosen.len());
        if chosen.len() > SORTED_WHOLE {
            chosen.select_nth_unstable(k);
            chosen[..k].sort_unstable();
        } else {
            chosen.sort_unstable();
        }
        let unpacked = |r: &u64| {
            let (d, i) = rank_parts(*r);
            (d, self.id[i])
        };
        chosen[..k].iter().map(unpacked).collect()
    }
}

/// Most ranks that [`Candidates::nearest`] sorts whole rather than selecting the k
/// least first: the standard library sorts up to 32 integers by a sorting network.
const SORTED_WHOLE: usize = 32;

/// How many of the `squared` distances are at most `bound`.
fn count_within(squared: &[f32], bound: f32) -> usize {
    // Counted in u32 lanes, eight to a vector (a block holds far fewer than 2³²).
    let count: u32 = squared.iter().map(|&d| u32::from(d <= bound)).sum();
    count as usize
}

/// A squared distance within which about [`NARROWED`] times `k` of the `kept`
/// candidates within the squared distance `bound` lie, if they spread over a surface:
/// their count grows as the squared distance does.
fn narrower(bound: f32, kept: usize, k: usize) -> f32 {
    bound * (NARROWED * k as f32 / kept as f32)
}

/// How many more than k candidates the narrower bound expects ([`narrower`]). On the
/// Lucy-size cloud 29 of the 38 within the first bound lie within it on average, and
/// at least k for 99.5 % of the queries.
const NARROWED: f32 = 1.2;

/// The grid's edge for `coords`: the [`EDGE_QUANTILE`] of the distance at which a
/// random eighth of them holds K / 8 others (about the whole set's K-th neighbour
/// distance), found from a k-d tree over that eighth. Small sets get one cell.
fn cell_edge(coords: &[[f32; 3]]) -> f64 {
    const QUERIES: usize = 4096;
    // An eighth taken by a hash of the index: a stride would follow a scan's or a
    // lattice's order (every 8th vertex of a generated surface is a sparser row).
    let picked = |i: usize| (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 61 == 0;
    let sample: Vec<[f32; 3]> = (coords.par_iter().enumerate())
        .filter_map(|(i, c)| picked(i).then_some(*c))
        .collect();
    let others = (K - 1) / 8;
    // One cell for all: only where no edge can be measured (a small or degenerate set).
    let whole = || {
        let extent = (coords.iter()).fold(0f32, |m, c| c.iter().fold(m, |m, x| m.max(x.abs())));
        4.0 * extent.max(1.0) as f64
    };
    let (Ok(tree), Some(n)) = (
        ImmutableKdTree::<f32, 3>::new_from_slice(&sample),
        NonZero::new(others + 1).filter(|n| sample.len() > n.get()),
    ) else {
        return whole();
    };
    let step = sample.len().div_ceil(QUERIES);
    let mut distances: Vec<f32> = (sample.iter().step_by(step))
        .filter_map(|p| {
            let found = tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f32>>(n)
                .execute();
            found.last().map(|f| f.distance.sqrt())
        })
        .filter(|d| *d > 0.0 && d.is_finite())
        .collect();
    if distances.is_empty() {
        return whole();
    }
    let at = (distances.len() * EDGE_QUANTILE / 100).min(distances.len() - 1);
    *distances.select_nth_unstable_by(at, f32::total_cmp).1 as f64
}

/// The quantile (in %) of the sampled K-th distances that is the cell edge. On the
/// Lucy-size cloud (14 M points, 4.2 M cells at 97 %) the tree answers 9.5 % of the
/// queries at the 75th percentile, 1.9 % at the 90th and 0.3 % at the 97th, where a
/// block holds 136 candidates; its surfels took 24.2, 21.4 and 20.8 s.
const EDGE_QUANTILE: usize = 97;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_names_its_cell() {
        let last = CELLS_PER_AXIS - 1;
        for cell in [
            [0, 0, 0],
            [1, 2, 3],
            [last, 0, last],
            [7, last, 0],
            [last; 3],
        ] {
            assert_eq!(cell_of_key(key_of(cell)), cell);
        }
    }
}
