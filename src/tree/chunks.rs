//! Chunks (docs/design.md §5, "Chunks"): the list cut into contiguous ranges, each a
//! sequential list of its own (sorted by parent error, descending) with its own box of
//! node centres, so that each frame the CPU culls whole chunks by the frustum and finds
//! each visible chunk's prefix from the chunk's own distance to the eye.
//!
//! A tree is cut at the maximal subtrees of at most `max_nodes` nodes ([`cut`]), the
//! nodes above them (whose subtrees are larger) making the *top* part; then each part
//! is cut across into bands of levels ([`by_level`]), from a small first band (64
//! nodes) growing eightfold up to a sixteenth of `max_nodes` (its lowest level
//! excepted). Each band is a chunk: its
//! nodes, its box and its least error. The list holds the chunks coarse first: by the
//! octave of their largest parent error, then by their first level, then in the
//! hierarchy's order, which is spatial ([`coarse_first`]).
//!
//! **Why bands.** In a tree of 2–4 children, the nodes above any cut are a third as
//! many as the cut: a chunk holding whole subtrees hands its nodes above the cut to the
//! GPU, to be rejected as too coarse. A band whose least error e_min exceeds ε · d_max
//! (d_max: the eye's farthest distance to the band's box) has no node fine enough to
//! draw, so the CPU skips it whole ([`super::select::PrefixIndex::ranges`]).
//!
//! **Why selection stays hole-free across chunk boundaries.** Every node keeps its
//! own record (e, e_parent, δ), so the exact test of docs/design.md §5 draws the same nodes
//! whatever the chunks are, and that set covers every leaf. What the chunks change is
//! only what the CPU hands over: in chunk c, the nodes past the first i with
//! `e_parent[i] ≤ ε · (d_min(c) − Δ_c[i])` cannot pass the test, because d_min(c), the
//! distance from the eye to the chunk's box, is at most any of its nodes' d, and `Δ_c[i]`
//! is the largest δ from i to the chunk's end. The chunk is sorted, so the predicate is
//! monotone and its binary search exact. A chunk whose box, grown by its largest splat
//! radius, lies outside the view cone holds only splats the GPU's frustum test would
//! cull ([`super::select::ViewCone`]). So the union of the chunks' prefixes holds every
//! node the GPU would draw: the partition needs no property of the tree (a chunk need
//! not even be a subtree) for the argument; subtrees make chunks compact in space and
//! let them be built and loaded apart.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::NodeRecord;
use super::hierarchy::Hierarchy;
use super::record::half_value;

/// Nodes per subtree cut ([`cut`]) at most, for a tree of `node_count` nodes: about
/// 1/4096 of the tree, between 2⁸ and 2¹⁶. Small subtrees cull tightly: with 256, the
/// GPU tests 1.4–1.5 nodes per splat drawn on close-ups, against 1.6–1.8 with 2¹⁰ and
/// 4 for one list (`spt render` prints the ratio); the bound keeps a billion nodes to
/// 15,000 subtrees, their bands to a table of a few MB.
pub fn chunk_nodes_for(node_count: usize) -> usize {
    (node_count / 4096).clamp(1 << 8, 1 << 16)
}

/// One chunk as the `.spt` file stores it (48 bytes): its range of the list, the box
/// of its node centres (relative to the origin) with its largest splat radius, and its
/// least error.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize)]
pub struct Chunk {
    /// First node (list index).
    pub start: u64,
    /// Nodes in the chunk.
    pub count: u32,
    /// The least level of its nodes (root 0).
    pub level: u32,
    pub centre_min: [f32; 3],
    pub centre_max: [f32; 3],
    /// The largest radius of its nodes (for culling by the frustum).
    pub radius_max: f32,
    /// The least error of its nodes, divided by the error scale: the value of the least
    /// f16 error, exact in f32, so that e_min · scale is each node's own decoding.
    pub error_min: f32,
}

impl Chunk {
    /// The chunk of `nodes`, which start at list index `start`.
    pub fn of(start: usize, nodes: &[NodeRecord]) -> Chunk {
        let (lo, hi, r, (e, level)) = nodes
            .par_iter()
            .with_min_len(4096)
            .map(|n| (n.position(), n.position(), n.radius(), (n.error, n.level)))
            .reduce(
                || {
                    let none = (u16::MAX, u16::MAX);
                    (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN), 0.0f32, none)
                },
                |a, b| {
                    let least = (a.3.0.min(b.3.0), a.3.1.min(b.3.1));
                    (a.0.min(b.0), a.1.max(b.1), a.2.max(b.2), least)
                },
            );
        Chunk {
            start: start as u64,
            count: nodes.len() as u32,
            level: level as u32,
            centre_min: lo.to_array(),
            centre_max: hi.to_array(),
            radius_max: r,
            error_min: half_value(e),
        }
    }

    pub fn range(&self) -> std::ops::Range<usize> {
        self.start as usize..self.start as usize + self.count as usize
    }

    /// The chunks of consecutive runs of `counts` list positions, each made from its
    /// nodes as `nodes` gives them for its range of positions.
    pub fn table_of(
        counts: &[usize],
        nodes: impl Fn(std::ops::Range<usize>) -> Vec<NodeRecord> + Sync,
    ) -> Vec<Chunk> {
        let starts: Vec<usize> = counts
            .iter()
            .scan(0, |at, &k| {
                *at += k;
                Some(*at - k)
            })
            .collect();
        starts
            .par_iter()
            .zip(counts)
            .map(|(&at, &k)| Chunk::of(at, &nodes(at..at + k)))
            .collect()
    }
}

