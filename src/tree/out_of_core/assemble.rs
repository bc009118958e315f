//! The end of an out-of-core build: the top tree over the jobs' subtrees, and the file.
//!
//! The jobs' split is a binary tree whose leaves are the jobs: it is the top tree's
//! hierarchy, its leaves the subtrees' roots ([`crate::tree::build_above`] makes the
//! internal nodes' records, errors and shapes from the roots', and gives each root its
//! parent error, δ and level). The file lists the top tree's internal nodes first (one
//! chunk, sorted by parent error, the root first), then the jobs' chunks interleaved
//! coarse first ([`super::order`]), each as its part file holds it, with its nodes'
//! levels shifted by its root's, its parent indices and start moved to their places in
//! the file, and each part's root record replaced by the linked one. The sections are
//! streamed from the part files, read ahead of the writes ([`super::read_ahead`]), and
//! hashed as they are written; the header, known before, gets the checksum last.

use glam::Vec3;

use super::Progress;
use super::job::{Model, Part};
use super::order::Layout;
use super::read_ahead::{AfterRead, PartFile, Span, read_buffer, stream};
use super::spill::Split;
use crate::io::PointAttributes;
use crate::surfel::NormalsTurned;
use crate::surfel::shape::SplatShape;
use crate::tree::chunks::Chunk;
use crate::tree::hierarchy::{Hierarchy, Internal};
use crate::tree::select::BlockIndexBuilder;
use crate::tree::spt_file::{file_bytes, header_for};
use crate::tree::spt_write::{Hashed, write_hashed};
use crate::tree::{NodeRecord, TreeMeta, attributes, build_above};

/// The top tree in file order, and how each part joins it.
struct Top {
    records: Vec<NodeRecord>,
    shapes: Vec<SplatShape>,
    attributes: Vec<PointAttributes>,
    parents: Vec<u32>,
    /// Per part: its root's linked record and its root's parent (a top list index).
    roots: Vec<(NodeRecord, u32)>,
}

/// The split as a hierarchy whose leaves are the jobs (internal nodes in post-order).
fn hierarchy_of(split: &Split, jobs: usize) -> Hierarchy {
    fn walk(s: &Split, jobs: u32, out: &mut Vec<Internal>) -> u32 {
        match s {
            Split::Job(j) => *j as u32,
            Split::Node(a, b) => {
                let (a, b) = (walk(a, jobs, out), walk(b, jobs, out));
                out.push(Internal {
                    children: [a, b, 0, 0],
                    child_count: 2,
                });
                jobs + out.len() as u32 - 1
            }
        }
    }
    let mut internal = Vec::new();
    walk(split, jobs as u32, &mut internal);
    Hierarchy {
        leaf_count: jobs as u32,
        internal,
        leaf_order: (0..jobs as u32).collect(),
    }
}

fn top_tree(split: &Split, parts: &[Part], model: &Model, oriented: bool) -> Top {
    let j = parts.len();
    let roots = (
        parts.iter().map(|p| p.root.0).collect(),
        parts.iter().map(|p| p.root.1).collect(),
        if model.has_attributes {
            parts.iter().map(|p| p.root.2).collect()
        } else {
            Vec::new()
        },
    );
    let set = build_above(hierarchy_of(split, j), roots, (model.error_scale, oriented));
    // The internal nodes, sorted by parent error (the root, +∞, first).
    let mut order: Vec<usize> = (j..set.records.len()).collect();
    order.sort_by_key(|&id| (0xffff - set.records[id].parent_error, id));
    let mut position = vec![u32::MAX; set.records.len()];
    for (k, &id) in order.iter().enumerate() {
        position[id] = k as u32;
    }
    let parent_at = |id: usize| match set.parent_ids[id] {
        u32::MAX => u32::MAX,
        p => position[p as usize],
    };
    Top {
        records: order.iter().map(|&id| set.records[id]).collect(),
        shapes: order.iter().map(|&id| set.shapes[id]).collect(),
        attributes: if model.has_attributes {
            order.iter().map(|&id| set.attributes[id]).collect()
        } else {
            Vec::new()
        },
        parents: order.iter().map(|&id| parent_at(id)).collect(),
        roots: (0..j).map(|k| (set.records[k], parent_at(k))).collect(),
    }
}

