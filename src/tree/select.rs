//! The selection of the nodes to draw (docs/design.md §5): the CPU's part each frame (which
//! chunks, and which prefix of each, the GPU tests), and the CPU reference that tests
//! and the renderer's tests use as ground truth.
//!
//! With ε = ε_px · θ (world error per unit of distance; θ = 2 tan(fov/2) / h is the
//! angle of one pixel) and d the distance from the eye to a node's centre, node n is
//! drawn iff
//!
//! ```text
//! e_n ≤ ε · d_n                 (fine enough)
//! ε · (d_n − δ_n) < e_parent(n)   (its parent is not, seen conservatively)
//! ```
//!
//! Every leaf then has a drawn ancestor-or-self: the first node on its path from the
//! root that is fine enough is drawn, because its parent's distance is at least
//! d_n − δ_n. Each chunk of the list ([`super::chunks`]) is sorted by e_parent
//! descending; nodes past the first i with `e_parent[i] ≤ ε · (d_min − Δ[i])` cannot pass
//! the second test (d_min: eye to the box of the chunk's node centres, `Δ[i]`: the
//! largest δ from i to the chunk's end), and that predicate is monotone in i, so a
//! binary search finds the chunk's prefix. Δ is kept per block of [`BLOCK`] nodes of a
//! chunk (the largest δ from the block's start on): a prefix may include up to a block
//! more than needed, never less. With each block's head (its first node's e_parent,
//! the block's largest) the search first finds the block, from the index alone, then
//! the node within it: a bound that reads no node ([`PrefixIndex::ranges_bound`]), for
//! a file streamed from disk, and one block's nodes to make it exact. Chunks outside
//! the view cone are skipped ([`ViewCone`]); the chunks module says why no hole opens
//! across their boundaries.

use std::ops::Range;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::chunks::Chunk;
use super::record::decode;
use super::{NodeRecord, TreeMeta};

mod fit;
mod within;

pub use fit::Fit;

/// Nodes per block of the suffix maximum of δ.
pub const BLOCK: usize = 64;

/// World error per unit of distance for a budget of `eps_px` pixels, with vertical field
/// of view `fov_y` (radians) over `height_px` pixels: ε = ε_px · 2 tan(fov/2) / h.
pub fn error_per_distance(eps_px: f64, fov_y: f64, height_px: u32) -> f64 {
    eps_px * 2.0 * (fov_y / 2.0).tan() / height_px.max(1) as f64
}

/// What the GPU's frustum test sees (`splat_visible` in common.wgsl), relative to the
/// model's origin: a sphere (centre c, radius r) with view coordinates (x, y, depth)
/// is outside when depth + r < near or |x| − r·√(1 + tx²) > tx · depth (and the same in
/// y), tx and ty the tangents of the half fields of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewCone {
    pub eye: DVec3,
    /// Unit view axes: right, up, and forward (toward the target).
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
    pub tan_half_fov: [f64; 2],
    /// √(1 + t²) of each tangent: a sphere's reach across a side plane per unit radius.
    pub secants: [f64; 2],
    pub near: f64,
}

impl ViewCone {
    /// The cone of a view from `eye` along unit axes `[right, up, forward]`, with
    /// tangents `tan_half_fov` of its half fields of view and its near plane.
    pub fn new(
        eye: DVec3,
        [right, up, forward]: [DVec3; 3],
        tan_half_fov: [f64; 2],
        near: f64,
    ) -> Self {
        ViewCone {
            eye,
            right,
            up,
            forward,
            tan_half_fov,
            secants: tan_half_fov.map(|t| (1.0 + t * t).sqrt()),
            near,
        }
    }

    /// Whether a sphere may be seen (false only when the GPU's test would cull every
    /// splat inside it; 10⁻⁴ of slack for its f32 arithmetic).
    pub fn sees_sphere(&self, centre: DVec3, r: f64) -> bool {
        let v = centre - self.eye;
        let (x, y, depth) = (v.dot(self.right), v.dot(self.up), v.dot(self.forward));
        let r = r + 1e-4 * (v.length() + r);
        let ([tx, ty], [sx, sy]) = (self.tan_half_fov, self.secants);
        depth + r >= self.near && x.abs() - r * sx <= tx * depth && y.abs() - r * sy <= ty * depth
    }

