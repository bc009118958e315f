//! What the renderer draws: a sequential list (built from a PLY file in memory, or a
//! memory-mapped `.spt`), its prefix index, and for meshes the triangles of the
//! reference pass.

use std::path::Path;

use glam::Vec3;

use crate::io::ply::read_ply;
use crate::tree::spt_file::{SptFile, is_spt};
use crate::surfel::leaf_surfels;
use crate::tree::select::PrefixIndex;
use crate::tree::{
    NodeRecord, SequentialList, TreeMeta, build_hierarchy, build_records, sort_list,
};

/// Hears how loading goes: each stage as it starts (with its amount of work, 0 when
/// unknown), then the work done, from any thread.
pub trait LoadReport: Sync {
    fn stage(&self, name: &'static str, total: u64);
    fn advance(&self, done: u64);
}

/// A [`LoadReport`] that ignores everything.
pub struct Silent;

impl LoadReport for Silent {
    fn stage(&self, _: &'static str, _: u64) {}
    fn advance(&self, _: u64) {}
}

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
        let index = PrefixIndex::new(&list.meta, &list.nodes);
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

    /// [`Scene::open`], telling `report` each stage: for an `.spt` file, its checksum
    /// and prefix index; for a PLY file, reading, surfels, tree, errors, sort and index.
    pub fn open_reporting(path: &Path, report: &dyn LoadReport) -> anyhow::Result<Scene> {
        if is_spt(path) {
            report.stage("checking", 0);
            let file = SptFile::open(path)?;
            report.stage("indexing", 0);
            let index = PrefixIndex::new(&file.meta, file.nodes());
            return Ok(Scene {
                tree: TreeSource::File(file),
                index,
                mesh: None,
            });
        }
        report.stage("reading", 0);
        let model = read_ply(path)?;
        report.stage("surfels", 0);
        let mut leaves = leaf_surfels(&model.geometry);
        let mesh = (!model.geometry.triangles.is_empty()).then(|| MeshData {
            positions: leaves.surfels.iter().map(|s| s.position).collect(),
            normals: leaves.surfels.iter().map(|s| s.normal).collect(),
            colors: leaves.surfels.iter().map(|s| s.color).collect(),
            triangles: model.geometry.triangles.clone(),
        });
        drop(model);
        report.stage("tree", leaves.surfels.len() as u64);
        let hierarchy = build_hierarchy(&mut leaves, &|n| report.advance(n));
        report.stage("errors", hierarchy.internal.len() as u64);
        let set = build_records(leaves, hierarchy, &|n| report.advance(n));
        report.stage("sorting", 0);
        let list = sort_list(set);
        report.stage("indexing", 0);
        Ok(Scene::from_list(list, mesh))
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
}
