//! One job of a mesh's out-of-core build: its vertices, their halo and the triangles
//! its surfels read ([`super::mesh_spill`]) in, its subtree out, in two runs.
//!
//! A mesh's normals turn outward by a vote of all its vertices
//! ([`crate::surfel::mesh::orient_outward`]), and a vertex's ellipse and shading field
//! are fitted to its oriented normals. So the plan takes the whole vote first, from
//! every job's terms ([`flux`]: each vertex's normal and radius from its faces, cheap
//! beside a build), and a job is built ([`build`]) with that orientation given. It
//! returns its own vertices' terms with its part, and the join checks that they add up
//! to the same decision. Otherwise a job is built as a cloud's is: leaf surfels of its
//! own vertices, tree with the model's error scale, chunks, part file.

use std::path::Path;

use glam::{DVec3, Vec3};

use super::job::{Built, Model, build_leaves};
use super::mesh_spill::MeshVertex;
use super::spill::read_records;
use crate::io::Geometry;
use crate::surfel::outward::Vote;
use crate::surfel::{mesh_flux_of, mesh_surfels_of};

/// A job's spill files: own vertices, halo vertices, triangles.
pub type Files<'a> = (&'a Path, &'a Path, &'a Path);

/// Where each file index lies in a job's vertex file (whose indices ascend): a table
/// over the span of its indices when they are dense enough (a mesh whose vertices are
/// stored in spatial order), else a binary search.
enum LocalIndex {
    Table { first: u32, slots: Vec<u32> },
    Search(Vec<u32>),
}

impl LocalIndex {
    /// A table when the span is at most this many times the vertices.
    const DENSE: u64 = 4;

    fn of(vertices: &[MeshVertex]) -> LocalIndex {
        let indices: Vec<u32> = vertices.iter().map(|m| m.index).collect();
        let (Some(&first), Some(&last)) = (indices.first(), indices.last()) else {
            return LocalIndex::Search(indices);
        };
        let span = u64::from(last - first) + 1;
        if span > Self::DENSE * indices.len() as u64 {
            return LocalIndex::Search(indices);
        }
        let mut slots = vec![u32::MAX; span as usize];
        for (k, &v) in indices.iter().enumerate() {
            slots[(v - first) as usize] = k as u32;
        }
        LocalIndex::Table { first, slots }
    }

    fn get(&self, v: u32) -> Option<u32> {
        match self {
            LocalIndex::Table { first, slots } => v
                .checked_sub(*first)
                .and_then(|k| slots.get(k as usize))
                .copied()
                .filter(|&k| k != u32::MAX),
            LocalIndex::Search(indices) => indices.binary_search(&v).ok().map(|k| k as u32),
        }
    }
}

/// The geometry of a job (its own vertices first, then its halo, triangles in those
/// indices) and its count of own vertices.
fn geometry(model: &Model, (own, halo, triangles): Files) -> anyhow::Result<(Geometry, usize)> {
    let own_vertices: Vec<MeshVertex> = read_records(own)?;
    let halo_vertices: Vec<MeshVertex> = read_records(halo)?;
    let mut tris: Vec<[u32; 3]> = read_records(triangles)?;
    let n = own_vertices.len();
    let own_index = LocalIndex::of(&own_vertices);
    let halo_index = LocalIndex::of(&halo_vertices);
    let local = |v: u32| -> Option<u32> {
        own_index
            .get(v)
            .or_else(|| halo_index.get(v).map(|k| n as u32 + k))
    };
    for t in &mut tris {
        for v in t.iter_mut() {
            *v = local(*v).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: triangle vertex {v} is in neither vertex file of its job",
                    triangles.display()
                )
            })?;
        }
    }
    let all = || own_vertices.iter().chain(&halo_vertices);
    let g = Geometry {
        origin: model.origin,
        bounds: model.bounds,
        core: model.core,
        positions: all().map(|m| Vec3::from(m.position)).collect(),
        normals: model
            .has_normals
            .then(|| all().map(|m| Vec3::from(m.normal)).collect()),
        colors: model.has_colors.then(|| all().map(|m| m.color).collect()),
        triangles: tris,
        rows: None,
        attributes: None,
    };
    Ok((g, n))
}

/// The job's own vertices' terms of the orientation vote, about the model's mean
/// vertex `c` (relative to the origin).
pub fn flux(model: &Model, files: Files, c: DVec3) -> anyhow::Result<Vote> {
    let (g, own) = geometry(model, files)?;
    Ok(mesh_flux_of(&g, own, c))
}

/// Builds the job into `part`, its normals negated when `turn`; returns its part and
/// its terms of the orientation vote about `c` ([`flux`]).
pub fn build(
    model: &Model,
    files: Files,
    (turn, c): (bool, DVec3),
    part: &Path,
) -> anyhow::Result<(Built, Vote)> {
    let (g, own) = geometry(model, files)?;
    anyhow::ensure!(own > 0, "{}: a job without vertices", files.0.display());
    let (leaves, vote) = mesh_surfels_of(&g, own, (turn, c));
    drop(g);
    Ok((build_leaves(model, leaves, Vec::new(), part)?, vote))
}
