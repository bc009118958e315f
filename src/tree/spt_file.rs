//! `.spt` files: a sequential point tree, ready to memory-map and upload (docs/design.md §8).
//!
//! ```text
//! offset  size  field (little-endian)
//!      0     8  magic "spt-tree"
//!      8     4  format version (8; versions 7, 6, 5, 4, 3 and 2 read as well: version
//!                 7 did not store how estimated normals were turned (flags 8 and 16),
//!                 read as the leaf box tells ([`TreeMeta::normals_turned_by_leaf_box`]); version 6
//!                 had 16-byte shapes, without the colour field, read with a zero
//!                 one; version 5 had no block heads, version 4 no δ suffix section either,
//!                 versions 3 and 2 no chunk table (their
//!                 list is one chunk), version 2 no attributes section; version 1,
//!                 refused, no shapes section)
//!     12     4  header size (256)
//!     16     4  flags: 1 = has colours, 2 = oriented normals, 4 = LiDAR attributes,
//!                 8 = estimated normals turned up (a terrain's), 16 = turned toward
//!                 the origin (a sensor frame's); bits 5–7: the up axis, 0 none (a
//!                 sensor frame's view; z in files written before it was stored),
//!                 1–6 z, y, x, −z, −y, −x; 256 = oriented normals whose front is
//!                 not known, drawn two-sided (a mesh's open pieces, as wound)
//!     20     4  depth (largest level)
//!     24     8  leaf count
//!     32     8  node count
//!     40    24  origin, 3 × f64 (file coordinates)
//!     64    48  leaf-centre bounds min, max, 3 × f64 each (file coordinates)
//!    112    24  node-centre bounds min, max, 3 × f32 each (relative to origin)
//!    136     4  error scale, f32
//!    140     4  node record size (32)
//!    144     8  offset of the node records (256: page- and cache-aligned)
//!    152     8  offset of the parent indices (u32 per node, u32::MAX for the root)
//!    160     8  file size
//!    168     8  checksum: XXH3-64 of the header (this field zeroed) and all sections
//!    176     8  offset of the splat shapes (24 bytes per node, after the parents)
//!    184     4  splat shape size (24; 16 before version 7)
//!    188     8  offset of the LiDAR attributes (4 bytes per node, after the shapes;
//!                 an empty section when flag 4 is clear)
//!    196     4  attribute size (4)
//!    200     4  intensity range: 1st and 99th percentile of the leaves, 2 × u16
//!    204     8  offset of the chunk table (after the attributes)
//!    212     4  chunk record size (40)
//!    216     8  chunk count (≥ 1)
//!    224     8  offset of the δ suffix maxima (after the chunk table), followed
//!                 by as many block heads
//!    232     8  their count: one per block of 64 nodes of each chunk
//!    240    16  zero
//! ```
//!
//! Sections follow the header in this order: node records (what the culling pass
//! reads), parents (the CPU's), splat shapes (what only the splat passes read), LiDAR
//! attributes (what the attribute display modes read; a model without pays nothing),
//! the chunk table ([`Chunk`]: each chunk's range of the list, box and largest radius;
//! the chunks follow each other and cover the list), the δ suffix maxima of the prefix
//! search (u16 each, [`chunk_delta_suffix`](super::select::chunk_delta_suffix), chunk after chunk) and the block heads
//! (u16 each, [`block_heads`], as many), so that a file opens to its first frame, and
//! finds what a view needs, without reading its nodes.

use std::io::Write;
use std::path::{Path, PathBuf};

use memmap2::Mmap;
use thiserror::Error;
use xxhash_rust::xxh3::Xxh3;

use super::chunks::Chunk;
use super::select::{PrefixIndex, TreeView, block_heads, delta_suffix, delta_suffix_len};
use super::validate;
use super::{NodeRecord, SequentialList, TreeMeta};
use crate::io::atomic::write_atomically;
use crate::io::up::UpAxis;
use crate::io::{Bounds, PointAttributes};
use crate::surfel::NormalsTurned;
use crate::surfel::shape::SplatShape;