    /// Whether any splat of `chunk` may be seen: the sphere around its box of centres,
    /// grown by its largest radius.
    pub fn sees_chunk(&self, chunk: &Chunk) -> bool {
        let lo = Vec3::from(chunk.centre_min).as_dvec3();
        let hi = Vec3::from(chunk.centre_max).as_dvec3();
        let r = 0.5 * (hi - lo).length() + chunk.radius_max as f64;
        self.sees_sphere(0.5 * (lo + hi), r)
    }
}

/// Consecutive chunks per page: a frame tests a page's bounds before its chunks'.
pub const PAGE: usize = 64;

/// A page of [`PAGE`] consecutive chunks (which lie close together: the list orders the
/// chunks of a level band in the hierarchy's spatial order): what a frame tests to skip
/// them all.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Page {
    /// The union of the chunks' boxes, radii and least errors, as one [`Chunk`]: a page
    /// too coarse or unseen has only such chunks.
    bounds: Chunk,
    /// The largest first-block head and first-block δ suffix maximum (each its chunk's
    /// largest e_parent and δ) of the chunks, f16 bits: with the eye at d from the
    /// page's box, every chunk's prefix is empty when head ≤ ε (d − δ) (the block test
    /// of [`PrefixIndex::prefix_bound`] holds for each one's first block).
    head: u16,
    delta: u16,
}

/// The [`Page`] of `chunks`, whose first blocks' heads and δ suffix maxima are
/// `firsts`.
fn page_of(chunks: &[Chunk], firsts: impl Iterator<Item = (u16, u16)>) -> Page {
    let mut bounds = chunks[0];
    for c in &chunks[1..] {
        for k in 0..3 {
            bounds.centre_min[k] = bounds.centre_min[k].min(c.centre_min[k]);
            bounds.centre_max[k] = bounds.centre_max[k].max(c.centre_max[k]);
        }
        bounds.radius_max = bounds.radius_max.max(c.radius_max);
        bounds.error_min = bounds.error_min.min(c.error_min);
    }
    let (head, delta) = firsts.fold((0, 0), |(h, d), (head, delta)| (h.max(head), d.max(delta)));
    Page {
        bounds,
        head,
        delta,
    }
}

/// Distances from `eye` to the nearest and farthest points of a chunk's box of centres.
fn distances(chunk: &Chunk, eye: DVec3) -> (f64, f64) {
    let lo = Vec3::from(chunk.centre_min).as_dvec3();
    let hi = Vec3::from(chunk.centre_max).as_dvec3();
    let far = (eye - lo).abs().max((hi - eye).abs());
    ((eye.clamp(lo, hi) - eye).length(), far.length())
}

/// What the prefix searches need besides the nodes: the chunks and their pages, and
/// per chunk and block of [`BLOCK`] nodes the largest δ from the block's start to the
/// chunk's end ([`chunk_delta_suffix`]) and the block's head ([`block_heads`]). Built
/// from the nodes (one pass), or taken from an `.spt` file that stores it (version 6),
/// so that opening reads no node.
#[derive(Debug, Clone, PartialEq)]
pub struct PrefixIndex {
    chunks: Vec<Chunk>,
    pages: Vec<Page>,
    error_scale: f32,
    /// The suffix maxima of all chunks' blocks, f16 bits of δ / error scale; chunk c's
    /// start at `block_at[c]`.
    delta_suffix: Vec<u16>,
    /// Each block's head: its first node's e_parent (f16 bits), parallel to
    /// `delta_suffix`.
    heads: Vec<u16>,
    block_at: Vec<usize>,
    /// Each chunk's first block's head and δ suffix maximum, decoded, side by side in
    /// chunk order: the test that ends most chunks' searches reads them in sequence
    /// rather than missing the cache in the per-block arrays.
    firsts: Vec<(f64, f64)>,
}

