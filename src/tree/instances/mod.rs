//! Scenes of many placed models: each distinct model stored once ([`Scene`]), drawn at
//! many similarities (instances), each instance selecting its own level of detail from
//! its own distance ([`similarity`] states why the selection holds per instance).
//!
//! ```text
//! scene file (JSON) ─► models (PLY, LAS, LAZ, .spt, each opened once) + instances
//!                      (inline, or instance PLYs) ─► groups (spatial, for culling)
//! each frame: groups ─► visible instances ─► per instance, its model's prefixes (lod)
//! ```
//!
//! An instance costs 48 bytes here ([`Instance`]); its model's nodes are shared.

pub mod file;
pub mod groups;
pub mod lod;
pub mod scatter;
pub mod similarity;
pub mod table;

use std::path::Path;

use glam::{DQuat, DVec3};

pub use file::{is_scene, read_scene};
pub use groups::Groups;
pub use similarity::Similarity;

use super::TreeMeta;
use super::report::Report;
use super::scene::Scene;
use crate::io::Bounds;

/// One placed copy of a model: x ↦ translation + scale · R(rotation) x, x in the
/// model's file coordinates. 48 bytes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instance {
    pub translation: [f64; 3],
    /// A unit quaternion, (x, y, z, w).
    pub rotation: [f32; 4],
    pub scale: f32,
    /// The model's index in the scene.
    pub model: u32,
}

const _: () = assert!(std::mem::size_of::<Instance>() == 48);

impl Instance {
    /// An instance of `model` (one of `models`), its transform checked: finite, a
    /// rotation of non-zero length (normalised here), a positive scale.
    pub fn checked(
        model: usize,
        translation: DVec3,
        rotation: DQuat,
        scale: f64,
        models: usize,
    ) -> Result<Instance, String> {
        if model >= models {
            return Err(format!(
                "model {model} is not among the scene's {models} models"
            ));
        }
        if !translation.is_finite() {
            return Err(format!("translation {translation} is not finite"));
        }
        let length = rotation.length();
        if !rotation.is_finite() || length < 1e-6 {
            return Err(format!(
                "rotation {rotation} is not a rotation (a quaternion of non-zero length)"
            ));
        }
        if !(scale.is_finite() && scale > 0.0 && (scale as f32) > 0.0) {
            return Err(format!("scale {scale} is not positive and finite"));
        }
        let q = rotation / length;
        Ok(Instance {
            translation: translation.to_array(),
            rotation: [q.x, q.y, q.z, q.w].map(|c| c as f32),
            scale: scale as f32,
            model: model as u32,
        })
    }

    /// The map from the model's file coordinates to the world.
    pub fn similarity(&self) -> Similarity {
        let [x, y, z, w] = self.rotation.map(f64::from);
        Similarity {
            translation: DVec3::from(self.translation),
            rotation: DQuat::from_xyzw(x, y, z, w).normalize(),
            scale: self.scale as f64,
        }
    }
}

/// A scene: its models, each opened once, and its instances, sorted into spatial
/// groups.
pub struct InstancedScene {
    pub models: Vec<Scene>,
    /// The model files, as the scene file names them.
    pub model_paths: Vec<std::path::PathBuf>,
    pub instances: Vec<Instance>,
    pub groups: Groups,
    /// The whole scene as one model would describe it (world bounds, origin at their
    /// centre, the first model's up): what cameras are framed and planned with.
    pub meta: TreeMeta,
}

impl InstancedScene {
    /// Reads the scene file `path` and opens each of its models once (in parallel),
    /// telling `report` each model's steps.
    pub fn open(path: &Path, report: &dyn Report) -> anyhow::Result<InstancedScene> {
        let file = read_scene(path)?;
        // In parallel: opening a model is mostly checking its checksum.
        use rayon::prelude::*;
        let models = (file.models.par_iter())
            .map(|m| {
                Scene::open_reporting(m, report).map_err(|e| {
                    anyhow::anyhow!("{}: model {}: {e:#}", path.display(), m.display())
                })
            })
            .collect::<anyhow::Result<Vec<Scene>>>()?;
        Ok(InstancedScene::new(models, file.models, file.instances))
    }

