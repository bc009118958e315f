//! The scene file (JSON, docs/scenes.md): the models, each stored once, and where each
//! is drawn. An instance is a model index with a translation (f64: scenes are
//! geo-referenced), a rotation (a unit quaternion `[x, y, z, w]`, or a yaw in degrees
//! about z) and a uniform scale; an instance with none of them draws its model as stored
//! (a terrain under a forest). Large sets come from an instance PLY ([`super::table`])
//! named by a `{"file": …}` entry. Paths are relative to the scene file.
//!
//! ```json
//! { "models": ["terrain.spt", "tree.spt"],
//!   "instances": [ {"model": 0},
//!                  {"model": 1, "translation": [512300.5, 5403100.0, 210.0], "yaw": 30, "scale": 1.2},
//!                  {"file": "forest.ply"} ] }
//! ```

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use glam::{DQuat, DVec3};
use serde::Deserialize;

use super::Instance;

/// A scene file as written: model paths and instance entries.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneText {
    models: Vec<PathBuf>,
    instances: Vec<Entry>,
}

/// One entry of `instances`: one instance, or a file of them.
#[derive(Debug, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
enum Entry {
    File {
        file: PathBuf,
    },
    One {
        model: usize,
        #[serde(default)]
        translation: Option<[f64; 3]>,
        #[serde(default)]
        rotation: Option<[f64; 4]>,
        #[serde(default)]
        yaw: Option<f64>,
        #[serde(default)]
        scale: Option<f64>,
    },
}

/// A scene file read and checked: its models' paths (resolved) and its instances.
#[derive(Debug)]
pub struct SceneFile {
    pub models: Vec<PathBuf>,
    pub instances: Vec<Instance>,
}

/// Whether `path` names a scene file (by its `.json` extension).
pub fn is_scene(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// Reads the scene file at `path`: every model index in range, every transform finite,
/// every scale positive; the errors name the file and the entry.
pub fn read_scene(path: &Path) -> anyhow::Result<SceneFile> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the scene", path.display()))?;
    let parsed: SceneText = serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}: line {}, column {}: {} (docs/scenes.md gives the format)",
            path.display(),
            e.line(),
            e.column(),
            e
        )
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));
    if parsed.models.is_empty() {
        bail!("{}: the scene names no model", path.display());
    }
    let models: Vec<PathBuf> = parsed.models.iter().map(|m| dir.join(m)).collect();
    let mut instances = Vec::new();
    for (k, entry) in parsed.instances.into_iter().enumerate() {
        let at = |what: String| anyhow::anyhow!("{}: instances[{k}]: {what}", path.display());
        match entry {
            Entry::File { file } => {
                let file = dir.join(file);
                super::table::read_instances(&file, models.len(), &mut instances)?;
            }
            Entry::One {
                model,
                translation,
                rotation,
                yaw,
                scale,
            } => {
                let rotation = match (rotation, yaw) {
                    (Some(_), Some(_)) => return Err(at("both a rotation and a yaw".into())),
                    (Some([x, y, z, w]), None) => DQuat::from_xyzw(x, y, z, w),
                    (None, Some(deg)) => DQuat::from_rotation_z(deg.to_radians()),
                    (None, None) => DQuat::IDENTITY,
                };
                let translation = DVec3::from(translation.unwrap_or_default());
                let instance = Instance::checked(
                    model,
                    translation,
                    rotation,
                    scale.unwrap_or(1.0),
                    models.len(),
                )
                .map_err(at)?;
                instances.push(instance);
            }
        }
    }
    if instances.is_empty() {
        bail!("{}: the scene places no instance", path.display());
    }
    Ok(SceneFile { models, instances })
}
