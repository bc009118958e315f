//! Sequential point trees (docs/design.md §3–5): the hierarchy over the leaf surfels, node
//! disks and errors, and the flattened list sorted by parent error that each frame
//! draws a prefix of.
//!
//! ```text
//! LeafSurfels ─► hierarchy::build ─► build_records (disks, errors) ─► sort_list ─► SequentialList
//! ```
//!
//! [`scene`] opens a model from a file (a PLY built through these stages, or an `.spt`
//! file), telling a [`report::Report`] each step.

pub(crate) mod attributes;
pub mod chunks;
pub mod errors;
pub(crate) mod hierarchy;
pub mod instances;
mod internal;
pub mod out_of_core;
pub(crate) mod parent_shape;
pub mod record;
pub mod report;
pub mod scene;
pub mod select;
pub mod spt_file;
pub mod spt_write;
pub mod up;
pub mod validate;

use glam::{DVec3, Vec3};
use half::f16;
use rayon::prelude::*;
use serde::Serialize;

use crate::io::up::UpAxis;
use crate::io::{Bounds, PointAttributes};
use crate::surfel::LeafSurfels;
use crate::surfel::NormalsTurned;
use crate::surfel::Surfel;
use crate::surfel::cloud::Orientation;
use crate::surfel::shape::SplatShape;
use chunks::Chunk;
use hierarchy::Hierarchy;
pub use record::NodeRecord;
use record::encode_up;
use report::{Finished, Report, Silent, Step};

/// What a tree holds besides its nodes (the `.spt` header).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TreeMeta {
    /// Model origin in the file's coordinates: node positions are relative to it.
    pub origin: [f64; 3],
    /// Bounding box of the leaf centres, in the file's coordinates.
    pub bounds: Bounds,
    /// Bounding box of all node centres, relative to `origin` (for the prefix search).
    pub centre_min: [f32; 3],
    pub centre_max: [f32; 3],
    /// Errors and δ are stored divided by this (the size of the model's disks' box).
    pub error_scale: f32,
    pub leaf_count: u64,
    pub node_count: u64,
    /// Largest level (root 0).
    pub depth: u32,
    pub has_colors: bool,
    pub oriented_normals: bool,
    /// Oriented normals whose front is not known (a mesh's open pieces, kept as
    /// wound): drawn two-sided, as unoriented ones are.
    pub two_sided: bool,
    /// Which way the leaves' estimated normals were turned ([`NormalsTurned::No`] when
    /// `oriented_normals`): the builder's decision, on the model's core box.
    pub normals_turned: NormalsTurned,
    /// Whether the nodes carry LiDAR attributes ([`SequentialList::attributes`]).
    pub has_attributes: bool,
    /// The leaves' 1st and 99th intensity percentiles ([`attributes::intensity_range`]).
    pub intensity_range: [u16; 2],
    /// Which way is up ([`up`]); `None`: a sensor frame's view, or z (files written
    /// before the axis was stored).
    pub up: Option<UpAxis>,
}

impl TreeMeta {
    /// Where the sensor of a sensor frame stood, in the file's coordinates: the file's
    /// origin, for a cloud whose estimated normals were turned toward it; `None` for a
    /// mesh, a cloud with given normals, a terrain or any other cloud.
    pub fn sensor(&self) -> Option<DVec3> {
        (self.normals_turned == NormalsTurned::TowardOrigin).then_some(DVec3::ZERO)
    }

    /// Whether the leaves' normals were turned up (a terrain's estimated ones): a
    /// splat's underside is then the ground's, which the renderer weighs as a back.
    pub fn normals_up(&self) -> bool {
        self.normals_turned == NormalsTurned::Up
    }

    /// Whether the leaves' normals are a cloud's estimated ones that no rule turned:
    /// each faces either way, and a splat is drawn from the side the eye sees.
    pub fn normals_unknown(&self) -> bool {
        !self.oriented_normals && self.normals_turned == NormalsTurned::No
    }

    /// Whether the leaf box is a terrain's: less than a quarter as high as it is wide
    /// (the box rule of [`Orientation::of`]), which the default camera sees from
    /// above. A mesh can be flat too; only a cloud's normals are turned up.
    pub fn is_flat(&self) -> bool {
        self.leaf_box_orientation() == Orientation::Up
    }

