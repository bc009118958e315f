//! The spill of a mesh: every vertex to its job (by its cell, as a cloud's point), and
//! every triangle and vertex that a job's surfels read to that job, found by passes
//! over the file's vertices and faces without holding either.
//!
//! A vertex's surfel reads its one-ring (normal, radius, ellipse) and the normals of
//! its one-ring's vertices (its shading field, [`crate::surfel::field`]), which read
//! their own one-rings. So job J needs:
//! * V1(J): its own vertices and their neighbours, whose normals must be exact;
//! * T2(J): every triangle incident to a vertex of V1(J), so that those normals are;
//! * every vertex of T2(J).
//!
//! With `own(v)` the job of vertex v, v ∈ V1(J) iff J = own(v) or J = own(u) for a
//! neighbour u of v: pass 1 over the triangles records the second kind as pairs
//! (v, J) (the **ring** pairs; none for a triangle whose three vertices share a job).
//! A triangle t is in T2(J) iff J ∈ S(t) = ∪_{v ∈ t} ({own(v)} ∪ ring(v)): pass 2
//! writes t to the triangle file of every job of S(t), and records (v, J) for each
//! v ∈ t and J ∈ S(t) other than own(v) (the **halo** pairs). The vertex pass then
//! writes each vertex to its own job's file and to the halo file of each of its halo
//! pairs' jobs, in file order: each file's vertices ascend.
//!
//! Memory: 2 bytes per vertex for `own`, a bit per vertex for each list of pairs, and 8
//! bytes per pair, which only vertices near a job's border have (1–1.5 % of a job's
//! vertices are its halo on the Lucy-size mesh in 14 jobs).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use super::spill::{Grid, Scan, job_paths, spill_failed, writers};
use crate::io::formats::ModelStream;

/// `own` of a vertex that belongs to no job (one the scan drops: its triangles are
/// dropped, as the whole-file reader drops them).
pub const NO_JOB: u16 = u16::MAX;

/// A vertex as the mesh spill files hold it (32 bytes): its index in the file,
/// position relative to the origin, colour and given normal (zero when none).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct MeshVertex {
    pub index: u32,
    pub position: [f32; 3],
    pub color: [u8; 4],
    pub normal: [f32; 3],
}

/// The spill files of a mesh's jobs.
pub struct MeshFiles {
    pub own: Vec<PathBuf>,
    pub halo: Vec<PathBuf>,
    pub triangles: Vec<PathBuf>,
}

/// Sorted, deduplicated (vertex, job) pairs, each packed as `vertex << 16 | job`, and
/// a bit per vertex that has any.
struct Pairs {
    keys: Vec<u64>,
    has: Vec<u64>,
    /// Length at which the unsorted tail is sorted in.
    compact_at: usize,
}

impl Pairs {
    fn new(vertices: usize) -> Pairs {
        Pairs {
            keys: Vec::new(),
            has: vec![0; vertices.div_ceil(64)],
            compact_at: 1 << 20,
        }
    }

    fn push(&mut self, v: u32, job: u16) {
        self.keys.push(u64::from(v) << 16 | u64::from(job));
        self.has[v as usize / 64] |= 1 << (v % 64);
        if self.keys.len() >= self.compact_at {
            self.compact();
            self.compact_at = (2 * self.keys.len()).max(1 << 20);
        }
    }

    fn compact(&mut self) {
        self.keys.sort_unstable();
        self.keys.dedup();
    }

    /// The jobs paired with `v` (after [`Pairs::compact`]).
    fn jobs(&self, v: u32) -> impl Iterator<Item = u16> + '_ {
        let any = self.has[v as usize / 64] >> (v % 64) & 1 == 1;
        let keys = if any {
            let lo = self.keys.partition_point(|&k| k >> 16 < u64::from(v));
            let hi = self.keys[lo..].partition_point(|&k| k >> 16 == u64::from(v));
            &self.keys[lo..lo + hi]
        } else {
            &[][..]
        };
        keys.iter().map(|&k| k as u16)
    }
}

/// Pass over the vertices: each one's job by its cell ([`NO_JOB`] when the scan
/// drops it).
pub fn own_jobs(
    input: &ModelStream,
    (scan, grid): (&Scan, &Grid),
    table: &[u32],
) -> anyhow::Result<Vec<u16>> {
    let mut own = Vec::new();
    input.points(|b| {
        own.extend(b.xyz.iter().map(|p| {
            let p = DVec3::from(*p);
            if scan.keeps(p) {
                table[Grid::index(grid.locate(p).0)] as u16
            } else {
                NO_JOB
            }
        }))
    })?;
    Ok(own)
}

/// The jobs of a triangle's vertices, `None` when one has none.
fn jobs_of(t: &[u32; 3], own: &[u16]) -> Option<[u16; 3]> {
    let j = t.map(|v| own[v as usize]);
    (!j.contains(&NO_JOB)).then_some(j)
}