/// The head of every block of [`BLOCK`] nodes of each chunk, chunk after chunk: the
/// parent error (f16 bits) of its first node, the block's largest, since a chunk is
/// sorted by parent error, descending.
pub fn block_heads(chunks: &[Chunk], nodes: &[NodeRecord]) -> Vec<u16> {
    let per_chunk: Vec<Vec<u16>> = chunks
        .par_iter()
        .map(|c| {
            let chunk = &nodes[c.range()];
            chunk.chunks(BLOCK).map(|b| b[0].parent_error).collect()
        })
        .collect();
    per_chunk.concat()
}

/// The suffix maxima of δ over the blocks of [`BLOCK`] nodes of one chunk, as the
/// records store δ (f16 bits, in units of the error scale): entry b is the largest δ
/// from block b's start to the chunk's end. Non-negative halves order as their bits
/// do, so the largest bits are the largest δ (a corrupt negative or NaN δ gives larger
/// bits: a longer prefix, never a shorter one).
pub fn chunk_delta_suffix(nodes: &[NodeRecord]) -> Vec<u16> {
    let mut suffix: Vec<u16> = nodes
        .chunks(BLOCK)
        .map(|block| block.iter().map(|r| r.delta).max().unwrap_or(0))
        .collect();
    to_suffix_maxima(&mut suffix);
    suffix
}

/// Turns a chunk's block maxima into suffix maxima: entry b becomes the largest of
/// entries b and after.
fn to_suffix_maxima(blocks: &mut [u16]) {
    for b in (0..blocks.len().saturating_sub(1)).rev() {
        blocks[b] = blocks[b].max(blocks[b + 1]);
    }
}

/// [`delta_suffix`] and [`block_heads`] made from the nodes fed in list order, a slab
/// at a time (for a writer that streams the list).
pub struct BlockIndexBuilder<'a> {
    chunks: &'a [Chunk],
    /// The chunk the next node belongs to, and the nodes of it fed so far.
    chunk: usize,
    fed: usize,
    /// The current chunk's block maxima so far.
    blocks: Vec<u16>,
    out: Vec<u16>,
    heads: Vec<u16>,
}

impl<'a> BlockIndexBuilder<'a> {
    pub fn new(chunks: &'a [Chunk]) -> Self {
        let blocks = delta_suffix_len(chunks) as usize;
        BlockIndexBuilder {
            chunks,
            chunk: 0,
            fed: 0,
            blocks: Vec::new(),
            out: Vec::with_capacity(blocks),
            heads: Vec::with_capacity(blocks),
        }
    }

    /// Takes the next nodes of the list.
    pub fn feed(&mut self, nodes: &[NodeRecord]) {
        for r in nodes {
            if self.fed.is_multiple_of(BLOCK) {
                self.blocks.push(r.delta);
                self.heads.push(r.parent_error);
            } else {
                let last = self.blocks.last_mut().expect("a block was started");
                *last = (*last).max(r.delta);
            }
            self.fed += 1;
            if self
                .chunks
                .get(self.chunk)
                .is_some_and(|c| self.fed == c.count as usize)
            {
                to_suffix_maxima(&mut self.blocks);
                self.out.append(&mut self.blocks);
                (self.chunk, self.fed) = (self.chunk + 1, 0);
            }
        }
    }

    /// The δ suffix maxima and the block heads of every chunk, once all the nodes were
    /// fed.
    pub fn finish(self) -> (Vec<u16>, Vec<u16>) {
        debug_assert_eq!(self.chunk, self.chunks.len(), "every chunk's nodes fed");
        (self.out, self.heads)
    }
}

/// [`chunk_delta_suffix`] of every chunk, chunk after chunk.
pub fn delta_suffix(chunks: &[Chunk], nodes: &[NodeRecord]) -> Vec<u16> {
    let per_chunk: Vec<Vec<u16>> = chunks
        .par_iter()
        .map(|c| chunk_delta_suffix(&nodes[c.range()]))
        .collect();
    per_chunk.concat()
}

