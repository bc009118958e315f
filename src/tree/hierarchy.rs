//! The hierarchy over the leaf surfels (docs/design.md §3).
//!
//! A range of surfels is split in two at the midpoint of the longest axis of its
//! centres' bounding box (an in-place partition), and each half once more: two binary
//! levels make one node, so an internal node has 2–4 children and a range of at most 4
//! surfels has them as its children (leaves). When the midpoint split leaves fewer
//! than 1/[`UNBALANCED`] of the range on one side (duplicates, collinear or clustered
//! points), the range is split at its median instead (by index when all centres
//! coincide), so the depth stays O(log n) and the build O(n log n) on any input.
//!
//! Node ids: leaves are `0..n` (the surfels' order after partitioning,
//! [`Hierarchy::leaf_order`]), internal nodes `n..n + m` in post-order (children before
//! their parent; the root is last).
//!
//! The partitions move [`Key`]s, each a surfel's centre and index (16 bytes), not the
//! surfels themselves (52): on the Lucy-size mesh the surfels' swaps were three
//! quarters of the stage.

use rayon::prelude::*;

use super::report::Report;

use crate::surfel::Surfel;
use glam::Vec3;

/// A split keeps at least 1/UNBALANCED of the range on each side, or is redone at the median.
pub const UNBALANCED: usize = 16;
/// Ranges smaller than this are built on one thread.
const PARALLEL_RANGE: usize = 1 << 15;

/// The most children an internal node has: two binary levels make one node.
pub const MAX_CHILDREN: usize = 4;

/// An internal node: its children's ids (leaf or internal).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Internal {
    pub children: [u32; MAX_CHILDREN],
    pub child_count: u8,
}

impl Internal {
    pub fn children(&self) -> &[u32] {
        &self.children[..self.child_count as usize]
    }

    /// The node over `children` (at most [`MAX_CHILDREN`]), in their order.
    fn over(children: impl IntoIterator<Item = u32>) -> Internal {
        let mut node = Internal {
            children: [0; MAX_CHILDREN],
            child_count: 0,
        };
        for child in children {
            node.children[node.child_count as usize] = child;
            node.child_count += 1;
        }
        node
    }
}

/// The hierarchy: internal nodes in post-order, ids as in the module doc.
#[derive(Debug, Clone)]
pub struct Hierarchy {
    pub leaf_count: u32,
    pub internal: Vec<Internal>,
    /// Leaf id k is the input's surfel `leaf_order[k]` (a permutation of
    /// `0..leaf_count`). Emptied by [`build_records_scaled`](super::build_records_scaled),
    /// which puts the leaves' records in this order and drops the surfels.
    pub leaf_order: Vec<u32>,
}

/// What the partitions move: a surfel's centre and its index in the input.
#[derive(Debug, Clone, Copy)]
struct Key {
    position: Vec3,
    index: u32,
}

impl Hierarchy {
    pub fn node_count(&self) -> usize {
        self.leaf_count as usize + self.internal.len()
    }

    /// The root: the last internal node, or the single leaf of a one-surfel model.
    pub fn root(&self) -> u32 {
        (self.node_count() - 1) as u32
    }

    pub fn is_leaf(&self, id: u32) -> bool {
        id < self.leaf_count
    }

    /// Parent id of every node (the root's is u32::MAX).
    pub fn parents(&self) -> Vec<u32> {
        let mut parent = vec![u32::MAX; self.node_count()];
        for (k, node) in self.internal.iter().enumerate() {
            for &c in node.children() {
                parent[c as usize] = self.leaf_count + k as u32;
            }
        }
        parent
    }

    /// Depth of every node (root 0), computed parents first (reverse post-order).
    pub fn levels(&self) -> Vec<u16> {
        let mut level = vec![0u16; self.node_count()];
        for (k, node) in self.internal.iter().enumerate().rev() {
            let l = level[self.leaf_count as usize + k].saturating_add(1);
            for &c in node.children() {
                level[c as usize] = l;
            }
        }
        level
    }
}