/// Pass 1 over the triangles: the ring pairs.
fn ring_pairs(input: &ModelStream, own: &[u16]) -> anyhow::Result<Pairs> {
    let mut ring = Pairs::new(own.len());
    input.triangles(|tris| {
        for t in tris {
            let Some(j) = jobs_of(t, own) else { continue };
            if j[0] == j[1] && j[1] == j[2] {
                continue;
            }
            for a in 0..3 {
                for b in 0..3 {
                    if j[b] != j[a] {
                        ring.push(t[a], j[b]);
                    }
                }
            }
        }
    })?;
    ring.compact();
    Ok(ring)
}

/// Pass 2 over the triangles: each to the file of every job of S(t); the halo pairs.
fn route_triangles(
    input: &ModelStream,
    (own, ring): (&[u16], &Pairs),
    (files, dir): (&mut [BufWriter<File>], &Path),
) -> anyhow::Result<Pairs> {
    let mut halo = Pairs::new(own.len());
    let mut failed = None;
    let mut jobs: Vec<u16> = Vec::with_capacity(8);
    input.triangles(|tris| {
        for t in tris {
            let Some(j) = jobs_of(t, own) else { continue };
            jobs.clear();
            for (k, &v) in t.iter().enumerate() {
                for job in std::iter::once(j[k]).chain(ring.jobs(v)) {
                    if !jobs.contains(&job) {
                        jobs.push(job);
                    }
                }
            }
            for &job in &jobs {
                if let Err(e) = files[job as usize].write_all(bytemuck::bytes_of(t)) {
                    failed.get_or_insert(e);
                }
                for (k, &v) in t.iter().enumerate() {
                    if job != j[k] {
                        halo.push(v, job);
                    }
                }
            }
        }
    })?;
    if let Some(e) = failed {
        return Err(spill_failed(dir, e));
    }
    halo.compact();
    Ok(halo)
}

/// The vertex pass: each vertex to its job's file and to its halo pairs' jobs' files.
fn spill_vertices(
    input: &ModelStream,
    (own, halo): (&[u16], &Pairs),
    origin: DVec3,
    (own_files, halo_files, dir): (&mut [BufWriter<File>], &mut [BufWriter<File>], &Path),
    mut progress: impl FnMut(u64),
) -> anyhow::Result<()> {
    let mut failed = None;
    let mut index = 0u32;
    let mut pairs = halo.keys.iter().peekable();
    input.points_ahead(|b| {
        for (i, p) in b.xyz.iter().enumerate() {
            let v = index;
            index += 1;
            let job = own[v as usize];
            if job == NO_JOB {
                continue;
            }
            let vertex = MeshVertex {
                index: v,
                position: (DVec3::from(*p) - origin).as_vec3().to_array(),
                color: b.color(i, true).unwrap_or(crate::surfel::DEFAULT_COLOR),
                normal: b.normals.get(i).copied().unwrap_or(Vec3::ZERO).to_array(),
            };
            let bytes = bytemuck::bytes_of(&vertex);
            let mut result = own_files[job as usize].write_all(bytes);
            while let Some(k) = pairs.next_if(|&&k| k >> 16 == u64::from(v)) {
                result = result.and(halo_files[*k as u16 as usize].write_all(bytes));
            }
            if let Err(e) = result {
                failed.get_or_insert(e);
            }
        }
        progress(b.xyz.len() as u64);
    })?;
    match failed {
        Some(e) => Err(spill_failed(dir, e)),
        None => Ok(()),
    }
}

/// Spills the mesh `input` into per-job files in `dir`: its vertices (`own`, from
/// [`own_jobs`]), their halos and triangles; `buffer_bytes` per open file.
pub fn spill(
    input: &ModelStream,
    own: &[u16],
    (origin, jobs): (DVec3, usize),
    dir: &Path,
    buffer_bytes: usize,
    progress: impl FnMut(u64),
) -> anyhow::Result<MeshFiles> {
    let name = |kind| job_paths(dir, jobs, kind);
    let files = MeshFiles {
        own: name("own"),
        halo: name("halo"),
        triangles: name("tri"),
    };
    let ring = ring_pairs(input, own)?;
    let mut tri_files = writers(&files.triangles, buffer_bytes)?;
    let halo = route_triangles(input, (own, &ring), (&mut tri_files, dir))?;
    drop(ring);
    for w in &mut tri_files {
        w.flush().map_err(|e| spill_failed(dir, e))?;
    }
    drop(tri_files);
    let mut own_files = writers(&files.own, buffer_bytes)?;
    let mut halo_files = writers(&files.halo, buffer_bytes)?;
    let out = (&mut own_files[..], &mut halo_files[..], dir);
    spill_vertices(input, (own, &halo), origin, out, progress)?;
    for w in own_files.iter_mut().chain(halo_files.iter_mut()) {
        w.flush().map_err(|e| spill_failed(dir, e))?;
    }
    Ok(files)
}
