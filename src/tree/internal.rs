//! The internal nodes' records, shapes and attributes from their children's, bottom-up
//! (docs/design.md §3–4).
//!
//! Internal nodes are numbered in post-order ([`hierarchy`](super::hierarchy)): a node's
//! subtree holds the contiguous range of internal ids that ends at the node, and its
//! children's subtrees are consecutive parts of that range, in child order. So a subtree
//! of more than [`PARALLEL_NODES`] internal nodes is filled by filling its children's
//! ranges in parallel (disjoint slices), then the node; a smaller one in one pass in id
//! order, where every child comes before its parent. Each node is computed from its
//! children alone: the result is the same on any number of threads, and a subtree's
//! nodes stay together in memory while they are filled.

use arrayvec::ArrayVec;
use glam::Vec3;
use half::f16;
use rayon::prelude::*;

use super::attributes;
use super::errors::{Disk, Splat, node_error, parent_disk};
use super::hierarchy::{Hierarchy, MAX_CHILDREN};
use super::parent_shape::{Child, parent_shape};
use super::record::{NodeRecord, encode_up};
use super::report::Report;
use crate::io::PointAttributes;
use crate::surfel::field::unit_rgb;
use crate::surfel::shape::{Shape, SplatShape};

/// Subtrees with at most this many internal nodes are filled on one thread.
const PARALLEL_NODES: usize = 1 << 12;

/// A child's record and shape, as its parent reads them.
type Kid = (NodeRecord, SplatShape);

/// The nodes of a range of internal ids, from `first` on: records, shapes and
/// attributes (empty when the model has none).
struct Part<'a> {
    first: usize,
    records: &'a mut [NodeRecord],
    shapes: &'a mut [SplatShape],
    attributes: &'a mut [PointAttributes],
}

impl<'a> Part<'a> {
    /// The same nodes, borrowed for a shorter while.
    fn reborrow(&mut self) -> Part<'_> {
        Part {
            first: self.first,
            records: self.records,
            shapes: self.shapes,
            attributes: self.attributes,
        }
    }

    /// The nodes before internal id `at`, and those from it on.
    fn split_at(self, at: usize) -> (Part<'a>, Part<'a>) {
        let mid = at - self.first;
        let (r0, r1) = self.records.split_at_mut(mid);
        let (s0, s1) = self.shapes.split_at_mut(mid);
        let (a0, a1) = if self.attributes.is_empty() {
            (&mut [][..], &mut [][..])
        } else {
            self.attributes.split_at_mut(mid)
        };
        let head = Part {
            first: self.first,
            records: r0,
            shapes: s0,
            attributes: a0,
        };
        let tail = Part {
            first: at,
            records: r1,
            shapes: s1,
            attributes: a1,
        };
        (head, tail)
    }
}

/// Nodes already filled, read-only: those of a range of ids from `first` on (the
/// leaves: from 0).
#[derive(Clone, Copy)]
struct Filled<'a> {
    first: usize,
    records: &'a [NodeRecord],
    shapes: &'a [SplatShape],
    attributes: &'a [PointAttributes],
}

impl Filled<'_> {
    const NONE: Filled<'static> = Filled {
        first: usize::MAX,
        records: &[],
        shapes: &[],
        attributes: &[],
    };

    /// Node `id`'s index here, when it is here.
    fn index(&self, id: usize) -> Option<usize> {
        id.checked_sub(self.first)
            .filter(|&j| j < self.records.len())
    }
}

impl Part<'_> {
    /// Its nodes, read-only.
    fn filled(&self) -> Filled<'_> {
        Filled {
            first: self.first,
            records: self.records,
            shapes: self.shapes,
            attributes: self.attributes,
        }
    }
}

/// What every part reads: the hierarchy, the leaves' nodes and how errors are computed
/// and reported.
struct Fill<'a> {
    hierarchy: &'a Hierarchy,
    leaves: Filled<'a>,
    /// Each internal node's subtree's first internal id.
    starts: Vec<u32>,
    scale: f32,
    oriented: bool,
    report: &'a dyn Report,
}

/// Fills the internal nodes of `hierarchy`: `records`, `shapes` and `attributes` (empty
/// when the model has none) hold the leaves first, then a slot per internal node.
pub(super) fn fill_internal(
    hierarchy: &Hierarchy,
    (records, shapes, attributes): (&mut [NodeRecord], &mut [SplatShape], &mut [PointAttributes]),
    (scale, oriented): (f32, bool),
    report: &dyn Report,
) {
    let Some(root) = hierarchy.internal.len().checked_sub(1) else {
        return;
    };
    let n = hierarchy.leaf_count as usize;
    let (leaf_records, records) = records.split_at_mut(n);
    let (leaf_shapes, shapes) = shapes.split_at_mut(n);
    let (leaf_attributes, attributes) = attributes.split_at_mut(n.min(attributes.len()));
    let fill = Fill {
        hierarchy,
        leaves: Filled {
            first: 0,
            records: leaf_records,
            shapes: leaf_shapes,
            attributes: leaf_attributes,
        },
        starts: subtree_starts(hierarchy),
        scale,
        oriented,
        report,
    };
    // Internal ids from here on are indices among the internal nodes (id − n).
    let all = Part {
        first: 0,
        records,
        shapes,
        attributes,
    };
    fill.subtree(root, all);
}

