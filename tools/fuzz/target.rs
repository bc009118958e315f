//! One input through everything a reader feeds, with the invariants checked at every
//! stage of a success:
//!
//! * PLY: read, and read a window at a time ([`PlyStream`]: the same rows and
//!   triangles) → [`Geometry::check`] → leaf surfels → [`LeafSurfels::check`] → tree →
//!   meta, node and structure checks → `.spt` written and reopened (which validates it
//!   again) → the same list back → a prefix search from a few eyes.
//! * LAS and LAZ: read, then as PLY from [`Geometry::check`] on.
//! * `.spt`: open (checksum, header, nodes) → meta and node checks → a prefix search →
//!   written again and reopened → the same list back.
//!
//! Every 16th accepted PLY, LAS or LAZ input is also built out of core in jobs of 64
//! points ([`out_of_core`]): it must build, validate, and hold a leaf for every sample
//! the in-memory build holds one for (a terrain's walls, found by each job among its
//! own samples and halo, may differ near a job's border; a sensor frame, whose pixel
//! grid the jobs do not see, is not compared).
//!
//! A refusal (an error) is a fine outcome; a violated invariant is not.
//!
//! [`Geometry::check`]: spt::io::Geometry::check
//! [`LeafSurfels::check`]: spt::surfel::LeafSurfels::check

use std::path::Path;

use glam::DVec3;
use spt::io::Geometry;
use spt::io::las::read_las;
use spt::io::ply::{PlyStream, read_ply};
use spt::surfel::leaf_surfels;
use spt::tree::instances::table::read_instances;
use spt::tree::instances::{Instance, read_scene};
use spt::tree::out_of_core::{Options, Progress, build_file};
use spt::tree::select::PrefixIndex;
use spt::tree::spt_file::{SptFile, write_to};
use spt::tree::validate::{check_chunks, check_meta, check_nodes, check_structure};
use spt::tree::{SequentialList, build_sequential_list};

use crate::seeds::Kind;

/// How a run ended, when it did not panic.
pub enum Outcome {
    /// With the tree's leaves that are samples, not walls, which the out-of-core build
    /// must match; `None` where it need not: an input that is no model file (`.spt`,
    /// scene, instances), or a sensor frame, whose pixel grid only the file's row order
    /// shows (out of core, its points are those of any cloud).
    Accepted {
        samples: Option<u64>,
    },
    Refused,
    Violation(String),
}

fn violation(stage: &str) -> impl Fn(String) -> Outcome + '_ {
    move |why| Outcome::Violation(format!("{stage}: {why}"))
}

/// Writes `list` next to `at` (as `.spt`) and opens it again: the same list, valid.
fn round_trip(list: &SequentialList, at: &Path) -> Result<(), Outcome> {
    let path = at.with_extension("out.spt");
    let mut bytes = Vec::with_capacity(256 + 36 * list.nodes.len());
    write_to(&mut bytes, list).map_err(|e| Outcome::Violation(format!("write: {e}")))?;
    std::fs::write(&path, &bytes).map_err(|e| Outcome::Violation(format!("write: {e}")))?;
    let back = SptFile::open(&path).map_err(|e| Outcome::Violation(format!("reopen: {e}")))?;
    if back.to_list() != *list {
        return Err(Outcome::Violation("reopened list differs".into()));
    }
    Ok(())
}

/// The prefix search from the centre, a corner and far away, at a few budgets.
fn select(list: &SequentialList) -> Result<(), Outcome> {
    let index = PrefixIndex::new(&list.meta, &list.chunks, &list.nodes);
    let lo = DVec3::from(list.meta.centre_min.map(f64::from));
    let hi = DVec3::from(list.meta.centre_max.map(f64::from));
    for eye in [(lo + hi) * 0.5, lo, hi * 10.0 + DVec3::ONE] {
        for eps in [0.0, 1e-3, 1.0] {
            for r in index.ranges(&list.nodes, eye, eps, None) {
                if r.end > list.nodes.len() || r.is_empty() {
                    return Err(Outcome::Violation(format!("range {r:?} beyond the list")));
                }
            }
        }
    }
    Ok(())
}

/// Geometry read from the input at `path`, through surfels, tree, search and `.spt`.
fn build(geometry: &Geometry, path: &Path) -> Result<Outcome, Outcome> {
    geometry.check().map_err(violation("geometry"))?;
    if geometry.positions.is_empty() {
        // Nothing to draw: what the commands that draw refuse (`ModelError::Empty`).
        return Ok(Outcome::Refused);
    }
    let leaves = leaf_surfels(geometry);
    leaves.check().map_err(violation("surfels"))?;
    let walls = leaves.stats.added_splats();
    let frame = leaves.stats.pixel_grid.is_some();
    let list = build_sequential_list(leaves);
    check_meta(&list.meta).map_err(violation("tree meta"))?;
    check_nodes(&list.meta, &list.nodes, &list.parents).map_err(violation("tree nodes"))?;
    check_chunks(&list.nodes, &list.chunks).map_err(violation("tree chunks"))?;
    check_structure(&list.meta, &list.nodes, &list.parents, &list.chunks)
        .map_err(violation("tree"))?;
    select(&list)?;
    round_trip(&list, path)?;
    Ok(Outcome::Accepted {
        samples: (!frame).then_some(list.meta.leaf_count - walls),
    })
}