/// A tree cut into chunks: each chunk's node ids (in no particular order), the top
/// chunk first.
pub struct Cut {
    pub chunks: Vec<Vec<u32>>,
}

/// For each node: (subtree size, first leaf of the subtree), internal nodes in
/// post-order so children come first.
fn subtree_spans(h: &Hierarchy) -> Vec<(u32, u32)> {
    let n = h.leaf_count as usize;
    let mut span: Vec<(u32, u32)> = (0..n as u32).map(|i| (1, i)).collect();
    span.reserve(h.internal.len());
    for node in &h.internal {
        let (mut size, mut first) = (1u32, u32::MAX);
        for &c in node.children() {
            let (s, f) = span[c as usize];
            size += s;
            first = first.min(f);
        }
        span.push((size, first));
    }
    span
}

/// The ids of the subtree rooted at `root`: its leaves and its internal nodes are each
/// a contiguous range of ids (the hierarchy partitions the surfels in place and numbers
/// internal nodes in post-order, the subtree's root last).
fn subtree_ids(h: &Hierarchy, span: &[(u32, u32)], root: u32) -> Vec<u32> {
    let (size, first_leaf) = span[root as usize];
    if h.is_leaf(root) {
        return vec![root];
    }
    // Leaves of the subtree: the range from its first leaf (leaves make up
    // size − internal of it; count them by walking down the last child chain).
    let leaves = subtree_leaves(h, span, root);
    let internal = size - leaves;
    let mut ids: Vec<u32> = (first_leaf..first_leaf + leaves).collect();
    ids.extend(root + 1 - internal..=root);
    ids
}

/// Leaves under `root`: the last leaf is the last child chain's leaf.
fn subtree_leaves(h: &Hierarchy, span: &[(u32, u32)], root: u32) -> u32 {
    let mut at = root;
    while !h.is_leaf(at) {
        let node = &h.internal[(at - h.leaf_count) as usize];
        at = *node
            .children()
            .last()
            .expect("an internal node has children");
    }
    at + 1 - span[root as usize].1
}

/// Cuts `h` into chunks of at most `max_nodes` nodes (module doc): the top chunk (the
/// nodes whose subtree is larger; absent when the whole tree fits), then each maximal
/// subtree that fits, in depth-first child order.
pub fn cut(h: &Hierarchy, max_nodes: usize) -> Cut {
    if h.node_count() == 0 {
        return Cut { chunks: Vec::new() };
    }
    let span = subtree_spans(h);
    let fits = |id: u32| span[id as usize].0 as usize <= max_nodes;
    let root = h.root();
    if fits(root) {
        return Cut {
            chunks: vec![(0..h.node_count() as u32).collect()],
        };
    }
    let (mut top, mut roots) = (Vec::new(), Vec::new());
    let mut stack = vec![root];
    while let Some(id) = stack.pop() {
        if fits(id) {
            roots.push(id);
            continue;
        }
        top.push(id);
        let node = &h.internal[(id - h.leaf_count) as usize];
        // Reversed so that children pop in their order.
        stack.extend(node.children().iter().rev());
    }
    let mut chunks = vec![top];
    chunks.par_extend(roots.par_iter().map(|&r| subtree_ids(h, &span, r)));
    Cut { chunks }
}

/// The order of chunks in the list, coarse first: by the binary octave of the chunk's
/// largest parent error (f16 bits, non-negative: the exponent field), descending, then
/// by its least level. A view at ε needs chunk c only if that largest parent error
/// exceeds `ε · (d_min(c) − Δ_c[0])` (module doc), so over chunks at similar distances
/// what a view needs is a prefix of this order, within an octave: a viewer streaming
/// slices of consecutive nodes fetches few for a coarse view.
pub fn coarse_first(largest_parent_error: u16, level: u32) -> (u16, u32) {
    (0x1f - (largest_parent_error >> 10), level)
}

/// Nodes in a part's first band at least (unless `min_band` is less), and how much
/// larger each next band is at least, up to `min_band`. A far view needs only the head
/// of each subtree, and a viewer streaming under a budget fetches whole runs of the
/// list: small first bands, sorted to the front ([`coarse_first`]), keep what a far
/// view needs together. Growing bands keep their number per part to a few.
const FIRST_BAND: usize = 64;
const BAND_GROWTH: usize = 8;

