//! Geometry: what the surfel builder needs from a model file, rebased around its centre.
//!
//! Coordinates are read as f64. `origin` is the centre of the bounding box of the
//! finite vertices, in f64; positions are stored as f32 *relative to origin*, so a LiDAR
//! tile at x ≈ 5·10⁵ m keeps sub-millimetre precision. Vertices with a NaN or infinite
//! coordinate are dropped together with every triangle that uses them.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::io::ply::faces::Faces;
use crate::io::ply::fields::{VertexFields, VertexRows};
use crate::io::ply::scalar::Scalar;

/// Axis-aligned box in the file's own coordinates, at full f64 precision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Bounds {
    pub fn center(&self) -> DVec3 {
        (DVec3::from(self.min) + DVec3::from(self.max)) * 0.5
    }

    pub fn extent(&self) -> DVec3 {
        DVec3::from(self.max) - DVec3::from(self.min)
    }

    fn empty() -> Self {
        Bounds {
            min: [f64::INFINITY; 3],
            max: [f64::NEG_INFINITY; 3],
        }
    }

    fn grow(mut self, p: [f64; 3]) -> Self {
        self.min = std::array::from_fn(|a| self.min[a].min(p[a]));
        self.max = std::array::from_fn(|a| self.max[a].max(p[a]));
        self
    }

    fn union(self, o: Self) -> Self {
        self.grow(o.min).grow(o.max)
    }
}

/// A model ready for the surfel builder.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// Centre of `bounds`; every position below is relative to it.
    pub origin: DVec3,
    pub bounds: Bounds,
    pub positions: Vec<Vec3>,
    /// Normals given by the file, unit length; zero where the file's normal was zero or
    /// not finite (the surfel builder recomputes those).
    pub normals: Option<Vec<Vec3>>,
    /// Colours given by the file, RGBA8 (alpha 255 when the file has none).
    pub colors: Option<Vec<[u8; 4]>>,
    pub triangles: Vec<[u32; 3]>,
}

/// What was read and what was dropped, and why.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct GeometryStats {
    pub vertices_in_file: u64,
    pub vertices_dropped_nonfinite: u64,
    pub faces_in_file: u64,
    pub faces_with_fewer_than_3_vertices: u64,
    pub triangles: u64,
    pub triangles_dropped_nonfinite: u64,
    pub normals_given_invalid: u64,
}

/// A colour channel of type `s` as 8 bits: integers are taken as 0–255 (ushort as
/// 0–65535), floats as 0–1.
fn channel(v: f64, s: Scalar) -> u8 {
    let v = match s {
        Scalar::F32 | Scalar::F64 => v * 255.0,
        Scalar::U16 => v / 257.0,
        _ => v,
    };
    if v.is_nan() {
        0
    } else {
        v.round().clamp(0.0, 255.0) as u8
    }
}

const CHUNK: usize = 1 << 15;

fn is_finite(p: [f64; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}

/// Builds the geometry from decoded vertex rows and faces.
/// Fails only when no vertex has finite coordinates.
pub(crate) fn assemble<R: VertexRows>(
    rows: &R,
    fields: &VertexFields,
    faces: Option<Faces>,
) -> Result<(Geometry, GeometryStats), String> {
    let n = rows.len();
    // Pass 1: bounds of the finite vertices, and how many are not finite.
    let (bounds, nonfinite) = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .fold(
            || (Bounds::empty(), 0u64),
            |(b, bad), i| {
                let p = rows.position(i);
                if is_finite(p) {
                    (b.grow(p), bad)
                } else {
                    (b, bad + 1)
                }
            },
        )
        .reduce(|| (Bounds::empty(), 0), |a, b| (a.0.union(b.0), a.1 + b.1));
    if nonfinite == n as u64 {
        return Err(if n == 0 {
            "the model has no vertex".to_owned()
        } else {
            format!("none of the {n} vertices has finite coordinates")
        });
    }
    let origin = bounds.center();
    // Rows kept, in order (all of them in the common case).
    let kept: Option<Vec<u32>> = (nonfinite > 0).then(|| {
        (0..n as u32)
            .filter(|&i| is_finite(rows.position(i as usize)))
            .collect()
    });
    let kept_rows = kept.as_deref();
    let map_rows = |f: &(dyn Fn(usize) -> Vec3 + Sync)| -> Vec<Vec3> {
        match kept_rows {
            None => (0..n).into_par_iter().with_min_len(CHUNK).map(f).collect(),
            Some(k) => k
                .par_iter()
                .with_min_len(CHUNK)
                .map(|&i| f(i as usize))
                .collect(),
        }
    };
    // Pass 2: positions relative to origin, in f64 then rounded once to f32.
    let positions = map_rows(&|i| (DVec3::from(rows.position(i)) - origin).as_vec3());
    let mut stats = GeometryStats {
        vertices_in_file: n as u64,
        vertices_dropped_nonfinite: nonfinite,
        ..GeometryStats::default()
    };
    let normals = fields.has_normals.then(|| {
        let k = VertexFields::NORMAL;
        map_rows(&|i| {
            let v = Vec3::new(
                rows.get(i, k) as f32,
                rows.get(i, k + 1) as f32,
                rows.get(i, k + 2) as f32,
            );
            v.try_normalize().unwrap_or(Vec3::ZERO)
        })
    });
    if let Some(ns) = &normals {
        stats.normals_given_invalid = ns.par_iter().filter(|v| **v == Vec3::ZERO).count() as u64;
    }
    let colors = (fields.color_channels > 0).then(|| {
        let c0 = fields.color_start();
        let types: Vec<Scalar> = fields.fields[c0..].iter().map(|f| f.scalar).collect();
        let color = |i: usize| {
            let mut c = [255u8; 4];
            for (k, s) in types.iter().enumerate() {
                c[k] = channel(rows.get(i, c0 + k), *s);
            }
            c
        };
        match kept_rows {
            None => (0..n)
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(color)
                .collect(),
            Some(k) => k
                .par_iter()
                .with_min_len(CHUNK)
                .map(|&i| color(i as usize))
                .collect(),
        }
    });
    let mut triangles = Vec::new();
    if let Some(f) = faces {
        stats.faces_in_file = f.polygons;
        stats.faces_with_fewer_than_3_vertices = f.too_short;
        triangles = f.triangles;
        if let Some(k) = kept_rows {
            let mut new_index = vec![u32::MAX; n];
            for (new, &old) in k.iter().enumerate() {
                new_index[old as usize] = new as u32;
            }
            let before = triangles.len();
            triangles.retain_mut(|t| {
                t.iter_mut().all(|v| {
                    *v = new_index[*v as usize];
                    *v != u32::MAX
                })
            });
            stats.triangles_dropped_nonfinite = (before - triangles.len()) as u64;
        }
    }
    stats.triangles = triangles.len() as u64;
    Ok((
        Geometry {
            origin,
            bounds,
            positions,
            normals,
            colors,
            triangles,
        },
        stats,
    ))
}