pub const MAGIC: &[u8; 8] = b"spt-tree";
pub const VERSION: u32 = 8;
/// Where the up axis's code ([`UpAxis::code`], 0 for none) lies in the flags.
const UP_SHIFT: u32 = 5;

/// The flag of [`TreeMeta::two_sided`], after the up axis's three bits.
const TWO_SIDED_BIT: u32 = 8;
/// The oldest version read: version 2 files are version 3 files without attributes.
pub const OLDEST_READ: u32 = 2;
pub const HEADER_BYTES: usize = 256;
const RECORD_BYTES: usize = std::mem::size_of::<NodeRecord>();
const SHAPE_BYTES: usize = std::mem::size_of::<SplatShape>();
/// A splat shape before version 7: [`SplatShape`] without its colour field.
const SHAPE_BYTES_BEFORE_7: usize = 16;

/// The size of a splat shape in a file of format `version`.
fn shape_bytes(version: u32) -> usize {
    if version >= 7 {
        SHAPE_BYTES
    } else {
        SHAPE_BYTES_BEFORE_7
    }
}
const ATTRIBUTE_BYTES: usize = std::mem::size_of::<PointAttributes>();
const CHUNK_BYTES: usize = std::mem::size_of::<Chunk>();
const CHECKSUM_AT: usize = 168;

#[derive(Debug, Error)]
pub enum SptError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not an .spt file (no 'spt-tree' magic)")]
    NotSpt { path: PathBuf },
    #[error(
        "{path}: made by a newer spt (format version {version}; this build reads version {VERSION})"
    )]
    NewerVersion { path: PathBuf, version: u32 },
    #[error(
        "{path}: made by an older spt (format version {version}, without splat shapes): convert the model again"
    )]
    OlderVersion { path: PathBuf, version: u32 },
    #[error("{path}: truncated: {actual} bytes, the header says {expected}")]
    Truncated {
        path: PathBuf,
        actual: u64,
        expected: u64,
    },
    #[error("{path}: corrupt header: {what}")]
    BadHeader { path: PathBuf, what: String },
    #[error("{path}: invalid tree: {what}")]
    Invalid { path: PathBuf, what: String },
    #[error("{path}: corrupt: checksum mismatch (stored {stored:016x}, computed {computed:016x})")]
    Checksum {
        path: PathBuf,
        stored: u64,
        computed: u64,
    },
}

/// Whether `path` starts with the `.spt` magic (false for anything unreadable).
pub fn is_spt(path: &Path) -> bool {
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic))
        .is_ok_and(|_| &magic == MAGIC)
}

fn header_bytes(list: &SequentialList, checksum: u64) -> Vec<u8> {
    debug_assert_eq!(list.attributes.is_empty(), !list.meta.has_attributes);
    header_for(&list.meta, &list.chunks, checksum)
}

