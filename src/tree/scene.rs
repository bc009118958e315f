//! A model ready to draw: its sequential list (built from a PLY file in memory, or a
//! memory-mapped `.spt`), its prefix index, and for meshes the triangles of the
//! reference pass. Opening one is the one place the stages run from a file:
//!
//! ```text
//! PLY ─► read ─► leaf surfels ─► build_list (hierarchy, errors, sort) ─┐
//! .spt ─► map and check ───────────────────────────────────────────────┴─► prefix index
//! ```

use std::path::Path;

use glam::Vec3;

use super::report::{Finished, Report, Silent, Step};
use super::select::PrefixIndex;
use super::spt_file::{SptFile, is_spt};
use super::{NodeRecord, OrderedSet, SequentialList, TreeMeta, build_list, build_ordered};
use crate::io::formats::read_model_telling;
use crate::io::model::Model;
use crate::io::{Geometry, PointAttributes};
use crate::surfel::progress::Progress;
use crate::surfel::shape::SplatShape;
use crate::surfel::{DEFAULT_COLOR, LeafSurfels, leaf_surfels_with_progress};

/// The mesh a model came from, for the reference pass: per-vertex position (relative to
/// the same origin as the tree), unit normal (the leaf surfel's) and colour.
#[derive(Debug, Clone)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub colors: Vec<[u8; 4]>,
    pub triangles: Vec<[u32; 3]>,
}

pub enum TreeSource {
    Memory(SequentialList),
    File(SptFile),
}

pub struct Scene {
    pub tree: TreeSource,
    pub index: PrefixIndex,
    pub mesh: Option<MeshData>,
}

impl Scene {
    pub fn from_list(list: SequentialList, mesh: Option<MeshData>) -> Scene {
        let index = PrefixIndex::new(&list.meta, &list.chunks, &list.nodes);
        Scene {
            tree: TreeSource::Memory(list),
            index,
            mesh,
        }
    }

    /// Opens a PLY (built into a tree in memory, mesh kept) or an `.spt` file.
    pub fn open(path: &Path) -> anyhow::Result<Scene> {
        Scene::open_reporting(path, &Silent)
    }

    /// [`Scene::open`], telling `report` each step: for an `.spt` file, its check and
    /// prefix index; for a model file (PLY, LAS, LAZ), reading, surfels, tree, errors, sort and index.
    pub fn open_reporting(path: &Path, report: &dyn Report) -> anyhow::Result<Scene> {
        if is_spt(path) {
            report.step(Step::Check, 0);
            let file = SptFile::open(path)?;
            report.step(Step::Index, 0);
            let index = file
                .prefix_index()
                .map_err(|what| anyhow::anyhow!("{what}"))?;
            return Ok(Scene {
                tree: TreeSource::File(file),
                index,
                mesh: None,
            });
        }
        let (list, mesh) = build_from_file(path, true, report)?;
        report.step(Step::Index, 0);
        Ok(Scene::from_list(list, mesh))
    }

    /// Opens a model to stream it to the GPU: an `.spt` file with its header and chunk
    /// table checked and its stored prefix index read, not its nodes (the caller checks
    /// them beside the drawing: [`Scene::check_file`]); a model file as [`Scene::open`].
    pub fn open_for_streaming(path: &Path, report: &dyn Report) -> anyhow::Result<Scene> {
        if !is_spt(path) {
            return Scene::open_reporting(path, report);
        }
        report.step(Step::Index, 0);
        let (file, index) = SptFile::open_for_streaming(path)?;
        Ok(Scene {
            tree: TreeSource::File(file),
            index,
            mesh: None,
        })
    }

    /// The checks [`Scene::open_for_streaming`] left out: an `.spt` file's checksum and
    /// every node's values (nothing to do for a model built in memory).
    pub fn check_file(&self) -> anyhow::Result<()> {
        if let TreeSource::File(file) = &self.tree {
            file.verify()?;
            file.validate()?;
        }
        Ok(())
    }

    /// The scene of geometry already read (its mesh kept when it has triangles).
    pub fn from_geometry(geometry: Geometry) -> Scene {
        let (list, mesh) = build_from_geometry(geometry, true, &Silent);
        Scene::from_list(list, mesh)
    }

