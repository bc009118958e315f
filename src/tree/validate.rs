//! What every sequential list satisfies, checked on lists read from files (a file whose
//! checksum holds may still have been written by something else) and by the tests and
//! the fuzzer on lists just built.
//!
//! * [`check_meta`]: origin, bounds and the node-centre box finite, boxes not inverted,
//!   error scale finite and > 0.
//! * [`check_nodes`], per node: finite position inside the node-centre box, finite
//!   radius > 0, errors (e, e_parent, δ) not NaN and ≥ 0, e finite, e ≤ e_parent, parent
//!   index in range. Local checks only: O(n), in parallel, no random access.
//! * [`check_structure`]: the list as a tree: one root, first, with e_parent = +∞ and
//!   δ = 0; each node's e_parent a bit copy of its parent's e and its level one more;
//!   δ ≥ the distance to the parent; each chunk sorted by e_parent, descending.
//! * [`check_chunk_table`]: the chunks follow each other from 0 and cover the list,
//!   each non-empty, with a finite box, largest radius and least error (≥ 0).
//! * [`check_chunks`]: that, and each node's centre lies in its chunk's box, its radius
//!   is at most the chunk's largest (what culling chunks by the frustum relies on), and
//!   its error and level are at least the chunk's least (what skipping a chunk too
//!   coarse for the frame relies on).

use rayon::prelude::*;

use super::chunks::Chunk;
use super::record::half_value;
use super::{NodeRecord, TreeMeta};

fn finite3_f64(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Whether `lo` … `hi` is a finite box, not inverted.
fn finite_box(lo: [f32; 3], hi: [f32; 3]) -> bool {
    (0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k])
}

/// The header fields of a list.
pub fn check_meta(meta: &TreeMeta) -> Result<(), String> {
    let b = &meta.bounds;
    if !finite3_f64(&meta.origin) {
        return Err(format!("origin {:?} is not finite", meta.origin));
    }
    if !finite3_f64(&b.min) || !finite3_f64(&b.max) || (0..3).any(|k| b.min[k] > b.max[k]) {
        return Err(format!(
            "bounds {:?} … {:?} are not a finite box",
            b.min, b.max
        ));
    }
    let (lo, hi) = (meta.centre_min, meta.centre_max);
    if !finite_box(lo, hi) {
        return Err(format!(
            "node-centre box {lo:?} … {hi:?} is not a finite box"
        ));
    }
    let s = meta.error_scale;
    if !(s.is_finite() && s > 0.0) {
        return Err(format!("error scale {s} is not finite and > 0"));
    }
    Ok(())
}

/// What is wrong with node `r` on its own, if anything.
fn node_problem(meta: &TreeMeta, r: &NodeRecord, parent: u32, count: usize) -> Option<String> {
    let p = r.position();
    let (lo, hi) = (meta.centre_min, meta.centre_max);
    if !p.is_finite() || (0..3).any(|k| p[k] < lo[k] || p[k] > hi[k]) {
        return Some(format!(
            "position {p} is not finite or outside the node-centre box"
        ));
    }
    let radius = r.radius();
    if !(radius.is_finite() && radius > 0.0) {
        return Some(format!("radius {radius} is not finite and > 0"));
    }
    let (e, ep, d) = (
        half_value(r.error),
        half_value(r.parent_error),
        half_value(r.delta),
    );
    if !(e.is_finite() && e >= 0.0 && ep >= 0.0 && d >= 0.0 && !d.is_infinite()) {
        return Some(format!("errors e {e}, e_parent {ep}, δ {d} out of range"));
    }
    if e > ep {
        return Some(format!("error {e} above its parent's {ep}"));
    }
    if parent != u32::MAX && parent as usize >= count {
        return Some(format!("parent index {parent} beyond the {count} nodes"));
    }
    None
}

/// Per-node checks of `nodes` (with their `parents`); the first failing node is named.
pub fn check_nodes(meta: &TreeMeta, nodes: &[NodeRecord], parents: &[u32]) -> Result<(), String> {
    if nodes.len() != parents.len() {
        return Err(format!(
            "{} nodes but {} parent indices",
            nodes.len(),
            parents.len()
        ));
    }
    let bad = nodes
        .par_iter()
        .zip(parents)
        .enumerate()
        .find_first(|(_, (r, p))| node_problem(meta, r, **p, nodes.len()).is_some());
    match bad {
        None => Ok(()),
        Some((i, (r, p))) => Err(format!(
            "node {i}: {}",
            node_problem(meta, r, *p, nodes.len()).unwrap_or_default()
        )),
    }
}