/// Sorts `ids` by (`key(id)`, id), as one u64 each: the key is read once per id
/// rather than twice per comparison (a gather from the records in random order). On
/// the Lucy-size mesh the list's sorts took about 1 CPU-second that way.
pub fn sort_by_key_then_id(ids: &mut [u32], key: impl Fn(u32) -> u16) {
    let mut keyed: Vec<u64> = ids
        .iter()
        .map(|&id| (u64::from(key(id)) << 32) | u64::from(id))
        .collect();
    keyed.sort_unstable();
    for (id, k) in ids.iter_mut().zip(&keyed) {
        *id = *k as u32;
    }
}

/// Cuts each part of `cut` (the top part first, then the subtrees) into bands of
/// whole levels, the first of at least [`FIRST_BAND`] nodes, each next
/// [`BAND_GROWTH`] times more, up to `min_band` (the lowest band of a part excepted), and
/// orders the bands [`coarse_first`], then by part: the chunks of the list. `level`
/// and `parent_error` give each node's level and parent error (f16 bits).
pub fn by_level(
    cut: Cut,
    min_band: usize,
    level: impl Fn(u32) -> u16 + Sync,
    parent_error: impl Fn(u32) -> u16 + Sync,
) -> Cut {
    let mut bands: Vec<(u16, u32, usize, Vec<u32>)> = cut
        .chunks
        .into_par_iter()
        .enumerate()
        .flat_map_iter(|(part, mut ids)| {
            sort_by_key_then_id(&mut ids, &level);
            let mut out = Vec::new();
            let (mut start, mut least) = (0, min_band.min(FIRST_BAND));
            while start < ids.len() {
                // Whole levels until the band holds `least` nodes.
                let mut end = start;
                while end < ids.len()
                    && (end - start < least || level(ids[end]) == level(ids[end - 1]))
                {
                    end += 1;
                }
                least = min_band.min(least * BAND_GROWTH);
                let band = &ids[start..end];
                let e = band.iter().map(|&id| parent_error(id)).max().unwrap_or(0);
                let (octave, level) = coarse_first(e, level(ids[start]) as u32);
                out.push((octave, level, part, band.to_vec()));
                start = end;
            }
            out
        })
        .collect();
    bands.sort_by_key(|b| (b.0, b.1, b.2));
    Cut {
        chunks: bands.into_iter().map(|b| b.3).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surfel::Surfel;
    use crate::tree::report::Silent;

    #[test]
    fn ids_sort_by_key_then_id() {
        // Keys with many ties, ids in no order: the ties fall to the id.
        let ids: Vec<u32> = (0..1000u32).map(|i| i.wrapping_mul(7919) % 1000).collect();
        let key = |id: u32| (id.wrapping_mul(31) % 17) as u16;
        let mut sorted = ids.clone();
        sort_by_key_then_id(&mut sorted, key);
        let mut expected = ids;
        expected.sort_by_key(|&id| (key(id), id));
        assert_eq!(sorted, expected);
    }

    fn hierarchy(n: usize) -> Hierarchy {
        let surfels: Vec<Surfel> = (0..n)
            .map(|i| {
                let t = i as f32 * 0.37;
                Surfel {
                    position: Vec3::new(t.sin() * 10.0, t.cos() * 7.0, t * 0.01),
                    ..Zeroable::zeroed()
                }
            })
            .collect();
        crate::tree::hierarchy::build(&surfels, &Silent)
    }

    #[test]
    fn a_cut_partitions_the_ids_into_subtrees_that_fit() {
        let h = hierarchy(5000);
        let cut = cut(&h, 300);
        let mut seen = vec![0u32; h.node_count()];
        for chunk in &cut.chunks {
            for &id in chunk {
                seen[id as usize] += 1;
            }
        }
        assert!(
            seen.iter().all(|&k| k == 1),
            "every node in exactly one chunk"
        );
        assert!(cut.chunks.len() > 10);
        let parents = h.parents();
        for chunk in &cut.chunks[1..] {
            assert!(chunk.len() <= 300);
            // A subtree: exactly one node's parent lies outside the chunk.
            let inside: std::collections::HashSet<u32> = chunk.iter().copied().collect();
            let roots = chunk
                .iter()
                .filter(|&&id| !inside.contains(&parents[id as usize]))
                .count();
            assert_eq!(roots, 1);
        }
        // The top chunk: exactly the nodes with more than 300 nodes below them.
        assert!(cut.chunks[0].contains(&h.root()));
    }

    #[test]
    fn a_small_tree_is_one_chunk() {
        let h = hierarchy(100);
        let cut = cut(&h, 1000);
        assert_eq!(cut.chunks.len(), 1);
        assert_eq!(cut.chunks[0].len(), h.node_count());
    }
}
