//! One job of an out-of-core build: its points and halo in, its subtree out. The job
//! reads its spill files, makes the leaf surfels of its own points (their
//! neighbourhoods see the halo: the points beyond its border), builds their tree with
//! the model's error scale and cuts it into chunks: the list that [`Built::write`]
//! writes to a part file.
//! What the top tree and the final file need is kept in [`Part`]: the subtree's root,
//! its sizes, its box, a sample of its intensities. Given its input points, a job
//! depends on nothing else, so jobs can run anywhere.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};
use xxhash_rust::xxh3::Xxh3;

use super::checksums::FileEntry;
use super::spill::{JobFiles, SpillPoint, read_records, read_spill};
use crate::io::atomic::write_atomically;
use crate::io::up::UpAxis;
use crate::io::{Bounds, Geometry, PointAttributes};
use crate::surfel::shape::SplatShape;
use crate::surfel::{LeafSurfels, NormalsTurned, leaf_surfels_of};
use crate::tree::chunks::Chunk;
use crate::tree::report::Silent;
use crate::tree::{
    NodeRecord, SequentialList, build_hierarchy, build_records_scaled, sort_list_chunked,
};

/// Intensities kept per job for the model's intensity range, at most.
const INTENSITY_SAMPLE: usize = 1 << 16;

/// What the model shares with every job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub origin: DVec3,
    pub bounds: Bounds,
    /// The bounds without outliers: the model's size, for its unit scale.
    pub core: Bounds,
    pub error_scale: f32,
    pub has_colors: bool,
    /// Whether the file gives normals.
    pub has_normals: bool,
    pub has_attributes: bool,
    /// The up axis the file gives.
    pub up: Option<UpAxis>,
    /// Nodes per subtree chunk ([`crate::tree::chunks::chunk_nodes_for`] of the whole
    /// model, so that chunks do not depend on how it was split into jobs).
    pub chunk_nodes: usize,
}

/// A job's subtree, written to `path` as its list's sections back to back: nodes,
/// parents (u32::MAX for the root, first), shapes, attributes (when the model has
/// them), chunks, then the intensity sample.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Part {
    #[serde(skip)]
    pub path: PathBuf,
    #[serde(with = "super::record::root_hex")]
    pub root: (NodeRecord, SplatShape, PointAttributes),
    pub nodes: u64,
    pub leaves: u64,
    /// How many of them are no sample of the file: a terrain's walls and long
    /// triangles' splats ([`crate::surfel::SurfelStats::added_splats`]).
    pub walls: u64,
    pub chunks: u64,
    /// Each chunk's largest parent error (its first node's, f16 bits): where the file
    /// places it ([`super::order`]).
    pub chunk_keys: Vec<u16>,
    pub depth: u32,
    pub centre_min: Vec3,
    pub centre_max: Vec3,
    pub oriented: bool,
    /// Which way its estimated normals were turned (every job decides it alike, on the
    /// model's core box).
    pub normals_turned: NormalsTurned,
    /// A sample of its points' attributes, for the model's intensity range: at the end of
    /// the part file, `intensity_count` of them.
    #[serde(skip)]
    pub intensities: Vec<PointAttributes>,
    pub intensity_count: u64,
    /// The error scale its leaves alone would take ([`crate::tree::error_scale`]: the
    /// largest extent of the box holding their disks).
    pub disk_extent: f32,
}

/// The geometry of a job: its own points first, then its halo.
fn geometry(
    model: &Model,
    own: &[SpillPoint],
    halo: &[SpillPoint],
    normals: Option<Vec<Vec3>>,
) -> Geometry {
    let all = || own.iter().chain(halo);
    Geometry {
        origin: model.origin,
        bounds: model.bounds,
        core: model.core,
        positions: all().map(|p| Vec3::from(p.position)).collect(),
        normals,
        colors: model.has_colors.then(|| all().map(|p| p.color).collect()),
        triangles: Vec::new(),
        rows: None,
        attributes: model
            .has_attributes
            .then(|| all().map(|p| p.attributes).collect()),
    }
}

/// The given normals of a job's own points and halo, in that order, when it has any.
fn read_normals(files: JobFiles, points: usize) -> anyhow::Result<Option<Vec<Vec3>>> {
    let Some((own, halo)) = files.normals else {
        return Ok(None);
    };
    let mut normals: Vec<[f32; 3]> = read_records(own)?;
    normals.extend(read_records::<[f32; 3]>(halo)?);
    anyhow::ensure!(
        normals.len() == points,
        "{}: {} normals for {points} points",
        own.display(),
        normals.len()
    );
    Ok(Some(normals.into_iter().map(Vec3::from).collect()))
}

