//! Surfels of a triangle mesh, one per vertex (docs/design.md §2).
//!
//! * normal: normalize(Σ over incident triangles of (b − a) × (c − a)), the
//!   area-weighted face normals; a file's non-zero normal is kept instead.
//! * radius: the disks of a triangle's three vertices must cover it. The point of a
//!   triangle farthest from its nearest vertex is the circumcentre when the triangle
//!   is acute, and lies on the longest edge otherwise, at most half its length away
//!   from an endpoint. So each vertex takes the maximum over its triangles of
//!   R = abc / (4·area) (acute) or L/2 (right or obtuse, and zero-area triangles).
//!
//! Per-triangle terms are computed in f64 from the unit-scaled positions and the
//! radius is rounded up by [`super::triangle::RADIUS_MARGIN`] so that f32 storage never loses coverage.

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use super::cloud::neighbour_disks;
use super::covering::RadiusRule;
use super::outward::{Sides, Vote, orient_pieces};
use super::progress::{Progress, Stages};
use super::triangle::{RADIUS_MARGIN, triangle_terms};
use super::{Surfel, SurfelStats};
use crate::io::geometry::unit_vector;
use rayon::prelude::*;

/// A vertex's face normals cancel when |Σ cross| ≤ CANCELLED · Σ |cross|.
pub const CANCELLED: f32 = 1e-5;

/// A vertex position in unit-scaled f64.
#[inline]
fn at(points: &[Vec3], scale: f64, i: u32) -> DVec3 {
    points[i as usize].as_dvec3() * scale
}

/// Per-vertex sums over a run of triangles, for the vertices `lo..lo + radius.len()`
/// that the run touches (runs of a mesh in file order touch narrow vertex ranges).
struct Accumulator {
    lo: usize,
    normal_sum: Vec<Vec3>,
    area_sum: Vec<f32>,
    radius: Vec<f32>,
    degenerate: u64,
}

impl Accumulator {
    fn over(points: &[Vec3], scale: f64, triangles: &[[u32; 3]]) -> Self {
        let (lo, hi) = triangles
            .iter()
            .flatten()
            .fold((u32::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let (lo, len) = if triangles.is_empty() {
            (0, 0)
        } else {
            (lo as usize, (hi - lo) as usize + 1)
        };
        let mut acc = Accumulator {
            lo,
            normal_sum: vec![Vec3::ZERO; len],
            area_sum: vec![0.0; len],
            radius: vec![0.0; len],
            degenerate: 0,
        };
        for t in triangles {
            let [a, b, c] = t.map(|i| at(points, scale, i));
            let (cross, r, degenerate) = triangle_terms(a, b, c);
            let r = (r * (1.0 + RADIUS_MARGIN)) as f32;
            let (cross, area) = (cross.as_vec3(), cross.length() as f32);
            acc.degenerate += degenerate as u64;
            for &v in t {
                let v = v as usize - lo;
                acc.radius[v] = acc.radius[v].max(r);
                if !degenerate {
                    acc.normal_sum[v] += cross;
                    acc.area_sum[v] += area;
                }
            }
        }
        acc
    }

    /// (normal sum, area sum, radius) of vertex `v`, zero when outside the range.
    #[inline]
    fn get(&self, v: usize) -> (Vec3, f32, f32) {
        match v.checked_sub(self.lo).filter(|&k| k < self.radius.len()) {
            Some(k) => (self.normal_sum[k], self.area_sum[k], self.radius[k]),
            None => (Vec3::ZERO, 0.0, 0.0),
        }
    }
}

/// Triangles are summed in this many runs, in parallel, then merged in run order: the
/// result does not depend on the number of threads.
const RUNS: usize = 4;

/// How a vertex's normal was found.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Source {
    Given,
    Faces,
    Cancelled,
    NoFaces,
}

/// Which way a mesh's normals turn ([`super::outward`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outward {
    /// By the votes of its own pieces ([`orient_pieces`]).
    Vote,
    /// As decided for the whole model, of which this is a part
    /// ([`crate::tree::out_of_core`]), the model one piece: negated when `turn`. The
    /// part's own vertices (its first `own`) give their terms of the model's vote
    /// about its mean vertex `mean` ([`Vote::over`]), taken before the normals turn;
    /// whether the model is open is the model's to say when its parts are joined.
    Piece { turn: bool, own: usize, mean: DVec3 },
}

/// What [`vertex_disks`] returns besides the surfels.
pub struct MeshDisks {
    /// The isolated vertices that are redundant ([`super::isolated`]), ascending.
    pub redundant: Vec<u32>,
    /// The vertex normals (the surfels' are their shading fields', `super::field`).
    pub normals: Vec<Vec3>,
    /// A part's terms of the orientation vote ([`Outward::Piece`]).
    pub vote: Option<Vote>,
}