/// The header of a file of the tree `m` describes (its node count and attributes flag
/// give the sections' sizes) cut into `chunks`.
pub fn header_for(m: &TreeMeta, chunks: &[Chunk], checksum: u64) -> Vec<u8> {
    let chunk_count = chunks.len() as u64;
    let suffix_count = delta_suffix_len(chunks);
    let nodes = m.node_count as usize;
    let attribute_nodes = if m.has_attributes { nodes } else { 0 };
    let mut h = Vec::with_capacity(HEADER_BYTES);
    h.extend_from_slice(MAGIC);
    h.extend_from_slice(&VERSION.to_le_bytes());
    h.extend_from_slice(&(HEADER_BYTES as u32).to_le_bytes());
    let flags = m.has_colors as u32
        | (m.oriented_normals as u32) << 1
        | (m.has_attributes as u32) << 2
        | ((m.normals_turned == NormalsTurned::Up) as u32) << 3
        | ((m.normals_turned == NormalsTurned::TowardOrigin) as u32) << 4
        | m.up.map_or(0, UpAxis::code) << UP_SHIFT
        | (m.two_sided as u32) << TWO_SIDED_BIT;
    h.extend_from_slice(&flags.to_le_bytes());
    h.extend_from_slice(&m.depth.to_le_bytes());
    h.extend_from_slice(&m.leaf_count.to_le_bytes());
    h.extend_from_slice(&m.node_count.to_le_bytes());
    for v in m.origin.iter().chain(&m.bounds.min).chain(&m.bounds.max) {
        h.extend_from_slice(&v.to_le_bytes());
    }
    for v in m.centre_min.iter().chain(&m.centre_max) {
        h.extend_from_slice(&v.to_le_bytes());
    }
    h.extend_from_slice(&m.error_scale.to_le_bytes());
    h.extend_from_slice(&(RECORD_BYTES as u32).to_le_bytes());
    let nodes_at = HEADER_BYTES as u64;
    let parents_at = nodes_at + (nodes * RECORD_BYTES) as u64;
    let shapes_at = parents_at + 4 * nodes as u64;
    let attributes_at = shapes_at + (nodes * SHAPE_BYTES) as u64;
    let chunks_at = attributes_at + (attribute_nodes * ATTRIBUTE_BYTES) as u64;
    let suffix_at = chunks_at + chunk_count * CHUNK_BYTES as u64;
    let size = suffix_at + 4 * suffix_count;
    for v in [nodes_at, parents_at, size, checksum, shapes_at] {
        h.extend_from_slice(&v.to_le_bytes());
    }
    h.extend_from_slice(&(SHAPE_BYTES as u32).to_le_bytes());
    h.extend_from_slice(&attributes_at.to_le_bytes());
    h.extend_from_slice(&(ATTRIBUTE_BYTES as u32).to_le_bytes());
    for v in m.intensity_range {
        h.extend_from_slice(&v.to_le_bytes());
    }
    h.extend_from_slice(&chunks_at.to_le_bytes());
    h.extend_from_slice(&(CHUNK_BYTES as u32).to_le_bytes());
    h.extend_from_slice(&chunk_count.to_le_bytes());
    h.extend_from_slice(&suffix_at.to_le_bytes());
    h.extend_from_slice(&suffix_count.to_le_bytes());
    h.resize(HEADER_BYTES, 0);
    h
}

/// Where the checksum lies in the header.
pub const CHECKSUM_OFFSET: u64 = CHECKSUM_AT as u64;

/// XXH3-64 of the header (checksum zeroed) and the `sections` that follow it, in order.
fn payload_checksum(header: &[u8], sections: &[&[u8]]) -> u64 {
    let mut zeroed = header.to_vec();
    zeroed[CHECKSUM_AT..CHECKSUM_AT + 8].fill(0);
    let mut hasher = Xxh3::new();
    hasher.update(&zeroed);
    for section in sections {
        hasher.update(section);
    }
    hasher.digest()
}

/// Stores in an `.spt` image held in memory the checksum of its bytes, whatever they
/// hold; false when `bytes` is shorter than a header. For tools that edit files on
/// purpose (the fuzzer), so that their edits reach past the checksum.
pub fn reseal(bytes: &mut [u8]) -> bool {
    if bytes.len() < HEADER_BYTES {
        return false;
    }
    let (header, rest) = bytes.split_at(HEADER_BYTES);
    let checksum = payload_checksum(header, &[rest]);
    bytes[CHECKSUM_AT..CHECKSUM_AT + 8].copy_from_slice(&checksum.to_le_bytes());
    true
}

/// Writes the list in `.spt` form to `w` (little-endian hosts write their memory as is).
pub fn write_to(w: &mut dyn Write, list: &SequentialList) -> std::io::Result<()> {
    let suffix = delta_suffix(&list.chunks, &list.nodes);
    let heads = block_heads(&list.chunks, &list.nodes);
    let sections: [&[u8]; 7] = [
        bytemuck::cast_slice(&list.nodes),
        bytemuck::cast_slice(&list.parents),
        bytemuck::cast_slice(&list.shapes),
        bytemuck::cast_slice(&list.attributes),
        bytemuck::cast_slice(&list.chunks),
        bytemuck::cast_slice(&suffix),
        bytemuck::cast_slice(&heads),
    ];
    let checksum = payload_checksum(&header_bytes(list, 0), &sections);
    w.write_all(&header_bytes(list, checksum))?;
    // Large sections in chunks, so that writes stay short.
    for chunk in sections.iter().flat_map(|s| s.chunks(64 << 20)) {
        w.write_all(chunk)?;
    }
    Ok(())
}

