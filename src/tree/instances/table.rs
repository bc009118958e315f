//! Instance files: a PLY with one vertex per instance, for sets too large to list in a
//! scene file (10⁶ instances read in a fraction of a second). Properties, by name:
//! `x y z` (the translation, double for geo-referenced scenes), `scale` (default 1),
//! the rotation as `qx qy qz qw` (a unit quaternion) or `yaw` (radians about z; default
//! none), and `model` (the index among the scene's models; default 0). `spt scatter`
//! writes them ([`write_instances`]).

use std::path::Path;

use glam::{DQuat, DVec3};

use super::Instance;
use crate::io::atomic::write_atomically;
use crate::io::ply::table::{Column, read_table};

const fn column(names: &'static [&'static str], required: bool) -> Column<'static> {
    Column { names, required }
}

/// The columns read, in this order.
const COLUMNS: [Column; 10] = [
    column(&["x"], true),
    column(&["y"], true),
    column(&["z"], true),
    column(&["scale"], false),
    column(&["qx"], false),
    column(&["qy"], false),
    column(&["qz"], false),
    column(&["qw"], false),
    column(&["yaw"], false),
    column(&["model"], false),
];

/// Appends the instances of the instance PLY `path` to `out`, each checked against a
/// scene of `models` models.
pub fn read_instances(path: &Path, models: usize, out: &mut Vec<Instance>) -> anyhow::Result<()> {
    read_table(path, "vertex", &COLUMNS, |_, v| {
        let translation = DVec3::new(
            v[0].unwrap_or(0.0),
            v[1].unwrap_or(0.0),
            v[2].unwrap_or(0.0),
        );
        let rotation = match (v[4], v[5], v[6], v[7], v[8]) {
            (Some(x), Some(y), Some(z), Some(w), _) => DQuat::from_xyzw(x, y, z, w),
            (_, _, _, _, Some(yaw)) => DQuat::from_rotation_z(yaw),
            _ => DQuat::IDENTITY,
        };
        let model = v[9].unwrap_or(0.0);
        if model.fract() != 0.0 || model < 0.0 {
            return Err(format!("model {model} is not an index"));
        }
        let scale = v[3].unwrap_or(1.0);
        out.push(Instance::checked(
            model as usize,
            translation,
            rotation,
            scale,
            models,
        )?);
        Ok(())
    })?;
    Ok(())
}

/// Writes `instances` to `path` (binary PLY: x y z as double, scale, qx qy qz qw as
/// float, model as uint), atomically.
pub fn write_instances(path: &Path, instances: &[Instance]) -> anyhow::Result<()> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment spt instances (docs/scenes.md)\n\
         element vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property float scale\nproperty float qx\nproperty float qy\nproperty float qz\n\
         property float qw\nproperty uint model\nend_header\n",
        instances.len()
    );
    let mut bytes = header.into_bytes();
    bytes.reserve(instances.len() * 48);
    for i in instances {
        for t in i.translation {
            bytes.extend_from_slice(&t.to_le_bytes());
        }
        bytes.extend_from_slice(&i.scale.to_le_bytes());
        for q in i.rotation {
            bytes.extend_from_slice(&q.to_le_bytes());
        }
        bytes.extend_from_slice(&i.model.to_le_bytes());
    }
    write_atomically(path, |w| w.write_all(&bytes))?;
    Ok(())
}
