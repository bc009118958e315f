//! What the renderer draws: a sequential list (built from a PLY file in memory, or a
//! memory-mapped `.spt`), its prefix index, and for meshes the triangles of the
//! reference pass.

use std::path::Path;

use glam::Vec3;

use crate::io::ply::read_ply;
use crate::io::spt_file::{SptFile, is_spt};
use crate::surfel::leaf_surfels;
use crate::tree::select::PrefixIndex;
use crate::tree::{NodeRecord, SequentialList, TreeMeta, build_sequential_list};

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
        if is_spt(path) {
            let file = SptFile::open(path)?;
            let index = PrefixIndex::new(&file.meta, file.nodes());
            return Ok(Scene {
                tree: TreeSource::File(file),
                index,
                mesh: None,
            });
        }
        let model = read_ply(path)?;
        let leaves = leaf_surfels(&model.geometry);
        let mesh = (!model.geometry.triangles.is_empty()).then(|| MeshData {
            positions: leaves.surfels.iter().map(|s| s.position).collect(),
            normals: leaves.surfels.iter().map(|s| s.normal).collect(),
            colors: leaves.surfels.iter().map(|s| s.color).collect(),
            triangles: model.geometry.triangles.clone(),
        });
        Ok(Scene::from_list(build_sequential_list(leaves), mesh))
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
