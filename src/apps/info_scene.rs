//! `spt info SCENE.json`: what a scene of instances holds: its models (nodes, the
//! instances of each), its instances and their groups, its box, and what it costs in
//! memory beyond its models.

use std::path::Path;

use serde::Serialize;

use crate::apps::text::count;
use crate::tree::instances::InstancedScene;
use crate::tree::report::Silent;

/// One model of a scene.
#[derive(Debug, Serialize)]
struct ModelLine {
    path: String,
    nodes: u64,
    leaves: u64,
    instances: usize,
}

/// What `spt info` reports of a scene.
#[derive(Debug, Serialize)]
pub struct SceneInfo {
    path: String,
    models: Vec<ModelLine>,
    instances: usize,
    groups: usize,
    bounds_min: [f64; 3],
    bounds_max: [f64; 3],
    /// CPU bytes an instance costs (its record and its share of the group table).
    bytes_per_instance: u64,
    /// Reading the scene and opening its models, ms.
    open_ms: f64,
}

impl SceneInfo {
    pub fn gather(path: &Path) -> anyhow::Result<SceneInfo> {
        let started = std::time::Instant::now();
        let scene = InstancedScene::open(path, &Silent)?;
        let open_ms = started.elapsed().as_secs_f64() * 1e3;
        let models = (scene.models.iter().zip(&scene.model_paths).enumerate())
            .map(|(m, (model, p))| ModelLine {
                path: p.display().to_string(),
                nodes: model.meta().node_count,
                leaves: model.meta().leaf_count,
                instances: scene.count_of(m),
            })
            .collect();
        Ok(SceneInfo {
            path: path.display().to_string(),
            models,
            instances: scene.instances.len(),
            groups: scene.groups.len(),
            bounds_min: scene.meta.bounds.min,
            bounds_max: scene.meta.bounds.max,
            bytes_per_instance: scene.bytes_per_instance(),
            open_ms,
        })
    }

    pub fn to_text(&self) -> String {
        let mut out = format!("scene         {}\n", self.path);
        for (k, m) in self.models.iter().enumerate() {
            out += &format!(
                "model {k:<7} {} ({} nodes, {} leaves): {} instances\n",
                m.path,
                count(m.nodes),
                count(m.leaves),
                count(m.instances as u64)
            );
        }
        let drawn: u64 = self
            .models
            .iter()
            .map(|m| m.leaves * m.instances as u64)
            .sum();
        out += &format!(
            "instances     {} in {} groups of up to 64; {} leaves drawn at leaves only\n",
            count(self.instances as u64),
            count(self.groups as u64),
            count(drawn)
        );
        let [a, b, c] = self.bounds_min;
        let [x, y, z] = self.bounds_max;
        out += &format!("bbox min      {a} {b} {c}\nbbox max      {x} {y} {z}\n");
        out += &format!(
            "memory        {} B an instance beyond its model (CPU; the GPU adds 56 B: docs/scenes.md)\n",
            self.bytes_per_instance
        );
        out += &format!(
            "open          {:.1} ms (the scene and its models)\n",
            self.open_ms
        );
        out
    }
}

pub fn run(path: &Path, json: bool) -> anyhow::Result<()> {
    let info = SceneInfo::gather(path)?;
    if json {
        say!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        crate::apps::say_text(&info.to_text());
    }
    Ok(())
}