    /// The scene of `models` drawn at `instances` (each one's model in range).
    pub fn new(
        models: Vec<Scene>,
        model_paths: Vec<std::path::PathBuf>,
        mut instances: Vec<Instance>,
    ) -> InstancedScene {
        let spheres: Vec<(DVec3, f64)> = models.iter().map(|m| model_sphere(m.meta())).collect();
        let groups = Groups::sort(&mut instances, &spheres);
        let meta = scene_meta(&models, &instances);
        InstancedScene {
            models,
            model_paths,
            instances,
            groups,
            meta,
        }
    }

    /// The scene's box as one chunk (of no node), to frame cameras on.
    pub fn frame_chunk(&self) -> crate::tree::chunks::Chunk {
        crate::tree::chunks::Chunk {
            start: 0,
            count: 0,
            level: 0,
            centre_min: self.meta.centre_min,
            centre_max: self.meta.centre_max,
            radius_max: 0.0,
            error_min: 0.0,
        }
    }

    /// CPU bytes an instance costs: its record and its share of the group table,
    /// rounded up.
    pub fn bytes_per_instance(&self) -> u64 {
        let n = self.instances.len().max(1) as u64;
        std::mem::size_of::<Instance>() as u64 + self.groups.bytes().div_ceil(n)
    }

    /// Instances of model `m`.
    pub fn count_of(&self, m: usize) -> usize {
        self.instances
            .iter()
            .filter(|i| i.model as usize == m)
            .count()
    }
}

/// A model's bounding sphere in its file coordinates: about the centre of its box of
/// node centres, reaching every node's disk.
pub fn model_sphere(meta: &TreeMeta) -> (DVec3, f64) {
    let lo = DVec3::from(meta.centre_min.map(f64::from));
    let hi = DVec3::from(meta.centre_max.map(f64::from));
    let reach = meta
        .bounds
        .max
        .iter()
        .zip(meta.bounds.min)
        .map(|(a, b)| a - b)
        .fold(0.0, f64::max);
    let radius = 0.5 * (hi - lo).length() + 0.01 * reach;
    (
        DVec3::from(meta.origin) + 0.5 * (lo + hi),
        radius.max(f64::MIN_POSITIVE),
    )
}

/// The description of the whole scene as one model's: the box of every instance's
/// transformed box, the origin at its centre, the first model's up and error scale.
fn scene_meta(models: &[Scene], instances: &[Instance]) -> TreeMeta {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for i in instances {
        let meta = models[i.model as usize].meta();
        let s = i.similarity();
        for corner in corners(&meta.bounds) {
            let p = s.apply(corner);
            (lo, hi) = (lo.min(p), hi.max(p));
        }
    }
    let first = models[0].meta();
    let mut meta = first.clone();
    let centre = 0.5 * lo + 0.5 * hi;
    meta.origin = centre.to_array();
    meta.bounds = Bounds {
        min: lo.to_array(),
        max: hi.to_array(),
    };
    meta.centre_min = (lo - centre).as_vec3().to_array();
    meta.centre_max = (hi - centre).as_vec3().to_array();
    meta.leaf_count = models.iter().map(|m| m.meta().leaf_count).sum();
    meta.node_count = models.iter().map(|m| m.meta().node_count).sum();
    meta.oriented_normals = models.iter().all(|m| m.meta().oriented_normals);
    meta.two_sided = models.iter().any(|m| m.meta().two_sided);
    meta.has_attributes = models.iter().any(|m| m.meta().has_attributes);
    meta.has_colors = models.iter().any(|m| m.meta().has_colors);
    if models
        .iter()
        .any(|m| m.meta().normals_turned != first.normals_turned)
    {
        // Only what every model's normals share is drawn as such.
        meta.normals_turned = crate::surfel::NormalsTurned::No;
    }
    meta
}

/// The 8 corners of a box.
fn corners(b: &Bounds) -> [DVec3; 8] {
    std::array::from_fn(|k| {
        DVec3::new(
            if k & 1 == 0 { b.min[0] } else { b.max[0] },
            if k & 2 == 0 { b.min[1] } else { b.max[1] },
            if k & 4 == 0 { b.min[2] } else { b.max[2] },
        )
    })
}