/// A built job: what the join needs of its part, the part file's entry (size,
/// checksum), and the list whose sections the file holds, to be written
/// ([`Built::write`]) before the record that names it.
pub struct Built {
    pub part: Part,
    pub file: FileEntry,
    list: SequentialList,
}

/// Builds the job of spill files `files`, its part to be written at `part`.
pub fn build(model: &Model, files: JobFiles, part: &Path) -> anyhow::Result<Built> {
    let (own, halo) = (files.own, files.halo);
    let own_points = read_spill(own)?;
    anyhow::ensure!(
        !own_points.is_empty(),
        "{}: a job without points",
        own.display()
    );
    let halo_points = read_spill(halo)?;
    let normals = read_normals(files, own_points.len() + halo_points.len())?;
    let g = geometry(model, &own_points, &halo_points, normals);
    let step = (own_points.len() / INTENSITY_SAMPLE).max(1);
    let intensities: Vec<PointAttributes> = if model.has_attributes {
        own_points
            .iter()
            .step_by(step)
            .map(|p| p.attributes)
            .collect()
    } else {
        Vec::new()
    };
    let own_count = own_points.len();
    drop((own_points, halo_points));
    let leaves = leaf_surfels_of(&g, own_count);
    drop(g);
    build_leaves(model, leaves, intensities, part)
}

/// Builds the tree of a job's leaf surfels, its part to be written at `part`.
pub fn build_leaves(
    model: &Model,
    mut leaves: LeafSurfels,
    intensities: Vec<PointAttributes>,
    part: &Path,
) -> anyhow::Result<Built> {
    leaves.drop_redundant();
    let (leaf_count, walls) = (leaves.surfels.len() as u64, leaves.stats.added_splats());
    let disk_extent = crate::tree::error_scale(&leaves.surfels);
    let (oriented, normals_turned) = (leaves.oriented_normals, leaves.normals_turned);
    let hierarchy = build_hierarchy(&leaves, &Silent);
    let set = build_records_scaled(leaves, hierarchy, model.error_scale, &Silent);
    let list = sort_list_chunked(set, model.chunk_nodes);
    let file = part_entry(&list, &intensities, part);
    let part = Part {
        path: part.to_owned(),
        root: (
            list.nodes[0],
            list.shapes[0],
            list.attributes.first().copied().unwrap_or_default(),
        ),
        nodes: list.nodes.len() as u64,
        leaves: leaf_count,
        walls,
        chunks: list.chunks.len() as u64,
        chunk_keys: list
            .chunks
            .iter()
            .map(|c| list.nodes[c.start as usize].parent_error)
            .collect(),
        depth: list.meta.depth,
        centre_min: Vec3::from(list.meta.centre_min),
        centre_max: Vec3::from(list.meta.centre_max),
        oriented,
        normals_turned,
        intensity_count: intensities.len() as u64,
        intensities,
        disk_extent,
    };
    Ok(Built { part, file, list })
}

/// The part file's sections: the list's nodes, parents, shapes, attributes and
/// chunks, then the intensity sample.
fn sections<'a>(list: &'a SequentialList, intensities: &'a [PointAttributes]) -> [&'a [u8]; 6] {
    [
        bytemuck::cast_slice(&list.nodes),
        bytemuck::cast_slice(&list.parents),
        bytemuck::cast_slice(&list.shapes),
        bytemuck::cast_slice(&list.attributes),
        bytemuck::cast_slice::<Chunk, u8>(&list.chunks),
        bytemuck::cast_slice(intensities),
    ]
}

/// The entry (size, xxh3) of the part file at `path` that holds `list`'s sections.
fn part_entry(list: &SequentialList, intensities: &[PointAttributes], path: &Path) -> FileEntry {
    let mut hash = Xxh3::new();
    let mut bytes = 0;
    for s in sections(list, intensities) {
        hash.update(s);
        bytes += s.len() as u64;
    }
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    FileEntry {
        role: "part".to_owned(),
        name: name.into_owned(),
        bytes,
        xxh3: format!("{:016x}", hash.digest()),
    }
}

impl Built {
    /// Writes the part file at its path, atomically.
    pub fn write(&self) -> anyhow::Result<()> {
        write_atomically(&self.part.path, |w| {
            for s in sections(&self.list, &self.part.intensities) {
                w.write_all(s)?;
            }
            Ok(())
        })?;
        Ok(())
    }
}