/// The size in bytes of the `.spt` file of the tree `meta` describes, cut into
/// `chunks` (its header's file size).
pub fn file_bytes(meta: &TreeMeta, chunks: &[Chunk]) -> u64 {
    u64_at(&header_for(meta, chunks, 0), 160)
}

/// Writes `list` to `path` atomically (temporary file, then rename).
pub fn write_spt(path: &Path, list: &SequentialList) -> std::io::Result<()> {
    write_atomically(path, |w| write_to(w, list))
}

/// Where the sections of an `.spt` image lie, from its header.
struct Sections {
    nodes_at: u64,
    parents_at: u64,
    shapes_at: u64,
    attributes_at: u64,
    /// Where the chunk table starts and its chunks (0 before version 4).
    chunks_at: u64,
    chunk_count: u64,
    /// Where the δ suffix maxima start (the end of the file before version 5), and
    /// their count (the block heads follow from version 6).
    suffix_at: u64,
    suffix_count: u64,
    size: u64,
}

/// The sections of the `.spt` image `b` (a whole header, format `version`), checked
/// to follow each other as the module doc lays them out.
fn sections(b: &[u8], version: u32) -> Result<Sections, String> {
    let (leaf_count, node_count) = (u64_at(b, 24), u64_at(b, 32));
    let (nodes_at, parents_at, size) = (u64_at(b, 144), u64_at(b, 152), u64_at(b, 160));
    let shapes_at = u64_at(b, 176);
    let has_attributes = u32_at(b, 16) & 4 != 0;
    // Version 2: no attributes section (it ends the file, empty).
    let (attributes_at, attribute_bytes) = match version {
        2 => (size, ATTRIBUTE_BYTES as u32),
        _ => (u64_at(b, 188), u32_at(b, 196)),
    };
    let attribute_nodes = if has_attributes { node_count } else { 0 };
    let attributes_end = attribute_nodes
        .checked_mul(ATTRIBUTE_BYTES as u64)
        .and_then(|n| n.checked_add(attributes_at));
    // Before version 4: no chunk table (it ends the file, empty).
    let (chunks_at, chunk_bytes, chunk_count) = match version {
        ..=3 => (attributes_end.unwrap_or(u64::MAX), CHUNK_BYTES as u32, 0),
        _ => (u64_at(b, 204), u32_at(b, 212), u64_at(b, 216)),
    };
    let after = |at: u64, count: u64, bytes: usize| {
        count
            .checked_mul(bytes as u64)
            .and_then(|n| n.checked_add(at))
    };
    let chunks_end = after(chunks_at, chunk_count, CHUNK_BYTES);
    // Before version 5: no δ suffix maxima (they end the file, empty).
    let (suffix_at, suffix_count) = match version {
        ..=4 => (chunks_end.unwrap_or(u64::MAX), 0),
        _ => (u64_at(b, 224), u64_at(b, 232)),
    };
    if nodes_at != HEADER_BYTES as u64
        || Some(parents_at) != after(nodes_at, node_count, RECORD_BYTES)
        || Some(shapes_at) != after(parents_at, node_count, 4)
        || Some(attributes_at) != after(shapes_at, node_count, shape_bytes(version))
        || attribute_bytes as usize != ATTRIBUTE_BYTES
        || (version == 2 && has_attributes)
        || Some(chunks_at) != attributes_end
        || chunk_bytes as usize != CHUNK_BYTES
        || (version >= 4 && !(1..=node_count).contains(&chunk_count))
        || Some(suffix_at) != chunks_end
        || Some(size) != after(suffix_at, suffix_count, if version >= 6 { 4 } else { 2 })
        || leaf_count > node_count
        || node_count == 0
    {
        return Err(format!(
            "{node_count} nodes, {leaf_count} leaves, {chunk_count} chunks, sections at {nodes_at} and {parents_at}, size {size}"
        ));
    }
    Ok(Sections {
        nodes_at,
        parents_at,
        shapes_at,
        attributes_at,
        chunks_at,
        chunk_count,
        suffix_at,
        suffix_count,
        size,
    })
}