/// Each internal node's subtree's first internal id: its own, or that of its first
/// internal child's subtree (post-order).
fn subtree_starts(hierarchy: &Hierarchy) -> Vec<u32> {
    let n = hierarchy.leaf_count;
    let mut starts = Vec::with_capacity(hierarchy.internal.len());
    for (k, node) in hierarchy.internal.iter().enumerate() {
        let first_inner = node.children().iter().find(|&&c| c >= n);
        starts.push(first_inner.map_or(k as u32, |&c| starts[(c - n) as usize]));
    }
    starts
}

impl Fill<'_> {
    /// Fills the subtree of internal node `node`, whose range `part` is.
    fn subtree(&self, node: usize, part: Part) {
        if node + 1 - part.first <= PARALLEL_NODES {
            return self.in_order(part, Filled::NONE);
        }
        let n = self.hierarchy.leaf_count;
        let (mut below, own) = part.split_at(node);
        let mut pieces: Vec<(usize, Part)> = Vec::with_capacity(MAX_CHILDREN);
        let mut rest = below.reborrow();
        for &c in self.hierarchy.internal[node].children() {
            if c >= n {
                let child = (c - n) as usize;
                let (piece, tail) = rest.split_at(child + 1);
                debug_assert_eq!(piece.first, self.starts[child] as usize);
                pieces.push((child, piece));
                rest = tail;
            }
        }
        pieces
            .into_par_iter()
            .for_each(|(child, piece)| self.subtree(child, piece));
        self.in_order(own, below.filled());
    }

    /// Where node `id` (a leaf, or internal) was filled: in `part` (before the one being
    /// filled), in `done`, or among the leaves; and its index there.
    fn find<'a>(&'a self, id: u32, part: Filled<'a>, done: Filled<'a>) -> (Filled<'a>, usize) {
        let n = self.hierarchy.leaf_count as usize;
        let Some(internal) = (id as usize).checked_sub(n) else {
            return (self.leaves, id as usize);
        };
        [part, done]
            .into_iter()
            .find_map(|nodes| nodes.index(internal).map(|j| (nodes, j)))
            .expect("a child is filled before its parent")
    }

    /// Fills the nodes of `part` in id order: each one's children are leaves, nodes of
    /// `done` or come before it in `part`.
    fn in_order(&self, part: Part, done: Filled) {
        for k in 0..part.records.len() {
            let node = &self.hierarchy.internal[part.first + k];
            let mut kids: ArrayVec<Kid, MAX_CHILDREN> = ArrayVec::new();
            let mut weighed: ArrayVec<(PointAttributes, f64), MAX_CHILDREN> = ArrayVec::new();
            for &c in node.children() {
                let (nodes, j) = self.find(c, part.filled(), done);
                let (record, shape) = (nodes.records[j], nodes.shapes[j]);
                kids.push((record, shape));
                if let Some(&a) = nodes.attributes.get(j) {
                    let (r, ratio) = (record.radius() as f64, f16::from_bits(shape.ratio).to_f64());
                    weighed.push((a, r * r * ratio));
                }
            }
            let (record, shape) = internal_record(&kids, self.scale, self.oriented);
            if let Some(slot) = part.attributes.get_mut(k) {
                *slot = attributes::parent_attributes(&weighed);
            }
            part.records[k] = record;
            part.shapes[k] = shape;
        }
        self.report.advance(part.records.len() as u64);
    }
}

/// The record and shape of an internal node from its children's: the parent disk and
/// colour, its ellipse and normal field ([`parent_shape()`]), its radius (the ellipse's
/// major semi-axis) rounded up from f64 so that it still reaches every child, and its
/// error rounded up and never below a child's. The attributes are weighed by each
/// child's splat area r² · ratio ([`attributes::parent_attributes`]).
fn internal_record(kids: &[Kid], scale: f32, oriented: bool) -> (NodeRecord, SplatShape) {
    let k = kids.len();
    let mut disks = [Disk::new(Vec3::ZERO, Vec3::Z, 0.0); MAX_CHILDREN];
    let mut colors = [[0u8; 4]; MAX_CHILDREN];
    let mut children_max = 0;
    for (j, (r, _)) in kids.iter().enumerate() {
        disks[j] = Disk::new(r.position(), r.normal(), r.radius());
        colors[j] = r.color;
        children_max = children_max.max(r.error);
    }
    let (disks, colors) = (&disks[..k], &colors[..k]);
    let (disk, color) = parent_disk(disks, colors, oriented);
    let children: ArrayVec<Child, MAX_CHILDREN> = (kids.iter().zip(disks).zip(colors))
        .map(|(((_, shape), d), rgba)| Child {
            disk: *d,
            shape: shape.unpack(d.n),
            color: unit_rgb(*rgba),
        })
        .collect();
    let (shape, major) = parent_shape(&disk, &children);
    let splat = |disk: Disk, shape: &Shape| Splat {
        disk,
        axis: shape.axis,
        ratio: shape.ratio,
    };
    let splats: ArrayVec<Splat, MAX_CHILDREN> =
        children.iter().map(|c| splat(c.disk, &c.shape)).collect();
    let mut rec = NodeRecord::new(disk.p.as_vec3(), major as f32, disk.n.as_vec3(), color);
    if (rec.radius() as f64) < major {
        rec.radius = f32::from_bits(rec.radius).next_up().to_bits();
    }
    let e = node_error(&splat(Disk { r: major, ..disk }, &shape), &splats);
    rec.error = encode_up(e, scale).max(children_max);
    (rec, shape.pack())
}