/// Blocks of [`BLOCK`] nodes in the chunks: the length of their δ suffix maxima.
pub fn delta_suffix_len(chunks: &[Chunk]) -> u64 {
    chunks
        .iter()
        .map(|c| (c.count as u64).div_ceil(BLOCK as u64))
        .sum()
}

impl PrefixIndex {
    pub fn new(meta: &TreeMeta, chunks: &[Chunk], nodes: &[NodeRecord]) -> Self {
        let blocks = (delta_suffix(chunks, nodes), block_heads(chunks, nodes));
        Self::with_blocks(meta, chunks, blocks).expect("one per block")
    }

    /// The index of `chunks` with their δ suffix maxima and block heads already made (as
    /// [`delta_suffix`] and [`block_heads`] make them); an error when either is not one
    /// per block.
    pub fn with_blocks(
        meta: &TreeMeta,
        chunks: &[Chunk],
        (delta_suffix, heads): (Vec<u16>, Vec<u16>),
    ) -> Result<Self, String> {
        let expected = delta_suffix_len(chunks);
        if delta_suffix.len() as u64 != expected || heads.len() as u64 != expected {
            return Err(format!(
                "{} δ suffix maxima and {} block heads for {expected} blocks of {BLOCK} nodes",
                delta_suffix.len(),
                heads.len()
            ));
        }
        let mut block_at = Vec::with_capacity(chunks.len());
        let mut at = 0;
        for c in chunks {
            block_at.push(at);
            at += (c.count as usize).div_ceil(BLOCK);
        }
        // A chunk of no node has no block: it adds nothing to its page's largest.
        let first = |c: usize| match chunks[c].count {
            0 => (0, 0),
            _ => (heads[block_at[c]], delta_suffix[block_at[c]]),
        };
        let pages = (0..chunks.len().div_ceil(PAGE))
            .map(|p| {
                let range = p * PAGE..((p + 1) * PAGE).min(chunks.len());
                page_of(&chunks[range.clone()], range.map(first))
            })
            .collect();
        let scale = meta.error_scale;
        let decoded = |(head, delta)| (decode(head, scale), decode(delta, scale));
        let firsts = (0..chunks.len()).map(|c| decoded(first(c))).collect();
        Ok(PrefixIndex {
            chunks: chunks.to_vec(),
            pages,
            error_scale: meta.error_scale,
            delta_suffix,
            heads,
            block_at,
            firsts,
        })
    }

    /// The δ suffix maxima of every chunk, in chunk order (what an `.spt` file stores).
    pub fn delta_suffix(&self) -> &[u16] {
        &self.delta_suffix
    }

    /// The block heads of every chunk, in chunk order (what an `.spt` file stores).
    pub fn block_heads(&self) -> &[u16] {
        &self.heads
    }

    pub fn chunks(&self) -> &[Chunk] {
        &self.chunks
    }

    /// Whether the frame skips every chunk of `page`, seen from `eye`: all too coarse
    /// or unseen ([`PrefixIndex::skipped`]), or all too fine.
    fn page_skipped(&self, page: &Page, eye: DVec3, eps: f64, cone: Option<&ViewCone>) -> bool {
        let d = distances(&page.bounds, eye);
        self.skipped(&page.bounds, d, eps, cone) || self.page_too_fine(page, d.0, eps)
    }

    /// Whether every chunk of `page`, its box `d_min` from the eye, is too fine at
    /// `eps` (each one's prefix empty), and so at any larger ε.
    fn page_too_fine(&self, page: &Page, d_min: f64, eps: f64) -> bool {
        let scale = self.error_scale;
        decode(page.head, scale) <= eps * (d_min - decode(page.delta, scale))
    }

    /// The chunks of page `p`.
    fn page_chunks(&self, p: usize) -> Range<usize> {
        p * PAGE..((p + 1) * PAGE).min(self.chunks.len())
    }

    /// Whether the frame skips `chunk` (or page) whole, its distances from the eye
    /// being `(d_min, d_max)`: too coarse (no node fine enough to draw: e_min > ε ·
    /// d_max), or unseen by `cone`.
    fn skipped(
        &self,
        chunk: &Chunk,
        (_, d_max): (f64, f64),
        eps: f64,
        cone: Option<&ViewCone>,
    ) -> bool {
        let e_min = chunk.error_min as f64 * self.error_scale as f64;
        e_min > eps * d_max || cone.is_some_and(|v| !v.sees_chunk(chunk))
    }