    /// How the builder turns estimated normals, decided on the leaf box instead of the
    /// core box, seen from the file's origin: what files before version 8, which do not
    /// store [`TreeMeta::normals_turned`], are read with (what the renderer used then).
    pub fn normals_turned_by_leaf_box(&self) -> NormalsTurned {
        if self.oriented_normals {
            return NormalsTurned::No;
        }
        NormalsTurned::of(self.leaf_box_orientation())
    }

    fn leaf_box_orientation(&self) -> Orientation {
        Orientation::of(&self.bounds, &self.bounds, DVec3::from(self.origin))
    }

    /// The description of a tree with nothing in it yet, errors relative to `scale`.
    pub fn empty(error_scale: f32) -> TreeMeta {
        TreeMeta {
            origin: [0.0; 3],
            bounds: Bounds {
                min: [0.0; 3],
                max: [0.0; 3],
            },
            centre_min: [0.0; 3],
            centre_max: [0.0; 3],
            error_scale,
            leaf_count: 0,
            node_count: 0,
            depth: 0,
            has_colors: false,
            oriented_normals: false,
            two_sided: false,
            normals_turned: NormalsTurned::No,
            has_attributes: false,
            intensity_range: [0, 0],
            up: None,
        }
    }
}

/// A tree as built in memory: the nodes in list order (chunk by chunk, each chunk
/// sorted by parent error, descending: [`chunks`]) and each node's parent as a list
/// index (u32::MAX for the root).
#[derive(Debug, Clone, PartialEq)]
pub struct SequentialList {
    pub meta: TreeMeta,
    pub nodes: Vec<NodeRecord>,
    /// Each node's ellipse and normal field, in list order: read by the splat passes
    /// only (the culling pass reads `nodes`).
    pub shapes: Vec<SplatShape>,
    /// Each node's LiDAR attributes, in list order; empty when the model has none
    /// ([`attributes`]): read by the splat passes of the attribute display modes.
    pub attributes: Vec<PointAttributes>,
    pub parents: Vec<u32>,
    /// The chunks, in list order, covering it: the top chunk (with the root) first.
    pub chunks: Vec<Chunk>,
}

/// The hierarchy and its nodes in id order (leaves first, internal in post-order).
pub struct NodeSet {
    pub hierarchy: Hierarchy,
    pub records: Vec<NodeRecord>,
    /// Each node's ellipse and normal field, in the same order.
    pub shapes: Vec<SplatShape>,
    /// Each node's LiDAR attributes, in the same order (empty when the model has none).
    pub attributes: Vec<PointAttributes>,
    /// Parent id of every node (u32::MAX for the root).
    pub parent_ids: Vec<u32>,
    pub meta: TreeMeta,
}

/// Stage 1: the hierarchy, and the order its leaves take the surfels in; `report`
/// hears leaves done.
pub fn build_hierarchy(leaves: &LeafSurfels, report: &dyn Report) -> Hierarchy {
    hierarchy::build(&leaves.surfels, report)
}

