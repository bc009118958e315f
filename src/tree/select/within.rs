//! The exact prefixes of many chunks at once. Each chunk's exact prefix lies within the
//! last block of its bound ([`PrefixIndex::prefix_bound`]), found by a binary search of
//! that block's nodes. A view needs tens of thousands of such searches, each a chain
//! of six reads that depend on one another and mostly miss the cache (the nodes of a
//! large file are memory-mapped, spread over gigabytes). Run one after the other, the
//! CPU waits out each miss; run in lockstep, [`LANES`] searches at a time each taking
//! one step per round, a round's reads are independent and overlap.

use super::{BLOCK, Prefix, PrefixIndex};
use crate::tree::NodeRecord;

/// Searches run in lockstep.
const LANES: usize = 16;

impl PrefixIndex {
    /// Each chunk's prefix length for the view `prefixes` were found at (ε `eps`):
    /// exact where `exact` says so, its bound elsewhere.
    pub(super) fn prefixes_within(
        &self,
        prefixes: &[Prefix],
        exact: &[bool],
        nodes: &[NodeRecord],
        eps: f64,
    ) -> Vec<usize> {
        let mut out = Vec::with_capacity(prefixes.len());
        for (lane, exact) in prefixes.chunks(LANES).zip(exact.chunks(LANES)) {
            out.extend(self.lockstep(lane, exact, nodes, eps));
        }
        out
    }

    /// [`PrefixIndex::prefixes_within`] of at most [`LANES`] chunks: the searches of
    /// `prefix_within`, a step of each per round.
    fn lockstep<'a>(
        &self,
        lane: &'a [Prefix],
        exact: &[bool],
        nodes: &[NodeRecord],
        eps: f64,
    ) -> impl Iterator<Item = usize> + 'a {
        let (mut lo, mut hi) = ([0; LANES], [0; LANES]);
        for (j, p) in lane.iter().enumerate() {
            hi[j] = p.bound;
            lo[j] = match exact[j] {
                true => (p.bound.saturating_sub(1) / BLOCK) * BLOCK,
                false => p.bound,
            };
        }
        let mut heads = [0u16; LANES];
        // Each round halves every open interval: a block's search ends within
        // log₂ BLOCK + 1 rounds.
        while (0..lane.len()).any(|j| lo[j] < hi[j]) {
            // The reads first, none depending on another.
            for (j, p) in lane.iter().enumerate() {
                if lo[j] < hi[j] {
                    let mid = lo[j] + (hi[j] - lo[j]) / 2;
                    heads[j] = nodes[p.start + mid].parent_error;
                }
            }
            for (j, p) in lane.iter().enumerate() {
                if lo[j] < hi[j] {
                    let mid = lo[j] + (hi[j] - lo[j]) / 2;
                    match self.beyond(p.chunk, mid, heads[j], p.d_min, eps) {
                        true => hi[j] = mid,
                        false => lo[j] = mid + 1,
                    }
                }
            }
        }
        lo.into_iter().take(lane.len())
    }
}