    /// Length of the prefix of chunk `c` that holds every node of it the exact test
    /// can draw.
    pub fn chunk_prefix(&self, c: usize, nodes: &[NodeRecord], eye: DVec3, eps: f64) -> usize {
        let d_min = distances(&self.chunks[c], eye).0;
        self.prefix_within(c, nodes, d_min, eps, self.prefix_bound(c, d_min, eps))
    }

    /// Whether the nodes of chunk `c` from list offset `i` on (within the chunk) fail
    /// the second test, given node i's e_parent bits `e`: e_parent ≤ ε (d_min − Δ(i)).
    fn beyond(&self, c: usize, i: usize, e: u16, d_min: f64, eps: f64) -> bool {
        let delta = self.delta_suffix[self.block_at[c] + i / BLOCK];
        decode(e, self.error_scale) <= eps * (d_min - decode(delta, self.error_scale))
    }

    /// Whether chunk c's first block is beyond (its prefix empty), seen from `d_min`.
    fn first_beyond(&self, c: usize, d_min: f64, eps: f64) -> bool {
        let (head, delta) = self.firsts[c];
        head <= eps * (d_min - delta)
    }

    /// A prefix of chunk `c` (eye at `d_min` from its box) that holds the exact one,
    /// from the index alone: up to the first block whose head is beyond, so at most a
    /// block longer than [`PrefixIndex::chunk_prefix`]. (Every node of a block beyond
    /// is: its e_parent is at most the head's, its Δ the block's.) Most chunks of a
    /// view are drawn from none or all of their blocks: the first and last blocks are
    /// tested before the search between them.
    fn prefix_bound(&self, c: usize, d_min: f64, eps: f64) -> usize {
        let heads = &self.heads[self.block_at[c]..];
        let count = self.chunks[c].count as usize;
        let blocks = count.div_ceil(BLOCK);
        let beyond = |b: usize| self.beyond(c, b * BLOCK, heads[b], d_min, eps);
        if blocks == 0 || self.first_beyond(c, d_min, eps) {
            return 0;
        }
        if !beyond(blocks - 1) {
            return count;
        }
        // The first block beyond lies in [lo, lo + n), from [1, blocks − 1); halving n
        // with a select rather than a branch on the test, whose outcome a CPU cannot
        // predict.
        let (mut lo, mut n) = (1, blocks - 1);
        while n > 1 {
            let half = n / 2;
            lo = if beyond(lo + half - 1) { lo } else { lo + half };
            n -= half;
        }
        (lo * BLOCK).min(count)
    }