/// The tree's description in the header of the `.spt` image `b` (of format `version`);
/// an error where its flags say the normals were turned both up and toward the origin.
fn meta_of(b: &[u8], version: u32) -> Result<TreeMeta, String> {
    let flags = u32_at(b, 16);
    if flags & 24 == 24 {
        return Err(format!(
            "flags {flags:#x}: estimated normals turned both up (8) and toward the origin (16)"
        ));
    }
    let up_code = (flags >> UP_SHIFT) & 7;
    let up = UpAxis::from_code(up_code);
    if up_code != 0 && up.is_none() {
        return Err(format!(
            "flags {flags:#x}: up axis code {up_code} names no axis"
        ));
    }
    let v3 = |at: usize| [f64_at(b, at), f64_at(b, at + 8), f64_at(b, at + 16)];
    let f3 = |at: usize| [f32_at(b, at), f32_at(b, at + 4), f32_at(b, at + 8)];
    let mut meta = TreeMeta {
        origin: v3(40),
        bounds: Bounds {
            min: v3(64),
            max: v3(88),
        },
        centre_min: f3(112),
        centre_max: f3(124),
        error_scale: f32_at(b, 136),
        leaf_count: u64_at(b, 24),
        node_count: u64_at(b, 32),
        depth: u32_at(b, 20),
        has_colors: flags & 1 != 0,
        oriented_normals: flags & 2 != 0,
        two_sided: flags & 1 << TWO_SIDED_BIT != 0,
        normals_turned: match flags & 24 {
            8 => NormalsTurned::Up,
            16 => NormalsTurned::TowardOrigin,
            _ => NormalsTurned::No, // 0; 24 is refused above
        },
        has_attributes: flags & 4 != 0,
        intensity_range: [0, 2].map(|k| u16::from_le_bytes([b[200 + k], b[201 + k]])),
        up,
    };
    if version < 8 {
        meta.normals_turned = meta.normals_turned_by_leaf_box();
    }
    Ok(meta)
}

/// Shapes of [`SHAPE_BYTES_BEFORE_7`] bytes (`bytes`, whole ones) as [`SplatShape`]s: the
/// same fields, first, and a zero colour field.
fn widen(bytes: &[u8]) -> Vec<SplatShape> {
    bytes
        .chunks_exact(SHAPE_BYTES_BEFORE_7)
        .map(|old| {
            let mut shape = <SplatShape as bytemuck::Zeroable>::zeroed();
            bytemuck::bytes_of_mut(&mut shape)[..SHAPE_BYTES_BEFORE_7].copy_from_slice(old);
            shape
        })
        .collect()
}

/// An `.spt` file, memory-mapped: the node records are read in place.
pub struct SptFile {
    pub path: PathBuf,
    pub meta: TreeMeta,
    pub version: u32,
    pub checksum: u64,
    map: Mmap,
    nodes_at: usize,
    parents_at: usize,
    shapes_at: usize,
    attributes_at: usize,
    chunks_at: usize,
    suffix_at: usize,
    suffix_count: usize,
    /// The shapes of a file before version 7, each given a zero colour field.
    widened: Option<Vec<SplatShape>>,
    /// The chunk table (read from the file; before version 4, the whole list as one chunk).
    chunks: Vec<Chunk>,
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}
fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}
fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

impl SptFile {
    /// Opens and checks the file: its checksum, then every value a reader relies on
    /// ([`validate::check_meta`], [`validate::check_nodes`]): a file whose checksum
    /// holds may still come from another writer.
    pub fn open(path: &Path) -> Result<SptFile, SptError> {
        let file = Self::open_unverified(path)?;
        file.verify()?;
        file.validate()?;
        Ok(file)
    }