/// The meta of the whole tree.
fn meta(model: &Model, parts: &[Part], top: &Top, (oriented, two_sided): (bool, bool)) -> TreeMeta {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for p in parts {
        lo = lo.min(p.centre_min);
        hi = hi.max(p.centre_max);
    }
    for r in &top.records {
        lo = lo.min(r.position());
        hi = hi.max(r.position());
    }
    let samples: Vec<PointAttributes> = parts.iter().flat_map(|p| p.intensities.clone()).collect();
    let level = |k: usize| top.roots.get(k).map_or(0, |r| r.0.level as u32);
    TreeMeta {
        origin: model.origin.to_array(),
        bounds: model.bounds,
        centre_min: lo.to_array(),
        centre_max: hi.to_array(),
        error_scale: model.error_scale,
        leaf_count: parts.iter().map(|p| p.leaves).sum(),
        node_count: top.records.len() as u64 + parts.iter().map(|p| p.nodes).sum::<u64>(),
        depth: (0..parts.len())
            .map(|k| parts[k].depth + level(k))
            .max()
            .unwrap_or(0),
        has_colors: model.has_colors,
        oriented_normals: oriented,
        two_sided,
        normals_turned: normals_turned(parts, oriented),
        has_attributes: model.has_attributes,
        intensity_range: attributes::intensity_range(&samples),
        up: None,
    }
    .with_file_up(model.up)
}

/// How the jobs turned their estimated normals: alike, as all decide on the model's
/// core box, but a job whose points all had given normals turned none (`No` where
/// every job's were given: `oriented`).
fn normals_turned(parts: &[Part], oriented: bool) -> NormalsTurned {
    if oriented {
        return NormalsTurned::No;
    }
    (parts.iter().map(|p| p.normals_turned))
        .find(|&t| t != NormalsTurned::No)
        .unwrap_or_default()
}

/// Writes the `.spt` file of the jobs' `parts`, joined by the top tree of `split`,
/// atomically, flagged `two_sided` (an open mesh, [`TreeMeta::two_sided`]), its size and
/// then its bytes as they go told to `progress`, the parts' bytes kept or freed once
/// read (`after`); returns its meta.
pub fn write_file(
    path: &std::path::Path,
    model: &Model,
    (split, parts, after): (&Split, &[Part], AfterRead),
    (two_sided, progress): (bool, &dyn Progress),
) -> anyhow::Result<TreeMeta> {
    let oriented = parts.iter().all(|p| p.oriented);
    let top = if parts.len() > 1 {
        top_tree(split, parts, model, oriented)
    } else {
        let root = parts[0].root.0;
        Top {
            records: Vec::new(),
            shapes: Vec::new(),
            attributes: Vec::new(),
            parents: Vec::new(),
            roots: vec![(root, u32::MAX)],
        }
    };
    let meta = meta(model, parts, &top, (oriented, two_sided));
    let layout = layout(parts, &top, &part_tables(parts, model.has_attributes)?);
    let chunks = chunk_table(&layout, &top);
    let header = header_for(&meta, &chunks, 0);
    progress.writing(file_bytes(&meta, &chunks));
    write_hashed(path, &header, &|n| progress.advance(n), |out| {
        let files = parts.iter().map(|p| PartFile::open_for_join(p, after));
        let mut files: Vec<PartFile> = files.collect::<Result<_, _>>()?;
        write_sections(
            out,
            (&mut files, parts, &layout),
            &top,
            (&chunks, model.has_attributes),
        )
    })?;
    Ok(meta)
}

/// Offsets in a part file of `n` nodes of its parents, shapes, attributes and chunks.
fn part_offsets(n: u64, has_attributes: bool) -> (u64, u64, u64, u64) {
    let record = std::mem::size_of::<NodeRecord>() as u64;
    let shape = std::mem::size_of::<SplatShape>() as u64;
    let attribute = std::mem::size_of::<PointAttributes>() as u64;
    let parents = n * record;
    let shapes = parents + 4 * n;
    let attributes = shapes + n * shape;
    let chunks = attributes + if has_attributes { n * attribute } else { 0 };
    (parents, shapes, attributes, chunks)
}

/// Each part's chunk table as its part file holds it.
fn part_tables(parts: &[Part], has_attributes: bool) -> std::io::Result<Vec<Vec<Chunk>>> {
    let mut buffer = read_buffer();
    parts
        .iter()
        .map(|p| {
            let at = part_offsets(p.nodes, has_attributes).3;
            let mut table = vec![<Chunk as bytemuck::Zeroable>::zeroed(); p.chunks as usize];
            let into = bytemuck::cast_slice_mut(&mut table);
            PartFile::open(p)?.read_at((Some(at), 0), into, &mut buffer)?;
            Ok(table)
        })
        .collect()
}

