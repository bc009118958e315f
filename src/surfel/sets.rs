//! Disjoint sets of `0..n` (union–find with path halving), each named by its least
//! member: the connected pieces of a graph given as its edges, one join each.
//!
//! Joins may run on many threads at once. A join links the greater of two roots under
//! the lesser by compare-and-swap, and retries from the roots when another thread
//! linked that root first; path halving only ever points a member at one of its own
//! ancestors. So every parent is a lesser member of the same set (no cycle, and a
//! set's root is its least member), and once the joins are done each set holds the
//! members that the edges connect, whatever order the threads ran them in.

use std::sync::atomic::{AtomicU32, Ordering::AcqRel, Ordering::Relaxed};

use rayon::prelude::*;

use crate::io::parallel;

pub struct Sets {
    /// Each member's parent, a lesser member or itself (a root, the set's name).
    parent: Vec<AtomicU32>,
}

/// Members per piece of [`Sets::numbered`]'s running count of roots.
const PIECE: usize = 1 << 14;

impl Sets {
    /// `n` sets of one member each; `n` fits in a u32 (members are vertex indices).
    pub fn new(n: usize) -> Sets {
        debug_assert!(n <= u32::MAX as usize + 1);
        Sets {
            parent: (0..n as u64)
                .into_par_iter()
                .map(|k| AtomicU32::new(k as u32))
                .collect(),
        }
    }

    /// The name of `k`'s set: its least member.
    pub fn root(&self, k: usize) -> usize {
        let mut k = k as u32;
        loop {
            let parent = self.parent[k as usize].load(Relaxed);
            if parent == k {
                return k as usize;
            }
            let grand = self.parent[parent as usize].load(Relaxed);
            if grand != parent {
                self.parent[k as usize].store(grand, Relaxed);
            }
            k = grand;
        }
    }

    /// Joins the sets of `a` and `b`.
    pub fn join(&self, a: usize, b: usize) {
        let (mut a, mut b) = (self.root(a), self.root(b));
        while a != b {
            let (lo, hi) = (a.min(b), a.max(b));
            let linked = self.parent[hi].compare_exchange(hi as u32, lo as u32, AcqRel, Relaxed);
            if linked.is_ok() {
                return;
            }
            (a, b) = (self.root(hi), self.root(lo));
        }
    }

    /// Each member's set, the sets numbered from 0 in the order of their least
    /// members; and each set's least member, in that order.
    pub fn numbered(&self) -> (Vec<u32>, Vec<u32>) {
        let mut names: Vec<u32> = (0..self.parent.len())
            .into_par_iter()
            .map(|k| self.root(k) as u32)
            .collect();
        let is_root = |k: usize| names[k] as usize == k;
        // A root's name is itself: the roots kept are the least members.
        let firsts = parallel::filtered(&names, is_root);
        // Each member's count of roots before it, piece by piece: a piece starts
        // from the roots (sorted) below its first member.
        let mut before = vec![0u32; names.len()];
        (before.par_chunks_mut(PIECE).enumerate()).for_each(|(p, piece)| {
            let mut count = firsts.partition_point(|&f| (f as usize) < p * PIECE) as u32;
            for (j, slot) in piece.iter_mut().enumerate() {
                *slot = count;
                count += is_root(p * PIECE + j) as u32;
            }
        });
        names
            .par_iter_mut()
            .for_each(|name| *name = before[*name as usize]);
        (names, firsts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joined_members_share_the_least_as_their_name() {
        let sets = Sets::new(6);
        sets.join(4, 2);
        sets.join(5, 4);
        sets.join(1, 3);
        let names: Vec<usize> = (0..6).map(|k| sets.root(k)).collect();
        assert_eq!(names, [0, 1, 2, 1, 2, 2]);
        assert_eq!(sets.numbered(), (vec![0, 1, 2, 1, 2, 2], vec![0, 1, 2]));
    }

    /// Runs of 1000 members joined by every thread at once: the same sets as joined
    /// one by one.
    #[test]
    fn joins_on_many_threads_make_the_same_sets() {
        let n = 3 * PIECE + 7;
        // Each member joined to the next but at every 1000th, in a scrambled order
        // (7919 is prime to n − 1).
        let edges: Vec<(usize, usize)> = (0..n - 1)
            .map(|k| (k * 7919) % (n - 1))
            .filter(|a| a % 1000 != 999)
            .map(|a| (a, a + 1))
            .collect();
        let serial = Sets::new(n);
        edges.iter().for_each(|&(a, b)| serial.join(b, a));
        let parallel = Sets::new(n);
        edges.par_iter().for_each(|&(a, b)| parallel.join(a, b));
        assert_eq!(serial.numbered(), parallel.numbered());
        let (names, firsts) = parallel.numbered();
        assert_eq!(firsts.len(), n.div_ceil(1000));
        assert!(
            firsts
                .iter()
                .enumerate()
                .all(|(i, &f)| names[f as usize] == i as u32)
        );
        assert_eq!(firsts[1], 1000);
    }
}
