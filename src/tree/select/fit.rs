//! What a view asks of a list only partly loaded (while a model uploads, or under a GPU
//! memory budget), found without searching any chunk's prefix: the least ε at which
//! the view's prefixes lie in what is loaded (a coarser cut, never a holed one), and
//! the units of loading (slices) that the asked ε wants.
//!
//! Chunk c's prefix bound is the first block beyond ([`PrefixIndex::prefix_bound`]),
//! times [`BLOCK`], and the block test is monotone along the chunk and in ε. With k
//! nodes of the chunk loaded from its start, the bound is at most k once block
//! m = ⌊k / BLOCK⌋ is beyond:
//!
//! ```text
//! head_m ≤ ε (d_min − Δ_m)   ⇔   ε ≥ head_m / (d_min − Δ_m)  =: ε_hi     (d_min > Δ_m)
//! ```
//!
//! and a chunk is not drawn at all while it is too coarse, ε < e_min / d_max =: ε_lo.
//! So the chunk holds the frame back for ε in [ε_lo, ε_hi) only, and the least fitting
//! ε ≥ ε₀ is found by one block test a chunk and a sweep over those intervals in order
//! of ε_lo. A chunk with d_min ≤ Δ_m (the eye within reach of its nodes) or an infinite
//! head (a root's e_parent) needs the block at any ε; it is left out and its range is cut
//! to what is there.
//!
//! Likewise the prefix at ε₀ reaches a chunk offset o (the start of the next slice) iff
//! block ⌊o / BLOCK⌋ is not beyond: a test per slice boundary inside the chunk, which
//! finds the slices the prefix lies in without finding where in them it ends.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::{BLOCK, PrefixIndex, ViewCone, distances};
use crate::tree::record::decode;

/// Relative margin above each chunk's threshold, so that the block test, rounded, holds
/// there.
const MARGIN: f64 = 1e-9;

/// What a view at ε₀ asks of a partly loaded list ([`PrefixIndex::fit`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// The least ε ≥ ε₀ whose prefix bounds lie in what is loaded.
    pub eps: f64,
    /// Each chunk's prefix at ε₀, its end rounded up to the next multiple of the unit of
    /// loading (or the chunk's end): the same units as the prefixes, found without them.
    pub wanted: Vec<Range<usize>>,
}

/// One chunk's part of a [`Fit`]: its wanted range at ε₀, and the interval of ε over
/// which it holds the frame back.
type ChunkFit = (Option<Range<usize>>, Option<(f64, f64)>);

impl PrefixIndex {
    /// What the view from `eye` at `eps` (chunks culled by `cone`) asks of a list loaded
    /// in units of `unit` nodes, of which `loaded(start, count)` says how many, from list
    /// index `start` on, of the `count` of its chunk are there.
    pub fn fit(
        &self,
        eye: DVec3,
        eps: f64,
        cone: Option<&ViewCone>,
        unit: usize,
        loaded: impl Fn(usize, usize) -> usize + Sync,
    ) -> Fit {
        let per_chunk: Vec<ChunkFit> = (0..self.pages.len())
            .into_par_iter()
            .filter(|&p| !self.page_unasked(p, eye, eps, cone))
            .flat_map_iter(|p| {
                let chunks = self.page_chunks(p);
                let fits = chunks.map(|c| self.chunk_fit(c, eye, eps, cone, unit, &loaded));
                fits.filter(|f| f.0.is_some() || f.1.is_some())
            })
            .collect();
        let fit = least_outside(eps, per_chunk.iter().filter_map(|f| f.1));
        let wanted = per_chunk.into_iter().filter_map(|f| f.0).collect();
        Fit { eps: fit, wanted }
    }

    /// Whether no chunk of page `p` is asked for at `eps` or above: all unseen, or all
    /// too fine (each one's prefix empty, and so at any larger ε).
    fn page_unasked(&self, p: usize, eye: DVec3, eps: f64, cone: Option<&ViewCone>) -> bool {
        let page = &self.pages[p];
        let d_min = distances(&page.bounds, eye).0;
        cone.is_some_and(|v| !v.sees_chunk(&page.bounds)) || self.page_too_fine(page, d_min, eps)
    }

