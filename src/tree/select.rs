//! The selection of the nodes to draw (DESIGN.md §5): the CPU reference that tests and
//! the renderer's tests use as ground truth.
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
//! d_n − δ_n. The list is sorted by e_parent descending; nodes past the first i with
//! e_parent[i] ≤ ε · (d_min − Δ[i]) cannot pass the second test (d_min: eye to the box
//! of all node centres, Δ[i]: the largest δ from i on), and that predicate is monotone
//! in i, so a binary search finds the prefix. Δ is kept per block of [`BLOCK`] nodes
//! (the largest δ from the block's start on): the prefix may include up to a block more
//! than needed, never less.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::{NodeRecord, TreeMeta};

/// Nodes per block of the suffix maximum of δ.
pub const BLOCK: usize = 64;

/// World error per unit of distance for a budget of `eps_px` pixels, with vertical field
/// of view `fov_y` (radians) over `height_px` pixels: ε = ε_px · 2 tan(fov/2) / h.
pub fn error_per_distance(eps_px: f64, fov_y: f64, height_px: u32) -> f64 {
    eps_px * 2.0 * (fov_y / 2.0).tan() / height_px.max(1) as f64
}

/// What the prefix search needs besides the nodes: the box of all node centres and
/// the largest δ (model units) from the start of each block of [`BLOCK`] nodes to the
/// end of the list. Built once per tree (one pass over the nodes).
#[derive(Debug, Clone, PartialEq)]
pub struct PrefixIndex {
    centre_min: DVec3,
    centre_max: DVec3,
    error_scale: f32,
    delta_suffix: Vec<f64>,
}

impl PrefixIndex {
    pub fn new(meta: &TreeMeta, nodes: &[NodeRecord]) -> Self {
        let scale = meta.error_scale;
        let blocks = nodes.len().div_ceil(BLOCK);
        let block_max: Vec<f64> = (0..blocks)
            .into_par_iter()
            .map(|b| {
                let block = &nodes[b * BLOCK..((b + 1) * BLOCK).min(nodes.len())];
                block.iter().map(|r| r.delta(scale)).fold(0.0, f64::max)
            })
            .collect();
        let mut delta_suffix = block_max;
        for b in (0..blocks.saturating_sub(1)).rev() {
            delta_suffix[b] = delta_suffix[b].max(delta_suffix[b + 1]);
        }
        PrefixIndex {
            centre_min: Vec3::from(meta.centre_min).as_dvec3(),
            centre_max: Vec3::from(meta.centre_max).as_dvec3(),
            error_scale: scale,
            delta_suffix,
        }
    }

    /// Distance from `eye` (relative to the origin) to the box of all node centres.
    pub fn min_distance(&self, eye: DVec3) -> f64 {
        (eye.clamp(self.centre_min, self.centre_max) - eye).length()
    }

    /// Length of the prefix of `nodes` that holds every node the exact test can draw.
    pub fn prefix_len(&self, nodes: &[NodeRecord], eye: DVec3, eps: f64) -> usize {
        let d_min = self.min_distance(eye);
        // First i where e_parent[i] ≤ ε (d_min − Δ(i)); false before, true after.
        let beyond = |i: usize| {
            nodes[i].parent_error(self.error_scale) <= eps * (d_min - self.delta_suffix[i / BLOCK])
        };
        let (mut lo, mut hi) = (0, nodes.len());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if beyond(mid) { hi = mid } else { lo = mid + 1 }
        }
        lo
    }
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
    /// Nodes the CPU hands to the GPU (list indices `0..prefix_len`).
    pub prefix_len: usize,
    /// List indices of the nodes the exact test draws, ascending.
    pub drawn: Vec<u32>,
}

impl<'a> TreeView<'a> {
    pub fn new(meta: &'a TreeMeta, nodes: &'a [NodeRecord]) -> Self {
        TreeView {
            meta,
            nodes,
            index: PrefixIndex::new(meta, nodes),
        }
    }

    pub fn min_distance(&self, eye: DVec3) -> f64 {
        self.index.min_distance(eye)
    }

    /// The exact test for node `i` (list index).
    pub fn is_drawn(&self, i: usize, eye: DVec3, eps: f64) -> bool {
        is_drawn(&self.nodes[i], self.meta.error_scale, eye, eps)
    }

    pub fn prefix_len(&self, eye: DVec3, eps: f64) -> usize {
        self.index.prefix_len(self.nodes, eye, eps)
    }

    /// The prefix and, by the exact test over the whole list, the drawn nodes.
    pub fn select(&self, eye: DVec3, eps: f64) -> Selection {
        Selection {
            prefix_len: self.prefix_len(eye, eps),
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
    /// Nodes the exact test draws that lie past the CPU prefix, summed (must be 0).
    pub past_prefix: u64,
    /// Mean over views and leaves of the drawn nodes on a leaf's path to the root.
    pub drawn_per_leaf_path: f64,
    pub mean_prefix_len: f64,
    pub mean_drawn: f64,
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
            let past = sel
                .drawn
                .iter()
                .filter(|&&i| i as usize >= sel.prefix_len)
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
            (holes, past, on_paths, sel.prefix_len, sel.drawn.len())
        })
        .collect();
    let v = cameras.len().max(1) as f64;
    ViewStats {
        views: cameras.len(),
        holes: per_view.iter().map(|r| r.0).sum(),
        past_prefix: per_view.iter().map(|r| r.1).sum(),
        drawn_per_leaf_path: per_view.iter().map(|r| r.2).sum::<u64>() as f64
            / (v * leaves.len().max(1) as f64),
        mean_prefix_len: per_view.iter().map(|r| r.3).sum::<usize>() as f64 / v,
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