    /// The exact prefix of chunk `c`, given its `bound`: a search of the nodes of the
    /// one block before it (the nodes before that block are not beyond).
    fn prefix_within(
        &self,
        c: usize,
        nodes: &[NodeRecord],
        d_min: f64,
        eps: f64,
        bound: usize,
    ) -> usize {
        let chunk = &nodes[self.chunks[c].range()];
        let (mut lo, mut hi) = ((bound.saturating_sub(1) / BLOCK) * BLOCK, bound);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if self.beyond(c, mid, chunk[mid].parent_error, d_min, eps) {
                hi = mid
            } else {
                lo = mid + 1
            }
        }
        lo
    }

    /// The list ranges the GPU tests for a level of detail chosen from `eye` with `eps`:
    /// each chunk's prefix, the chunks too coarse to draw and those that `cone` (when
    /// given) cannot see left out. Non-empty, ascending, adjacent ones joined.
    pub fn ranges(
        &self,
        nodes: &[NodeRecord],
        eye: DVec3,
        eps: f64,
        cone: Option<&ViewCone>,
    ) -> Vec<Range<usize>> {
        self.ranges_refined(nodes, eye, eps, cone, |_| true).1
    }

    /// [`PrefixIndex::ranges`] from the index alone (no node read): each chunk's prefix
    /// rounded up to its block, a superset of the exact ranges.
    pub fn ranges_bound(&self, eye: DVec3, eps: f64, cone: Option<&ViewCone>) -> Vec<Range<usize>> {
        self.prefixes(eye, eps, cone).bounds()
    }

    /// [`PrefixIndex::ranges_bound`] and the ranges with each chunk's prefix exact where
    /// `refine` says so of its bound (a list range) and the bound elsewhere: nodes are
    /// read only there.
    pub fn ranges_refined(
        &self,
        nodes: &[NodeRecord],
        eye: DVec3,
        eps: f64,
        cone: Option<&ViewCone>,
        refine: impl Fn(Range<usize>) -> bool,
    ) -> (Vec<Range<usize>>, Vec<Range<usize>>) {
        let prefixes = self.prefixes(eye, eps, cone);
        (prefixes.bounds(), self.refined(&prefixes, nodes, refine))
    }

    /// The ranges of `prefixes`, each chunk's prefix exact where `refine` says so of
    /// its bound (a list range) and the bound elsewhere: nodes are read only there.
    pub fn refined(
        &self,
        prefixes: &Prefixes,
        nodes: &[NodeRecord],
        refine: impl Fn(Range<usize>) -> bool,
    ) -> Vec<Range<usize>> {
        let Prefixes {
            eps,
            list: prefixes,
        } = prefixes;
        let eps = *eps;
        let exact: Vec<bool> = prefixes
            .iter()
            .map(|p| refine(p.start..p.start + p.bound))
            .collect();
        let lengths: Vec<usize> = prefixes
            .par_chunks(PARALLEL_CHUNKS)
            .zip(exact.par_chunks(PARALLEL_CHUNKS))
            .flat_map_iter(|(group, exact)| self.prefixes_within(group, exact, nodes, eps))
            .collect();
        let mut refined = Vec::new();
        for (p, n) in prefixes.iter().zip(lengths) {
            push_range(&mut refined, p.start, n);
        }
        refined
    }

    /// The chunks the view from `eye` (culled by `cone`) may need at `eps`, with their
    /// prefix bounds. Pages of chunks are searched in parallel: a city tile's view
    /// meets tens of thousands of chunks.
    pub fn prefixes(&self, eye: DVec3, eps: f64, cone: Option<&ViewCone>) -> Prefixes {
        let list = (0..self.pages.len())
            .into_par_iter()
            .filter(|&p| !self.page_skipped(&self.pages[p], eye, eps, cone))
            .flat_map_iter(|p| {
                (self.page_chunks(p)).filter_map(move |c| self.prefix_of(c, eye, eps, cone))
            })
            .collect();
        Prefixes { eps, list }
    }

    /// The prefixes of every chunk seen from `d` away (or farther), without a cone: for
    /// an eye at least `d` from each chunk's box (an instance seen from afar, `d` its
    /// distance to the model's bounding sphere) they hold every node the exact test
    /// draws, since each chunk's own d_min ≥ d and the prefix only grows as d shrinks.
    pub fn prefixes_at(&self, d: f64, eps: f64) -> Prefixes {
        let mut list = Vec::new();
        for (p, page) in self.pages.iter().enumerate() {
            if self.page_too_fine(page, d, eps) {
                continue;
            }
            for c in self.page_chunks(p) {
                if self.first_beyond(c, d, eps) {
                    continue;
                }
                let bound = self.prefix_bound(c, d, eps);
                if bound > 0 {
                    let start = self.chunks[c].start as usize;
                    list.push(Prefix {
                        chunk: c,
                        start,
                        d_min: d,
                        bound,
                    });
                }
            }
        }
        Prefixes { eps, list }
    }

    /// Chunk c's [`Prefix`], when the view may need any of it.
    fn prefix_of(&self, c: usize, eye: DVec3, eps: f64, cone: Option<&ViewCone>) -> Option<Prefix> {
        let chunk = &self.chunks[c];
        let d = distances(chunk, eye);
        // Too fine (an empty prefix) is the cheaper test: before the cone's.
        if self.first_beyond(c, d.0, eps) || self.skipped(chunk, d, eps, cone) {
            return None;
        }
        let bound = self.prefix_bound(c, d.0, eps);
        (bound > 0).then_some(Prefix {
            chunk: c,
            start: chunk.start as usize,
            d_min: d.0,
            bound,
        })
    }
}

