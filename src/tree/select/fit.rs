//! The least ε whose prefixes lie in what is loaded: when only part of the list is on
//! the GPU (while a model uploads, or under a memory budget), a frame is drawn at the
//! finest ε whose prefix bounds all lie in the resident part, a coarser cut, never a
//! holed one.
//!
//! Chunk c's bound is the first block beyond ([`PrefixIndex::prefix_bound`]), times
//! [`BLOCK`]. With k nodes of the chunk resident from its start, the bound is at most k
//! once block m = ⌊k / BLOCK⌋ is beyond, and the test of a block is monotone in ε:
//!
//! ```text
//! head_m ≤ ε (d_min − Δ_m)   ⇔   ε ≥ head_m / (d_min − Δ_m)     (d_min > Δ_m)
//! ```
//!
//! so the least fitting ε is the largest of these over the chunks whose bound at the
//! asked ε exceeds their resident part: one block test a chunk, not a search over ε
//! that evaluates every chunk's prefix several times. A chunk with d_min ≤ Δ_m (the eye
//! within reach of its nodes) or an infinite head (the root's e_parent) needs the block
//! at any ε; it is left out of the largest and its range is cut to what is there.

use rayon::prelude::*;

use super::{BLOCK, PrefixIndex, Prefixes};
use crate::tree::record::decode;

/// Relative margin above each chunk's threshold, so that the block test, rounded, holds
/// there.
const MARGIN: f64 = 1e-9;

impl PrefixIndex {
    /// The least ε ≥ `prefixes.eps()` at which the prefix bound of every chunk of
    /// `prefixes` is at most its resident part, `resident(start, count)`: the nodes from
    /// list index `start` on, of the `count` of its chunk, that are loaded. (Chunks
    /// skipped at the asked ε for being too coarse could enter at the larger one; the
    /// caller checks the bounds found there and calls again with them.)
    pub fn least_fitting_eps(
        &self,
        prefixes: &Prefixes,
        resident: impl Fn(usize, usize) -> usize + Sync,
    ) -> f64 {
        prefixes
            .list
            .par_iter()
            .with_min_len(super::PARALLEL_CHUNKS)
            .filter_map(|p| {
                let count = self.chunks[p.chunk].count as usize;
                let held = resident(p.start, count);
                match p.bound > held {
                    true => self.threshold(p.chunk, held / BLOCK, p.d_min),
                    false => None,
                }
            })
            .reduce(|| prefixes.eps, f64::max)
    }

    /// The least ε at which block `m` of chunk `c`, seen from `d_min`, is beyond; `None`
    /// when no ε makes it so (the eye within its reach, or a head of infinite error: a
    /// root's).
    fn threshold(&self, c: usize, m: usize, d_min: f64) -> Option<f64> {
        let at = self.block_at[c] + m;
        let reach = d_min - decode(self.delta_suffix[at], self.error_scale);
        let least = decode(self.heads[at], self.error_scale) / reach * (1.0 + MARGIN);
        (reach > 0.0 && least.is_finite()).then_some(least)
    }
}