fn ply(path: &Path) -> Result<Outcome, Outcome> {
    let streamed = streamed(path);
    match read_ply(path) {
        Ok(model) => {
            let (rows, triangles) =
                streamed.map_err(violation("stream refuses what read_ply reads"))?;
            if rows != model.stats.vertices_in_file {
                return Err(violation("stream")(format!("{rows} vertex rows")));
            }
            // With no vertex dropped, the triangles are the file's, in its order.
            if model.geometry.rows.is_none() && triangles != model.geometry.triangles {
                return Err(violation("stream")("other triangles".to_owned()));
            }
            build(&model.geometry, path)
        }
        Err(_) => Ok(Outcome::Refused),
    }
}

/// The file read a window at a time (windows of 5 rows): its vertex rows and triangles.
fn streamed(path: &Path) -> Result<(u64, Vec<[u32; 3]>), String> {
    let stream = PlyStream::open(path)
        .map_err(|e| e.to_string())?
        .with_window(5);
    let mut rows = 0;
    stream
        .vertices(|b| rows += b.xyz.len() as u64)
        .map_err(|e| e.to_string())?;
    let mut triangles = Vec::new();
    stream
        .triangles(|t| triangles.extend_from_slice(t))
        .map_err(|e| e.to_string())?;
    Ok((rows, triangles))
}

fn las(path: &Path) -> Result<Outcome, Outcome> {
    match read_las(path) {
        Ok(model) => build(&model.geometry, path),
        Err(_) => Ok(Outcome::Refused),
    }
}

fn spt(path: &Path) -> Result<Outcome, Outcome> {
    let Ok(file) = SptFile::open(path) else {
        return Ok(Outcome::Refused);
    };
    let list = file.to_list();
    check_meta(&list.meta).map_err(violation("meta"))?;
    check_nodes(&list.meta, &list.nodes, &list.parents).map_err(violation("nodes"))?;
    check_chunks(&list.nodes, &list.chunks).map_err(violation("chunks"))?;
    select(&list)?;
    round_trip(&list, path)?;
    Ok(Outcome::Accepted { samples: None })
}

/// Runs the input stored at `path`.
pub fn run(kind: Kind, path: &Path) -> Outcome {
    let result = match kind {
        Kind::Ply => ply(path),
        Kind::Spt => spt(path),
        Kind::Las | Kind::Laz => las(path),
        Kind::Scene => scene(path),
        Kind::Instances => instances(path),
    };
    result.unwrap_or_else(|o| o)
}

/// A scene file: read (its instance files too); every instance in range, finite, of
/// positive scale and unit rotation.
fn scene(path: &Path) -> Result<Outcome, Outcome> {
    let scene = read_scene(path).map_err(|_| Outcome::Refused)?;
    check_instances(&scene.instances, scene.models.len())?;
    Ok(Outcome::Accepted { samples: None })
}

/// An instance file, for a scene of two models: as [`scene`].
fn instances(path: &Path) -> Result<Outcome, Outcome> {
    let mut out = Vec::new();
    read_instances(path, 2, &mut out).map_err(|_| Outcome::Refused)?;
    check_instances(&out, 2)?;
    Ok(Outcome::Accepted { samples: None })
}

fn check_instances(instances: &[Instance], models: usize) -> Result<(), Outcome> {
    for (k, i) in instances.iter().enumerate() {
        let s = i.similarity();
        let fine = (i.model as usize) < models
            && s.translation.is_finite()
            && s.scale.is_finite()
            && s.scale > 0.0
            && (s.rotation.length() - 1.0).abs() < 1e-6;
        if !fine {
            return Err(Outcome::Violation(format!("instance {k} accepted: {i:?}")));
        }
    }
    Ok(())
}

/// An accepted PLY, LAS or LAZ input built out of core in jobs of 64 points: it builds,
/// opens and validates, with a leaf for each of the `samples` the in-memory build made
/// one for, besides its walls.
pub fn out_of_core(path: &Path, samples: u64) -> Outcome {
    struct Quiet;
    impl Progress for Quiet {
        fn stage(&self, _: &'static str, _: u64) {}
        fn advance(&self, _: u64) {}
    }
    let dir = path.with_extension("ooc");
    if let Err(e) = std::fs::create_dir_all(&dir) {
        return Outcome::Violation(format!("temporary folder: {e}"));
    }
    let options = Options {
        job_points: 64,
        spill_buffers: 1 << 16,
        temp_dir: dir.clone(),
    };
    let out = dir.join("out.spt");
    let built = build_file(path, &out, &options, &Quiet);
    let outcome = match built.map(|b| (SptFile::open(&out), b.walls)) {
        Err(e) => Outcome::Violation(format!("out of core refuses what the reader reads: {e:#}")),
        Ok((Err(e), _)) => Outcome::Violation(format!("out of core wrote a bad file: {e}")),
        Ok((Ok(f), walls)) if f.meta.leaf_count.checked_sub(walls) != Some(samples) => {
            Outcome::Violation(format!(
                "out of core: {} leaves with {walls} walls, in memory {samples} samples",
                f.meta.leaf_count
            ))
        }
        Ok(_) => Outcome::Accepted {
            samples: Some(samples),
        },
    };
    let _ = std::fs::remove_dir_all(&dir);
    outcome
}