/// Chunks a thread of the prefix searches takes at least.
const PARALLEL_CHUNKS: usize = 512;

/// A chunk the view may need: its index, its first node (list index), its distance
/// from the eye, and its prefix bound ([`PrefixIndex::prefix_bound`]).
struct Prefix {
    chunk: usize,
    start: usize,
    d_min: f64,
    bound: usize,
}

/// The chunks a view may need at `eps`, in list order, each with its prefix bound
/// (> 0): what [`PrefixIndex::prefixes`] finds, for [`PrefixIndex::refined`] and
/// the GPU's culling ranges.
pub struct Prefixes {
    eps: f64,
    list: Vec<Prefix>,
}

impl Prefixes {
    /// The ε they were found for.
    pub fn eps(&self) -> f64 {
        self.eps
    }

    /// Their bounds as list ranges ([`PrefixIndex::ranges_bound`]).
    pub fn bounds(&self) -> Vec<Range<usize>> {
        let mut out = Vec::new();
        for p in &self.list {
            push_range(&mut out, p.start, p.bound);
        }
        out
    }
}

/// Appends the range of `n` nodes from `start` to `out` (ascending), joined to the last
/// when adjacent; nothing when `n` is 0.
fn push_range(out: &mut Vec<Range<usize>>, start: usize, n: usize) {
    match out.last_mut() {
        _ if n == 0 => {}
        Some(last) if last.end == start => last.end = start + n,
        _ => out.push(start..start + n),
    }
}

/// Nodes in `ranges`.
pub fn tested(ranges: &[Range<usize>]) -> usize {
    ranges.iter().map(|r| r.len()).sum()
}

/// The exact test for one node, with the eye relative to the origin.
pub fn is_drawn(r: &NodeRecord, error_scale: f32, eye: DVec3, eps: f64) -> bool {
    let d = (r.position().as_dvec3() - eye).length();
    r.error(error_scale) <= eps * d
        && eps * (d - r.delta(error_scale)) < r.parent_error(error_scale)
}

/// A tree's nodes in list order with its prefix index, borrowed from an in-memory list
/// or a memory-mapped file.
pub struct TreeView<'a> {
    pub meta: &'a TreeMeta,
    pub nodes: &'a [NodeRecord],
    pub index: PrefixIndex,
}

/// What one view draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Selection {
    /// The list ranges the CPU hands to the GPU (each chunk's prefix).
    pub ranges: Vec<Range<usize>>,
    /// List indices of the nodes the exact test draws, ascending.
    pub drawn: Vec<u32>,
}

impl Selection {
    /// Nodes the GPU tests.
    pub fn tested(&self) -> usize {
        tested(&self.ranges)
    }
}

impl<'a> TreeView<'a> {
    pub fn new(meta: &'a TreeMeta, nodes: &'a [NodeRecord], chunks: &[Chunk]) -> Self {
        TreeView {
            meta,
            nodes,
            index: PrefixIndex::new(meta, chunks, nodes),
        }
    }

    /// The exact test for node `i` (list index).
    pub fn is_drawn(&self, i: usize, eye: DVec3, eps: f64) -> bool {
        is_drawn(&self.nodes[i], self.meta.error_scale, eye, eps)
    }

    /// The ranges the GPU tests (no frustum: every chunk).
    pub fn ranges(&self, eye: DVec3, eps: f64) -> Vec<Range<usize>> {
        self.index.ranges(self.nodes, eye, eps, None)
    }

    /// The ranges and, by the exact test over the whole list, the drawn nodes.
    pub fn select(&self, eye: DVec3, eps: f64) -> Selection {
        Selection {
            ranges: self.ranges(eye, eps),
            drawn: (0..self.nodes.len())
                .filter(|&i| self.is_drawn(i, eye, eps))
                .map(|i| i as u32)
                .collect(),
        }
    }
}