/// The chunk table on its own: non-empty chunks that follow each other and cover the
/// `node_count` nodes of the list, each with a finite box (not inverted), largest
/// radius and least error, both ≥ 0 (what opening a file to stream it checks).
pub fn check_chunk_table(chunks: &[Chunk], node_count: u64) -> Result<(), String> {
    let mut at = 0u64;
    for (c, chunk) in chunks.iter().enumerate() {
        if chunk.start != at || chunk.count == 0 {
            return Err(format!(
                "chunk {c} starts at {} with {} nodes; expected a non-empty chunk at {at}",
                chunk.start, chunk.count
            ));
        }
        if let Some(what) = chunk_bounds_problem(chunk) {
            return Err(format!("chunk {c}: {what}"));
        }
        at += chunk.count as u64;
        if at > node_count {
            return Err(format!(
                "chunk {c} ends at {at}, past the {node_count} nodes"
            ));
        }
    }
    if at != node_count {
        return Err(format!("the chunks cover {at} of the {node_count} nodes"));
    }
    Ok(())
}

/// What is wrong with a chunk's box, largest radius or least error on their own.
fn chunk_bounds_problem(chunk: &Chunk) -> Option<String> {
    let (lo, hi) = (chunk.centre_min, chunk.centre_max);
    if !finite_box(lo, hi) {
        return Some(format!("box {lo:?} … {hi:?} is not a finite box"));
    }
    let (r, e) = (chunk.radius_max, chunk.error_min);
    if !(r.is_finite() && r >= 0.0 && e.is_finite() && e >= 0.0) {
        return Some(format!(
            "largest radius {r} or least error {e} is not finite and ≥ 0"
        ));
    }
    None
}

/// The chunk table against the nodes (module doc): [`check_chunk_table`], and every
/// node within its chunk's box and largest radius, at or above its least error and
/// level. The chunks are checked in parallel, each one's nodes in turn (a parallel
/// search within each of the Lucy-size model's 9,305 chunks took 0.54 s, this 0.02 s).
pub fn check_chunks(nodes: &[NodeRecord], chunks: &[Chunk]) -> Result<(), String> {
    check_chunk_table(chunks, nodes.len() as u64)?;
    let first_outside = chunks.par_iter().enumerate().find_map_first(|(c, chunk)| {
        let range = chunk.range();
        let start = range.start;
        nodes[range]
            .iter()
            .position(|r| !within(chunk, r))
            .map(|i| (c, start + i))
    });
    match first_outside {
        None => Ok(()),
        Some((c, i)) => Err(format!(
            "node {i}: outside the box of its chunk {c}, or above its largest radius, or \
             below its least error or level"
        )),
    }
}

/// Whether node `r` lies within `chunk`'s box and largest radius, at or above its least
/// error and level.
fn within(chunk: &Chunk, r: &NodeRecord) -> bool {
    let (lo, hi) = (chunk.centre_min, chunk.centre_max);
    let p = r.position();
    (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k])
        && r.radius() <= chunk.radius_max
        && half_value(r.error) >= chunk.error_min
        && u32::from(r.level) >= chunk.level
}

/// The list as a tree (module doc). Assumes [`check_nodes`] and [`check_chunks`] passed.
pub fn check_structure(
    meta: &TreeMeta,
    nodes: &[NodeRecord],
    parents: &[u32],
    chunks: &[Chunk],
) -> Result<(), String> {
    let mut chunk_start = vec![false; nodes.len()];
    for c in chunks {
        chunk_start[c.start as usize] = true;
    }
    let roots = parents.iter().filter(|&&p| p == u32::MAX).count();
    if roots != 1 || parents.first() != Some(&u32::MAX) {
        return Err(format!("{roots} roots; the root must be alone and first"));
    }
    let root = &nodes[0];
    if !half_value(root.parent_error).is_infinite() || root.delta != 0 {
        return Err("the root's parent error is not +∞ or its δ is not 0".to_owned());
    }
    let scale = meta.error_scale;
    for (i, (r, &p)) in nodes.iter().zip(parents).enumerate().skip(1) {
        if !chunk_start[i] && r.parent_error > nodes[i - 1].parent_error {
            return Err(format!("node {i}: its chunk is not sorted by parent error"));
        }
        let parent = &nodes[p as usize];
        if r.parent_error != parent.error || r.level != parent.level.wrapping_add(1) {
            return Err(format!(
                "node {i}: parent error or level does not match its parent {p}"
            ));
        }
        let d = (r.position().as_dvec3() - parent.position().as_dvec3()).length();
        if r.delta(scale) < d {
            return Err(format!(
                "node {i}: δ {} below the distance {d} to its parent",
                r.delta(scale)
            ));
        }
    }
    Ok(())
}