    /// Chunk c's wanted range at `eps` (its prefix rounded up to `unit`s) and the
    /// interval [ε_lo, ε_hi) of ε ≥ `eps` over which its loaded part is too short.
    fn chunk_fit(
        &self,
        c: usize,
        eye: DVec3,
        eps: f64,
        cone: Option<&ViewCone>,
        unit: usize,
        loaded: impl Fn(usize, usize) -> usize,
    ) -> ChunkFit {
        let chunk = &self.chunks[c];
        let (d_min, d_max) = distances(chunk, eye);
        // Too fine (nothing asked at `eps` or above) is the cheaper test: first.
        if self.first_beyond(c, d_min, eps) || cone.is_some_and(|v| !v.sees_chunk(chunk)) {
            return (None, None);
        }
        let (start, count) = (chunk.start as usize, chunk.count as usize);
        let e_min = chunk.error_min as f64 * self.error_scale as f64;
        // Too coarse to draw below ε_lo ([`PrefixIndex::skipped`]'s test).
        let lo = if e_min > 0.0 { e_min / d_max } else { 0.0 };
        let wanted = (e_min <= eps * d_max)
            .then(|| self.reach_in_units(c, d_min, eps, unit))
            .filter(|&n| n > 0)
            .map(|n| start..start + n);
        let held = loaded(start, count);
        let hold = (held < count)
            .then(|| self.threshold(c, held / BLOCK, d_min))
            .flatten()
            .filter(|&hi| hi > eps && hi > lo)
            .map(|hi| (lo, hi));
        (wanted, hold)
    }

    /// Chunk c's prefix bound at `eps`, its first block not beyond, rounded up to the
    /// next multiple of `unit` in the list (or the chunk's end): the first slice
    /// boundary inside the chunk that the prefix does not reach, by one block test a
    /// boundary.
    fn reach_in_units(&self, c: usize, d_min: f64, eps: f64, unit: usize) -> usize {
        let heads = &self.heads[self.block_at[c]..];
        let beyond = |i: usize| self.beyond(c, i, heads[i / BLOCK], d_min, eps);
        let (start, count) = (self.chunks[c].start as usize, self.chunks[c].count as usize);
        // The first block is not beyond (the caller tested it).
        let mut end = (start / unit + 1) * unit - start;
        while end < count && !beyond(end) {
            end += unit;
        }
        end.min(count)
    }

    /// The least ε at which block `m` of chunk `c`, seen from `d_min`, is beyond; `None`
    /// when no ε makes it so (the eye within its reach, or a head of infinite error: a
    /// root's).
    fn threshold(&self, c: usize, m: usize, d_min: f64) -> Option<f64> {
        let at = self.block_at[c] + m;
        let (head, delta) = match m {
            0 => self.firsts[c],
            _ => (
                decode(self.heads[at], self.error_scale),
                decode(self.delta_suffix[at], self.error_scale),
            ),
        };
        let reach = d_min - delta;
        let least = head / reach * (1.0 + MARGIN);
        (reach > 0.0 && least.is_finite()).then_some(least)
    }
}

/// The least ε ≥ `eps` in none of the intervals [lo, hi) of `holds`: the largest hi of
/// those holding `eps`, then a sweep, in order of lo, over those that begin above it
/// (chunks too coarse at `eps`: few).
fn least_outside(eps: f64, holds: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (now, mut later): (Vec<_>, Vec<_>) = holds.partition(|&(lo, _)| lo <= eps);
    let mut fit = now.iter().fold(eps, |fit, &(_, hi)| fit.max(hi));
    later.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    for (lo, hi) in later {
        if lo > fit {
            break;
        }
        fit = fit.max(hi);
    }
    fit
}