/// Splits `s` in two non-empty parts; returns the size of the first.
fn split(s: &mut [Key]) -> usize {
    let n = s.len();
    let (mut lo, mut hi) = (s[0].position, s[0].position);
    for x in s.iter() {
        lo = lo.min(x.position);
        hi = hi.max(x.position);
    }
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = 0.5 * (lo[axis] + hi[axis]);
    let left = partition_below(s, axis, mid);
    if left.min(n - left) * UNBALANCED >= n {
        return left;
    }
    // Median along the axis: O(n), and both halves non-empty even if all coincide.
    let half = n / 2;
    s.select_nth_unstable_by(half, |a, b| a.position[axis].total_cmp(&b.position[axis]));
    half
}

/// Moves the keys whose centre lies below `mid` along `axis` to the front, in place,
/// and returns how many there are: Lomuto's partition, each key in turn swapped with
/// the first key not below when it lies below. The swap is done or not by selects
/// rather than a branch, which a random half of the keys would mispredict; the keys
/// end where the branching loop puts them.
fn partition_below(s: &mut [Key], axis: usize, mid: f32) -> usize {
    let mut left = 0;
    for i in 0..s.len() {
        let (here, first) = (s[i], s[left]);
        let below = here.position[axis] < mid;
        s[i] = if below { first } else { here };
        s[left] = if below { here } else { first };
        left += below as usize;
    }
    left
}

/// Splits a range into its up to four child ranges (two binary levels).
fn child_ranges(s: &mut [Key]) -> Vec<(usize, usize)> {
    if s.len() <= 4 {
        return (0..s.len()).map(|i| (i, 1)).collect();
    }
    let a = split(s);
    let mut out = Vec::with_capacity(4);
    for (start, len) in [(0, a), (a, s.len() - a)] {
        if len >= 2 {
            let b = split(&mut s[start..start + len]);
            out.push((start, b));
            out.push((start + b, len - b));
        } else {
            out.push((start, len));
        }
    }
    out
}

/// A child reference local to a subtree: leaves are absolute ids, internal nodes are
/// `leaf_count + index` into the subtree's own post-order vector.
fn build_seq(s: &mut [Key], offset: usize, leaf_count: u32, out: &mut Vec<Internal>) -> u32 {
    if s.len() == 1 {
        return offset as u32;
    }
    let node = Internal::over(child_ranges(s).into_iter().map(|(start, len)| {
        build_seq(&mut s[start..start + len], offset + start, leaf_count, out)
    }));
    out.push(node);
    leaf_count + out.len() as u32 - 1
}

/// A subtree of [`build_par`]: built whole on one thread (nodes in post-order, ids
/// local as [`build_seq`] gives them, and its root), or split, its parts built in
/// parallel and joined only once, by [`Built::append`]. Joining at every parallel level
/// had copied the Lucy-size mesh's 7 M internal nodes four or five times.
enum Built {
    Whole(Vec<Internal>, u32),
    Split(Vec<Built>),
}

impl Built {
    /// Its internal nodes.
    fn len(&self) -> usize {
        match self {
            Built::Whole(nodes, _) => nodes.len(),
            Built::Split(parts) => parts.iter().map(Built::len).sum::<usize>() + 1,
        }
    }

    /// Appends its nodes to `out` in post-order, each internal id moved by where its
    /// subtree lands, and returns its root's id.
    fn append(self, out: &mut Vec<Internal>, leaf_count: u32) -> u32 {
        match self {
            Built::Whole(nodes, root) => {
                let base = out.len() as u32;
                let shift = |id: u32| if id >= leaf_count { id + base } else { id };
                out.extend(nodes.into_iter().map(|mut n| {
                    for c in &mut n.children[..n.child_count as usize] {
                        *c = shift(*c);
                    }
                    n
                }));
                shift(root)
            }
            Built::Split(parts) => {
                let node =
                    Internal::over(parts.into_iter().map(|part| part.append(out, leaf_count)));
                out.push(node);
                leaf_count + out.len() as u32 - 1
            }
        }
    }
}