/// Where the parts' chunks go ([`Layout::plan`]): each part's root chunk keyed by the
/// root's parent error in the top tree.
fn layout(parts: &[Part], top: &Top, tables: &[Vec<Chunk>]) -> Layout {
    let keys: Vec<Vec<u16>> = parts
        .iter()
        .zip(&top.roots)
        .map(|(p, (root, _))| {
            let mut keys = p.chunk_keys.clone();
            keys[0] = root.parent_error;
            keys
        })
        .collect();
    let shifts: Vec<u32> = top.roots.iter().map(|r| r.0.level as u32).collect();
    Layout::plan(top.records.len() as u64, tables, &keys, &shifts)
}

/// The whole file's chunk table: the top tree's chunk, then the parts' chunks at their
/// places in the list and below their root's level.
fn chunk_table(layout: &Layout, top: &Top) -> Vec<Chunk> {
    let mut chunks: Vec<Chunk> = Vec::with_capacity(layout.pieces.len() + 1);
    if !top.records.is_empty() {
        chunks.push(Chunk::of(0, &top.records));
    }
    chunks.extend(layout.pieces.iter().map(|p| Chunk {
        start: p.to,
        level: p.chunk.level + top.roots[p.part].0.level as u32,
        ..p.chunk
    }));
    chunks
}

/// The six sections, each from the top tree then every piece of the layout, the pieces
/// read ahead ([`read_ahead::stream`]).
fn write_sections(
    out: &mut Hashed,
    (files, parts, layout): (&mut [PartFile], &[Part], &Layout),
    top: &Top,
    (chunks, has_attributes): (&[Chunk], bool),
) -> std::io::Result<()> {
    let offsets: Vec<_> = parts
        .iter()
        .map(|p| part_offsets(p.nodes, has_attributes))
        .collect();
    // Each piece's values in the section that starts at `section(part)`.
    let spans = |section: &dyn Fn(usize) -> u64, size: usize| -> Vec<Span> {
        (layout.pieces.iter())
            .map(|p| Span {
                part: p.part,
                at: section(p.part) + p.chunk.start * size as u64,
                count: p.chunk.count as usize,
            })
            .collect()
    };
    let piece = |k: usize| &layout.pieces[k];
    let mut blocks = BlockIndexBuilder::new(chunks);
    out.put(bytemuck::cast_slice(&top.records))?;
    blocks.feed(&top.records);
    let records = spans(&|_| 0, std::mem::size_of::<NodeRecord>());
    stream::<NodeRecord>(files, &records, out, |k, first, slab| {
        let (root, _) = top.roots[piece(k).part];
        for r in slab.iter_mut() {
            r.level += root.level;
        }
        if piece(k).chunk.start == 0 && first == 0 {
            slab[0] = root;
        }
        blocks.feed(slab);
    })?;
    out.put(bytemuck::cast_slice(&top.parents))?;
    let parents = spans(&|part| offsets[part].0, 4);
    // Each piece's lookups start from its first chunk.
    let mut finger = 0;
    stream::<u32>(files, &parents, out, |k, first, slab| {
        let p = piece(k);
        let up = top.roots[p.part].1;
        if first == 0 {
            finger = 0;
        }
        for q in slab.iter_mut() {
            *q = match *q {
                u32::MAX => up,
                local => layout.position(p.part, local as u64, &mut finger) as u32,
            };
        }
    })?;
    out.put(bytemuck::cast_slice(&top.shapes))?;
    let shapes = spans(&|part| offsets[part].1, std::mem::size_of::<SplatShape>());
    stream::<SplatShape>(files, &shapes, out, |_, _, _| {})?;
    if has_attributes {
        out.put(bytemuck::cast_slice(&top.attributes))?;
        let size = std::mem::size_of::<PointAttributes>();
        let attributes = spans(&|part| offsets[part].2, size);
        stream::<PointAttributes>(files, &attributes, out, |_, _, _| {})?;
    }
    out.put(bytemuck::cast_slice(chunks))?;
    let (suffix, heads) = blocks.finish();
    out.put(bytemuck::cast_slice(&suffix))?;
    out.put(bytemuck::cast_slice(&heads))?;
    Ok(())
}