    /// Checks the header's values and every node on its own ([`validate`]), and the
    /// stored δ suffix maxima and block heads against the nodes.
    pub fn validate(&self) -> Result<(), SptError> {
        validate::check_meta(&self.meta)
            .and_then(|_| validate::check_nodes(&self.meta, self.nodes(), self.parents()))
            .and_then(|_| validate::check_chunks(self.nodes(), &self.chunks))
            .and_then(|_| match self.delta_suffix() {
                Some(stored) if stored != delta_suffix(&self.chunks, self.nodes()) => {
                    Err("the stored δ suffix maxima differ from the nodes' δ".to_string())
                }
                _ => Ok(()),
            })
            .and_then(|_| match self.block_heads() {
                Some(stored) if stored != block_heads(&self.chunks, self.nodes()) => {
                    Err("the stored block heads differ from the nodes' parent errors".to_string())
                }
                _ => Ok(()),
            })
            .map_err(|what| self.invalid(what))
    }

    fn invalid(&self, what: String) -> SptError {
        SptError::Invalid {
            path: self.path.clone(),
            what,
        }
    }

    /// Opens the file to stream it: checks the header, the sections' layout, the header's
    /// values and the chunk table, and reads the prefix index the file stores, without
    /// reading a node (a file before version 6 has its index, or what it lacks of it,
    /// built from its nodes). The
    /// checksum and the nodes' own checks ([`SptFile::verify`], [`SptFile::validate`])
    /// are left to the caller, to run beside the drawing.
    pub fn open_for_streaming(path: &Path) -> Result<(SptFile, PrefixIndex), SptError> {
        let file = Self::open_unverified(path)?;
        validate::check_meta(&file.meta)
            .and_then(|_| validate::check_chunk_table(&file.chunks, file.meta.node_count))
            .map_err(|what| file.invalid(what))?;
        let index = file.prefix_index().map_err(|what| file.invalid(what))?;
        Ok((file, index))
    }

    /// The prefix index: what the file stores of it (the δ suffix maxima from version 5,
    /// the block heads from version 6), the rest built from the nodes.
    pub fn prefix_index(&self) -> Result<PrefixIndex, String> {
        let (chunks, nodes) = (&self.chunks, || self.nodes());
        let suffix = self
            .delta_suffix()
            .map_or_else(|| delta_suffix(chunks, nodes()), <[u16]>::to_vec);
        let heads = self
            .block_heads()
            .map_or_else(|| block_heads(chunks, nodes()), <[u16]>::to_vec);
        PrefixIndex::with_blocks(&self.meta, chunks, (suffix, heads))
    }

    /// The δ suffix maxima the file stores (from version 5).
    pub fn delta_suffix(&self) -> Option<&[u16]> {
        let (at, n) = (self.suffix_at, self.suffix_count);
        (self.version >= 5).then(|| bytemuck::cast_slice(&self.map[at..at + 2 * n]))
    }

    /// The block heads the file stores (from version 6).
    pub fn block_heads(&self) -> Option<&[u16]> {
        let at = self.suffix_at + 2 * self.suffix_count;
        (self.version >= 6).then(|| bytemuck::cast_slice(&self.map[at..at + 2 * self.suffix_count]))
    }