/// Like [`build_seq`], on several threads: the child subtrees are built in parallel
/// and joined in child order, so the result does not depend on the number of threads.
fn build_par(s: &mut [Key], offset: usize, leaf_count: u32, report: &dyn Report) -> Built {
    if s.len() <= PARALLEL_RANGE {
        let mut out = Vec::new();
        let root = build_seq(s, offset, leaf_count, &mut out);
        report.advance(s.len() as u64);
        return Built::Whole(out, root);
    }
    let ranges = child_ranges(s);
    let mut pieces = Vec::with_capacity(4);
    let mut rest = s;
    let mut at = 0;
    for &(start, len) in &ranges {
        let (_, tail) = rest.split_at_mut(start - at);
        let (piece, tail) = tail.split_at_mut(len);
        pieces.push((piece, offset + start));
        rest = tail;
        at = start + len;
    }
    Built::Split(
        pieces
            .into_par_iter()
            .map(|(piece, off)| build_par(piece, off, leaf_count, report))
            .collect(),
    )
}

/// Builds the hierarchy over `surfels`, ordering its leaves so that every node covers
/// a contiguous range of them ([`Hierarchy::leaf_order`]). `report` is told how many
/// leaves each finished subtree holds.
pub fn build(surfels: &[Surfel], report: &dyn Report) -> Hierarchy {
    let leaf_count = u32::try_from(surfels.len()).expect("leaf ids fit u32");
    let mut keys: Vec<Key> = surfels
        .par_iter()
        .enumerate()
        .map(|(i, s)| Key {
            position: s.position,
            index: i as u32,
        })
        .collect();
    let internal = if keys.is_empty() {
        Vec::new()
    } else {
        let built = build_par(&mut keys, 0, leaf_count, report);
        let mut internal = Vec::with_capacity(built.len());
        built.append(&mut internal, leaf_count);
        internal
    };
    Hierarchy {
        leaf_count,
        internal,
        leaf_order: keys.par_iter().map(|k| k.index).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_branch_free_partition_puts_each_key_where_the_branching_one_does() {
        // Lomuto's partition with a branch, as the reference.
        fn branching(s: &mut [Key], axis: usize, mid: f32) -> usize {
            let mut left = 0;
            for i in 0..s.len() {
                if s[i].position[axis] < mid {
                    s.swap(i, left);
                    left += 1;
                }
            }
            left
        }
        // Keys on a scrambled lattice with repeated coordinates, split on each axis at
        // a coordinate some keys hold, between two, below all and above all.
        let keys: Vec<Key> = (0..1000u32)
            .map(|i| {
                let h = i.wrapping_mul(2_654_435_761);
                let c = |shift: u32| ((h >> shift) % 17) as f32 - 8.0;
                Key {
                    position: Vec3::new(c(3), c(11), c(19)),
                    index: i,
                }
            })
            .collect();
        let order = |s: &[Key]| s.iter().map(|k| k.index).collect::<Vec<_>>();
        for axis in 0..3 {
            for mid in [0.0, 0.5, -9.0, 9.0, f32::NAN] {
                let (mut a, mut b) = (keys.clone(), keys.clone());
                let (left_a, left_b) = (
                    partition_below(&mut a, axis, mid),
                    branching(&mut b, axis, mid),
                );
                assert_eq!(
                    (left_a, order(&a)),
                    (left_b, order(&b)),
                    "axis {axis}, mid {mid}"
                );
                assert!(a[..left_a].iter().all(|k| k.position[axis] < mid));
                assert!(!a[left_a..].iter().any(|k| k.position[axis] < mid));
            }
        }
    }
}