/// The size errors are stored relative to: the largest extent of the box holding every
/// leaf disk (> 0 since radii are > 0).
pub fn error_scale(surfels: &[Surfel]) -> f32 {
    let (lo, hi) = surfels
        .par_iter()
        .map(|s| {
            (
                s.position - Vec3::splat(s.radius),
                s.position + Vec3::splat(s.radius),
            )
        })
        .reduce(
            || (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let e = (hi - lo).max_element();
    if e > 0.0 && e.is_finite() { e } else { 1.0 }
}

/// Top-down: each node's parent error (a bit copy), δ rounded up and level; parents
/// read from a snapshot of the internal nodes (ids `n..`) so that every node is
/// written in parallel.
fn link_parents(
    records: &mut [NodeRecord],
    parent_ids: &[u32],
    levels: &[u16],
    n: usize,
    scale: f32,
) {
    let internal: Vec<(u16, Vec3)> = records[n..]
        .par_iter()
        .map(|r| (r.error, r.position()))
        .collect();
    records.par_iter_mut().enumerate().for_each(|(id, r)| {
        r.level = levels[id];
        match parent_ids[id] {
            u32::MAX => {
                r.parent_error = f16::INFINITY.to_bits();
                r.delta = 0;
            }
            p => {
                let (error, position) = internal[p as usize - n];
                r.parent_error = error;
                r.delta = encode_up(
                    (r.position().as_dvec3() - position.as_dvec3()).length(),
                    scale,
                );
            }
        }
    });
}

/// Stage 2: node disks and errors bottom-up, subtrees in parallel
/// ([`internal::fill_internal`]), then each node's parent error, δ and level top-down. `report` hears
/// internal nodes done. Errors are stored relative to the size of the leaves' box.
pub fn build_records(leaves: LeafSurfels, hierarchy: Hierarchy, report: &dyn Report) -> NodeSet {
    let scale = error_scale(&leaves.surfels);
    build_records_scaled(leaves, hierarchy, scale, report)
}

/// Grows the leaves' records, shapes and attributes (empty when the model has none) to
/// the hierarchy's nodes, fills the internal ones ([`internal::fill_internal`]) and links every
/// node to its parent ([`link_parents`]); returns each node's level and parent id.
fn complete_internal(
    hierarchy: &Hierarchy,
    (records, shapes, attributes): (
        &mut Vec<NodeRecord>,
        &mut Vec<SplatShape>,
        &mut Vec<PointAttributes>,
    ),
    (scale, oriented): (f32, bool),
    report: &dyn Report,
) -> (Vec<u16>, Vec<u32>) {
    let n = records.len();
    let total = hierarchy.node_count();
    grow_to(
        records,
        total,
        NodeRecord::new(Vec3::ZERO, 0.0, Vec3::Z, [0; 4]),
    );
    grow_to(shapes, total, SplatShape::circle(Vec3::Z));
    if !attributes.is_empty() {
        grow_to(attributes, total, PointAttributes::default());
    }
    let levels = hierarchy.levels();
    let slices = (&mut records[..], &mut shapes[..], &mut attributes[..]);
    internal::fill_internal(hierarchy, slices, (scale, oriented), report);
    let parent_ids = hierarchy.parents();
    link_parents(records, &parent_ids, &levels, n, scale);
    (levels, parent_ids)
}

/// `list` grown to `len` with copies of `value`, written on every core (a serial
/// `resize` of the Lucy-size cloud's internal slots took 0.2 s on one thread).
fn grow_to<T: Copy + Send + Sync>(list: &mut Vec<T>, len: usize, value: T) {
    let more = len.saturating_sub(list.len());
    list.par_extend(rayon::iter::repeat_n(value, more));
}

/// The nodes above subtrees built apart (the top tree of an out-of-core build): given
/// the subtrees' roots (records, shapes, attributes: empty when the model has none) as
/// the leaves of `hierarchy`, the internal nodes' records as [`build_records`] makes
/// them, then every node's parent error, δ and level, the roots' included. Returns the
/// nodes in id order (the roots first) and each one's parent id.
pub fn build_above(
    hierarchy: Hierarchy,
    (mut records, mut shapes, mut attributes): (
        Vec<NodeRecord>,
        Vec<SplatShape>,
        Vec<PointAttributes>,
    ),
    (scale, oriented): (f32, bool),
) -> NodeSet {
    let nodes = (&mut records, &mut shapes, &mut attributes);
    let (_, parent_ids) = complete_internal(&hierarchy, nodes, (scale, oriented), &Silent);
    NodeSet {
        hierarchy,
        records,
        shapes,
        attributes,
        parent_ids,
        meta: TreeMeta::empty(scale),
    }
}

/// [`build_records`] with errors stored relative to `scale` (> 0).
pub fn build_records_scaled(
    leaves: LeafSurfels,
    mut hierarchy: Hierarchy,
    scale: f32,
    report: &dyn Report,
) -> NodeSet {
    let n = leaves.surfels.len();
    let (oriented, normals_turned) = (leaves.oriented_normals, leaves.normals_turned);
    let two_sided = leaves.two_sided;
    let bounds = leaf_bounds(&leaves);
    // Leaf id k is surfel leaf_order[k]: the leaves' records in id order.
    let in_leaf_order = std::mem::take(&mut hierarchy.leaf_order);
    let leaf = |k: &u32| &leaves.surfels[*k as usize];
    let total = hierarchy.node_count();
    // Room for every node at once: the internal slots are added without a copy.
    let mut leaf_nodes = (Vec::with_capacity(total), Vec::with_capacity(total));
    leaf_nodes.par_extend(in_leaf_order.par_iter().map(|k| {
        let s = leaf(k);
        let rec = NodeRecord::new(s.position, s.radius, s.normal, s.color);
        (rec, s.shape)
    }));
    let (mut records, mut shapes): (Vec<NodeRecord>, Vec<SplatShape>) = leaf_nodes;
    let mut attributes: Vec<PointAttributes> = if leaves.has_attributes {
        let mut a = Vec::with_capacity(total);
        a.par_extend(in_leaf_order.par_iter().map(|k| leaf(k).attributes));
        a
    } else {
        Vec::new()
    };
    drop(in_leaf_order);
    drop(leaves.surfels);
    let nodes = (&mut records, &mut shapes, &mut attributes);
    let (levels, parent_ids) = complete_internal(&hierarchy, nodes, (scale, oriented), report);
    let depth = levels.iter().copied().max().unwrap_or(0);
    let (centre_min, centre_max) = records
        .par_iter()
        .map(|r| (r.position(), r.position()))
        .reduce(
            || (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let meta = TreeMeta {
        origin: bounds.1.to_array(),
        bounds: bounds.0,
        centre_min: centre_min.to_array(),
        centre_max: centre_max.to_array(),
        error_scale: scale,
        leaf_count: n as u64,
        node_count: records.len() as u64,
        depth: depth as u32,
        has_colors: bounds.2,
        oriented_normals: oriented,
        two_sided,
        normals_turned,
        has_attributes: !attributes.is_empty(),
        intensity_range: attributes::intensity_range(attributes.get(..n).unwrap_or(&[])),
        up: None,
    }
    .with_file_up(None);
    NodeSet {
        hierarchy,
        records,
        shapes,
        attributes,
        parent_ids,
        meta,
    }
}

/// Bounding box of the leaf centres in file coordinates, the origin, and has_colors.
fn leaf_bounds(leaves: &LeafSurfels) -> (Bounds, DVec3, bool) {
    let (lo, hi) = leaves
        .surfels
        .par_iter()
        .map(|s| (s.position, s.position))
        .reduce(
            || (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let o = leaves.origin;
    let bounds = Bounds {
        min: (lo.as_dvec3() + o).to_array(),
        max: (hi.as_dvec3() + o).to_array(),
    };
    (bounds, o, leaves.has_colors)
}

/// Stage 3: the sequential list: the tree cut into chunks ([`chunks::cut`]), each
/// sorted by parent error descending (ties by node id, so the order is the same on
/// every machine), with parents as list indices.
pub fn sort_list(set: NodeSet) -> SequentialList {
    let max_nodes = chunks::chunk_nodes_for(set.records.len());
    sort_list_chunked(set, max_nodes)
}

/// [`sort_list`] with subtrees of at most `max_nodes` nodes ([`chunks::cut`]).
pub fn sort_list_chunked(set: NodeSet, max_nodes: usize) -> SequentialList {
    order_list(set, max_nodes).gather()
}

/// A tree's nodes in id order with the order of its list (stage 3 before the nodes
/// move): what [`OrderedSet::gather`] sorts in memory, and what
/// [`spt_write::write_ordered`] writes without ever holding the list sorted.
pub struct OrderedSet {
    pub meta: TreeMeta,
    /// Records, shapes and attributes (empty when the model has none) in id order.
    pub records: Vec<NodeRecord>,
    pub shapes: Vec<SplatShape>,
    pub attributes: Vec<PointAttributes>,
    /// The node at each list position.
    pub order: Vec<u32>,
    /// Each node's parent as a list index, in list order (u32::MAX for the root).
    pub parents: Vec<u32>,
    /// The chunks, in list order.
    pub chunks: Vec<Chunk>,
}

/// The order of `set`'s list: the tree cut into chunks of at most `max_nodes` nodes,
/// each sorted by parent error descending (ties by id), and the chunk table.
pub fn order_list(set: NodeSet, max_nodes: usize) -> OrderedSet {
    let NodeSet {
        hierarchy,
        records,
        shapes,
        attributes,
        parent_ids,
        meta,
    } = set;
    let cut = chunks::cut(&hierarchy, max_nodes);
    drop(hierarchy);
    let mut cut = chunks::by_level(
        cut,
        max_nodes / 16,
        |id| records[id as usize].level,
        |id| records[id as usize].parent_error,
    );
    cut.chunks.par_iter_mut().for_each(|ids| {
        chunks::sort_by_key_then_id(ids, |id| 0xffff - records[id as usize].parent_error)
    });
    let counts: Vec<usize> = cut.chunks.iter().map(Vec::len).collect();
    let order: Vec<u32> = cut.chunks.concat();
    drop(cut);
    let mut position = vec![0u32; order.len()];
    for (i, &id) in order.iter().enumerate() {
        position[id as usize] = i as u32;
    }
    let parents = order
        .par_iter()
        .map(|&id| match parent_ids[id as usize] {
            u32::MAX => u32::MAX,
            p => position[p as usize],
        })
        .collect();
    let chunks = Chunk::table_of(&counts, |range| gather(&records, &order[range]));
    OrderedSet {
        meta,
        records,
        shapes,
        attributes,
        order,
        parents,
        chunks,
    }
}

/// `values` at `ids`, in that order.
pub fn gather<T: Copy + Send + Sync>(values: &[T], ids: &[u32]) -> Vec<T> {
    let mut out = Vec::new();
    gather_into(values, ids, &mut out);
    out
}

/// [`gather`] into `out`, whose allocation is reused when it is large enough.
pub fn gather_into<T: Copy + Send + Sync>(values: &[T], ids: &[u32], out: &mut Vec<T>) {
    ids.par_iter()
        .map(|&id| values[id as usize])
        .collect_into_vec(out);
}

impl OrderedSet {
    /// The list in memory: each array moved into list order, one at a time.
    pub fn gather(self) -> SequentialList {
        let OrderedSet {
            meta,
            records,
            shapes,
            attributes,
            order,
            parents,
            chunks,
        } = self;
        let nodes = gather(&records, &order);
        drop(records);
        let shapes = gather(&shapes, &order);
        let attributes = if attributes.is_empty() {
            Vec::new()
        } else {
            gather(&attributes, &order)
        };
        SequentialList {
            meta,
            nodes,
            shapes,
            attributes,
            parents,
            chunks,
        }
    }
}

/// All three stages, each told to `report` as a [`Step`] with what it made.
pub fn build_list(leaves: LeafSurfels, report: &dyn Report) -> SequentialList {
    build_ordered(leaves, report).gather()
}

/// All three stages, up to the list's order ([`order_list`]): its nodes not yet
/// moved, for [`spt_write::write_ordered`].
pub fn build_ordered(mut leaves: LeafSurfels, report: &dyn Report) -> OrderedSet {
    leaves.drop_redundant();
    let n = leaves.surfels.len() as u64;
    report.step(Step::Hierarchy, n);
    let hierarchy = build_hierarchy(&leaves, report);
    let internal = hierarchy.internal.len() as u64;
    report.finished(Finished::Hierarchy {
        leaves: n,
        internal,
    });
    report.step(Step::Errors, internal);
    let set = build_records(leaves, hierarchy, report);
    report.finished(Finished::Errors(&set.meta));
    report.step(Step::Sort, 0);
    let max_nodes = chunks::chunk_nodes_for(set.records.len());
    let ordered = order_list(set, max_nodes);
    report.finished(Finished::Sort {
        nodes: ordered.order.len() as u64,
    });
    ordered
}

/// All three stages, silently.
pub fn build_sequential_list(leaves: LeafSurfels) -> SequentialList {
    build_list(leaves, &Silent)
}