    /// Opens the file and checks its header and size, not its checksum.
    pub fn open_unverified(path: &Path) -> Result<SptFile, SptError> {
        let p = || path.to_owned();
        let io = |source| SptError::Io { path: p(), source };
        let f = std::fs::File::open(path).map_err(io)?;
        // SAFETY: read-only map; a file truncated by another process while mapped is
        // outside what a reader can guard against.
        let map = unsafe { Mmap::map(&f) }.map_err(io)?;
        let b = &map[..];
        if b.len() < 12 || &b[..8] != MAGIC {
            return Err(SptError::NotSpt { path: p() });
        }
        let version = u32_at(b, 8);
        if version > VERSION {
            return Err(SptError::NewerVersion { path: p(), version });
        }
        if version < OLDEST_READ && version > 0 {
            return Err(SptError::OlderVersion { path: p(), version });
        }
        if b.len() < HEADER_BYTES {
            return Err(SptError::Truncated {
                path: p(),
                actual: b.len() as u64,
                expected: HEADER_BYTES as u64,
            });
        }
        let bad = |what: String| SptError::BadHeader { path: p(), what };
        if version == 0
            || u32_at(b, 12) as usize != HEADER_BYTES
            || u32_at(b, 140) as usize != RECORD_BYTES
            || u32_at(b, 184) as usize != shape_bytes(version)
        {
            return Err(bad(format!(
                "version {version}, header size {}, record size {}, shape size {}",
                u32_at(b, 12),
                u32_at(b, 140),
                u32_at(b, 184)
            )));
        }
        let s = sections(b, version).map_err(bad)?;
        let size = s.size;
        if (b.len() as u64) < size {
            return Err(SptError::Truncated {
                path: p(),
                actual: b.len() as u64,
                expected: size,
            });
        }
        if b.len() as u64 > size {
            return Err(bad(format!(
                "{} bytes past the end of the last section",
                b.len() as u64 - size
            )));
        }
        let meta = meta_of(b, version).map_err(bad)?;
        let checksum = u64_at(b, CHECKSUM_AT);
        let chunks = if s.chunk_count == 0 {
            let nodes = bytemuck::cast_slice(&b[s.nodes_at as usize..s.parents_at as usize]);
            vec![Chunk::of(0, nodes)]
        } else {
            b[s.chunks_at as usize..s.suffix_at as usize]
                .chunks_exact(CHUNK_BYTES)
                .map(bytemuck::pod_read_unaligned)
                .collect()
        };
        Ok(SptFile {
            path: p(),
            meta,
            version,
            checksum,
            nodes_at: s.nodes_at as usize,
            parents_at: s.parents_at as usize,
            shapes_at: s.shapes_at as usize,
            attributes_at: s.attributes_at as usize,
            chunks_at: s.chunks_at as usize,
            suffix_at: s.suffix_at as usize,
            suffix_count: s.suffix_count as usize,
            chunks,
            widened: (version < 7)
                .then(|| widen(&b[s.shapes_at as usize..s.attributes_at as usize])),
            map,
        })
    }

    /// Recomputes the checksum over the header and every section.
    pub fn verify(&self) -> Result<(), SptError> {
        let b = &self.map[..];
        let computed = payload_checksum(&b[..HEADER_BYTES], &[&b[self.nodes_at..]]);
        if computed != self.checksum {
            return Err(SptError::Checksum {
                path: self.path.clone(),
                stored: self.checksum,
                computed,
            });
        }
        Ok(())
    }

    /// The node records in list order, in place in the map.
    pub fn nodes(&self) -> &[NodeRecord] {
        bytemuck::cast_slice(&self.map[self.nodes_at..self.parents_at])
    }

    /// Each node's parent as a list index (u32::MAX for the root).
    pub fn parents(&self) -> &[u32] {
        bytemuck::cast_slice(&self.map[self.parents_at..self.shapes_at])
    }

    /// Each node's ellipse, normal and colour fields, in list order.
    pub fn shapes(&self) -> &[SplatShape] {
        match &self.widened {
            Some(shapes) => shapes,
            None => bytemuck::cast_slice(&self.map[self.shapes_at..self.attributes_at]),
        }
    }

    /// Each node's LiDAR attributes, in list order (empty when the model has none).
    pub fn attributes(&self) -> &[PointAttributes] {
        bytemuck::cast_slice(&self.map[self.attributes_at..self.chunks_at])
    }

    /// The chunks, in list order ([`Chunk`]).
    pub fn chunks(&self) -> &[Chunk] {
        &self.chunks
    }

    pub fn file_bytes(&self) -> u64 {
        self.map.len() as u64
    }

    pub fn view(&self) -> TreeView<'_> {
        TreeView::new(&self.meta, self.nodes(), &self.chunks)
    }

    /// A copy in memory, as `spt convert` built it.
    pub fn to_list(&self) -> SequentialList {
        SequentialList {
            meta: self.meta.clone(),
            nodes: self.nodes().to_vec(),
            shapes: self.shapes().to_vec(),
            attributes: self.attributes().to_vec(),
            parents: self.parents().to_vec(),
            chunks: self.chunks.clone(),
        }
    }
}