    pub fn meta(&self) -> &TreeMeta {
        match &self.tree {
            TreeSource::Memory(l) => &l.meta,
            TreeSource::File(f) => &f.meta,
        }
    }

    pub fn nodes(&self) -> &[NodeRecord] {
        match &self.tree {
            TreeSource::Memory(l) => &l.nodes,
            TreeSource::File(f) => f.nodes(),
        }
    }

    /// Each node's ellipse and normal field, in list order.
    pub fn shapes(&self) -> &[SplatShape] {
        match &self.tree {
            TreeSource::Memory(l) => &l.shapes,
            TreeSource::File(f) => f.shapes(),
        }
    }
    /// Each node's LiDAR attributes, in list order (empty when the model has none).
    pub fn attributes(&self) -> &[PointAttributes] {
        match &self.tree {
            TreeSource::Memory(l) => &l.attributes,
            TreeSource::File(f) => f.attributes(),
        }
    }
}

/// Reads a model file (PLY, LAS or LAZ) and builds its sequential list, telling `report` each step; with
/// `keep_mesh`, also the mesh of the reference pass (for a model with triangles).
pub fn build_from_file(
    path: &Path,
    keep_mesh: bool,
    report: &dyn Report,
) -> anyhow::Result<(SequentialList, Option<MeshData>)> {
    let model = read_step(path, report)?;
    let up = model.summary.up;
    let (mut list, mesh) = build_from_geometry(model.geometry, keep_mesh, report);
    list.meta = list.meta.with_file_up(up);
    Ok((list, mesh))
}

/// Reads a model file (PLY, LAS or LAZ) and builds its tree up to the list's order
/// ([`build_ordered`]), telling `report` each step: what `spt convert` writes with
/// [`write_ordered`](super::spt_write::write_ordered), never sorting the list in memory.
pub fn ordered_from_file(path: &Path, report: &dyn Report) -> anyhow::Result<OrderedSet> {
    let model = read_step(path, report)?;
    let up = model.summary.up;
    let mut leaves = surfels_step(&model.geometry, report);
    drop(model);
    leaves.vertex_normals = Vec::new();
    let mut set = build_ordered(leaves, report);
    set.meta = set.meta.with_file_up(up);
    Ok(set)
}

/// The read step: the model in `path`, its bytes told as they are read.
fn read_step(path: &Path, report: &dyn Report) -> anyhow::Result<Model> {
    let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
    report.step(Step::Read, bytes);
    let model = read_model_telling(path, &|n| report.advance(n))?.drawable(path)?;
    report.finished(Finished::Read(&model));
    Ok(model)
}

/// The surfels step: the leaf surfels of `geometry`, its samples told as they are done.
fn surfels_step(geometry: &Geometry, report: &dyn Report) -> LeafSurfels {
    report.step(Step::Surfels, geometry.positions.len() as u64);
    let done = |n: u64| report.advance(n);
    let leaves = leaf_surfels_with_progress(geometry, Progress::to(&done));
    report.finished(Finished::Surfels(&leaves));
    leaves
}

/// Builds the sequential list of `geometry` (and with `keep_mesh`, the mesh of the
/// reference pass, for a model with triangles), telling `report` each step from the
/// surfels on.
pub fn build_from_geometry(
    mut geometry: Geometry,
    keep_mesh: bool,
    report: &dyn Report,
) -> (SequentialList, Option<MeshData>) {
    let mut leaves = surfels_step(&geometry, report);
    let normals = std::mem::take(&mut leaves.vertex_normals);
    let mesh = (keep_mesh && !geometry.triangles.is_empty()).then(|| MeshData {
        // The vertices' surfels, not the splats of a meshed frame's long triangles
        // that follow them.
        positions: (leaves.surfels.iter().take(geometry.positions.len()))
            .map(|s| s.position)
            .collect(),
        normals,
        // The file's colours: the surfels' are fitted to pass 2's blend.
        colors: geometry
            .colors
            .take()
            .unwrap_or_else(|| vec![DEFAULT_COLOR; leaves.surfels.len()]),
        // The geometry is dropped next: its triangles move, they are not copied.
        triangles: std::mem::take(&mut geometry.triangles),
    });
    drop(geometry);
    (build_list(leaves, report), mesh)
}