/// The selection checked over many views.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ViewStats {
    pub views: usize,
    /// Leaves without a drawn ancestor-or-self, summed over the views (must be 0).
    pub holes: u64,
    /// Nodes the exact test draws that lie outside the CPU's ranges, summed (must be 0).
    pub past_prefix: u64,
    /// Mean over views and leaves of the drawn nodes on a leaf's path to the root.
    pub drawn_per_leaf_path: f64,
    /// Mean nodes the GPU tests (in the ranges) and mean nodes drawn.
    pub mean_tested: f64,
    pub mean_drawn: f64,
}

impl ViewStats {
    /// Nodes tested per node drawn, over all views.
    pub fn tested_per_drawn(&self) -> f64 {
        self.mean_tested / self.mean_drawn.max(1e-9)
    }
}

/// Checks the selection for each (eye, ε) pair; `parents` are list indices.
pub fn check_views(view: &TreeView, parents: &[u32], cameras: &[(DVec3, f64)]) -> ViewStats {
    let n = view.nodes.len();
    let mut has_child = vec![false; n];
    for &p in parents {
        if p != u32::MAX {
            has_child[p as usize] = true;
        }
    }
    let leaves: Vec<usize> = (0..n).filter(|&i| !has_child[i]).collect();
    let per_view: Vec<(u64, u64, u64, usize, usize)> = cameras
        .par_iter()
        .map(|&(eye, eps)| {
            let sel = view.select(eye, eps);
            let mut drawn = vec![false; n];
            for &i in &sel.drawn {
                drawn[i as usize] = true;
            }
            let mut in_ranges = vec![false; n];
            for r in &sel.ranges {
                in_ranges[r.clone()].fill(true);
            }
            let past = sel
                .drawn
                .iter()
                .filter(|&&i| !in_ranges[i as usize])
                .count() as u64;
            let (mut holes, mut on_paths) = (0u64, 0u64);
            for &leaf in &leaves {
                let mut k = 0;
                let mut at = leaf as u32;
                loop {
                    k += drawn[at as usize] as u64;
                    at = parents[at as usize];
                    if at == u32::MAX {
                        break;
                    }
                }
                holes += (k == 0) as u64;
                on_paths += k;
            }
            (holes, past, on_paths, sel.tested(), sel.drawn.len())
        })
        .collect();
    let v = cameras.len().max(1) as f64;
    ViewStats {
        views: cameras.len(),
        holes: per_view.iter().map(|r| r.0).sum(),
        past_prefix: per_view.iter().map(|r| r.1).sum(),
        drawn_per_leaf_path: per_view.iter().map(|r| r.2).sum::<u64>() as f64
            / (v * leaves.len().max(1) as f64),
        mean_tested: per_view.iter().map(|r| r.3).sum::<usize>() as f64 / v,
        mean_drawn: per_view.iter().map(|r| r.4).sum::<usize>() as f64 / v,
    }
}

/// `count` reproducible random views of a model: eyes uniform in the box of the node
/// centres grown by `reach` times its size on every side (so some eyes are inside the
/// model's box), ε_px uniform in [0, `max_eps_px`], 60° field of view over 1024 rows.
pub fn random_views(
    meta: &TreeMeta,
    count: usize,
    reach: f64,
    max_eps_px: f64,
    seed: u64,
) -> Vec<(DVec3, f64)> {
    let lo = Vec3::from(meta.centre_min).as_dvec3();
    let hi = Vec3::from(meta.centre_max).as_dvec3();
    let size = (hi - lo).max_element().max(meta.error_scale as f64);
    let (lo, hi) = (
        lo - DVec3::splat(reach * size),
        hi + DVec3::splat(reach * size),
    );
    // xorshift64*: deterministic across machines.
    let mut state = seed.max(1);
    let mut next = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            let eye = lo + (hi - lo) * DVec3::new(next(), next(), next());
            let eps_px = max_eps_px * next();
            (eye, error_per_distance(eps_px, 60f64.to_radians(), 1024))
        })
        .collect()
}