/// Normals and radii of the vertices of a mesh, written into `surfels` (one per
/// vertex), then their ellipses and shading fields. `scale` is the model's unit scale
/// ([`super::unit_scale`]); `given` the file's normals, `colored` whether it has
/// colours (the surfels' on entry). The shaped vertices are told to `progress`.
pub fn vertex_disks(
    points: &[Vec3],
    scale: f32,
    triangles: &[[u32; 3]],
    (given, colored, outward): (Option<&[Vec3]>, bool, Outward),
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> MeshDisks {
    let stages = Stages::new(surfels.len(), 100, progress);
    let isolated = face_disks(points, scale, triangles, given, surfels, stats);
    stages.ended(WEIGHTS.faces);
    let mut vote = None;
    stats.sides = match outward {
        Outward::Vote => orient_pieces(points, triangles, surfels),
        Outward::Piece { turn, own, mean } => {
            vote = Some(Vote::over(&points[..own], &surfels[..own], mean));
            if turn {
                surfels.par_iter_mut().for_each(|s| s.normal = -s.normal);
            }
            Sides {
                turned: u64::from(turn),
                ..Sides::default()
            }
        }
    };
    stages.ended(WEIGHTS.orient);
    let rings = super::corners::Rings::of(points.len(), triangles);
    stages.ended(WEIGHTS.rings);
    let (all, at) = (surfels.len(), (triangles, &rings));
    let share = stages.share(WEIGHTS.shapes);
    let progress = Progress::to(&share);
    let normals = super::ring::ring_shapes(points, scale, at, (surfels, all), colored, progress);
    let redundant = super::isolated::redundant(points, scale, &isolated, surfels);
    stats.redundant_vertices = redundant.len() as u64;
    MeshDisks {
        redundant,
        normals,
        vote,
    }
}

/// Each stage's share of a mesh's surfels time, in percent, for its progress: on a
/// mesh of 3.07 M vertices and 6.14 M triangles (`gen_model --segments 3000 --sides
/// 1024`, 2 cores, Intel, 2026-12-04) the face normals took 0.19 s, the orientation 0.14
/// s, the rings 0.08 s and the rings' shapes 1.28 s.
pub(crate) struct Weights {
    pub faces: u32,
    pub orient: u32,
    pub rings: u32,
    pub shapes: u32,
}

/// See [`Weights`]; they add up to 100.
pub(crate) const WEIGHTS: Weights = Weights {
    faces: 11,
    orient: 8,
    rings: 5,
    shapes: 76,
};

/// Normals and radii of the vertices of a mesh from their faces (and from their
/// neighbours for those without usable faces), not yet oriented; returns the isolated
/// vertices (no triangle reaches them).
pub fn face_disks(
    points: &[Vec3],
    scale: f32,
    triangles: &[[u32; 3]],
    given: Option<&[Vec3]>,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
) -> Vec<u32> {
    let s = scale as f64;
    let runs = if triangles.len() < 1 << 16 { 1 } else { RUNS };
    let per_run = triangles.len().div_ceil(runs).max(1);
    let accs: Vec<Accumulator> = triangles
        .par_chunks(per_run)
        .map(|run| Accumulator::over(points, s, run))
        .collect();
    stats.degenerate_triangles = accs.iter().map(|a| a.degenerate).sum();
    let sources: Vec<Source> = surfels
        .par_iter_mut()
        .enumerate()
        .with_min_len(1 << 14)
        .map(|(v, surfel)| {
            let (mut sum, mut area, mut radius) = (Vec3::ZERO, 0.0f32, 0.0f32);
            for acc in &accs {
                let (s, a, r) = acc.get(v);
                sum += s;
                area += a;
                radius = radius.max(r);
            }
            surfel.radius = radius / scale;
            let given_n = given.map_or(Vec3::ZERO, |g| g[v]);
            let (normal, source) = if given_n != Vec3::ZERO {
                (given_n, Source::Given)
            } else if area == 0.0 {
                (Vec3::ZERO, Source::NoFaces)
            } else if sum.length() <= CANCELLED * area {
                (Vec3::ZERO, Source::Cancelled)
            } else {
                (
                    unit_vector(sum.as_dvec3()).unwrap_or(Vec3::Z),
                    Source::Faces,
                )
            };
            surfel.normal = normal;
            source
        })
        .collect();
    drop(accs);
    let with = |source: Source| -> Vec<u32> {
        (0..sources.len() as u32)
            .into_par_iter()
            .filter(|&v| sources[v as usize] == source)
            .collect()
    };
    let cancelled = with(Source::Cancelled);
    // Vertices without a normal from faces (only degenerate triangles, or none), and
    // those no triangle reaches (radius 0) even when the file gives them a normal:
    // radius and normal (unless given) from their neighbours, like a cloud.
    let from_neighbours: Vec<u32> = (0..surfels.len() as u32)
        .into_par_iter()
        .filter(|&v| sources[v as usize] == Source::NoFaces || surfels[v as usize].radius == 0.0)
        .collect();
    let isolated: Vec<u32> = from_neighbours
        .iter()
        .copied()
        .filter(|&v| surfels[v as usize].radius == 0.0)
        .collect();
    stats.isolated_vertices = isolated.len() as u64;
    largest_face_normals(points, s, triangles, &cancelled, surfels);
    stats.cancelled_normals = cancelled.len() as u64;
    let walls = neighbour_disks(
        points,
        scale,
        &from_neighbours,
        (
            RadiusRule::Ranked,
            super::cloud::Orientation::Unknown,
            Progress::NONE,
        ),
        given,
        surfels,
        stats,
    );
    debug_assert!(walls.is_empty(), "only a terrain has walls");
    isolated
}

/// Gives each vertex of `cancelled` (whose face normals cancel) the normal of its
/// largest incident face: the sign of a fold is arbitrary.
fn largest_face_normals(
    points: &[Vec3],
    s: f64,
    triangles: &[[u32; 3]],
    cancelled: &[u32],
    surfels: &mut [Surfel],
) {
    if cancelled.is_empty() {
        return;
    }
    let mut best: HashMap<u32, (f64, DVec3)> =
        cancelled.iter().map(|&v| (v, (0.0, DVec3::Z))).collect();
    for t in triangles {
        let [a, b, c] = t.map(|i| at(points, s, i));
        let (cross, _, degenerate) = triangle_terms(a, b, c);
        if degenerate {
            continue;
        }
        let area = cross.length();
        for v in t {
            if let Some(b) = best.get_mut(v)
                && area > b.0
            {
                *b = (area, cross / area);
            }
        }
    }
    for (v, (_, nrm)) in best {
        surfels[v as usize].normal = unit_vector(nrm).unwrap_or(Vec3::Z);
    }
}
