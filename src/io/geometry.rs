//! Geometry: what the surfel builder needs from a model file, rebased around its centre.
//!
//! Coordinates are read as f64. `origin` is the centre of the bounding box of the
//! model's core (its vertices but the outliers, [`super::rebase`]), in f64; positions
//! are stored as f32 *relative to origin*, so a LiDAR tile at x ≈ 5·10⁵ m keeps
//! sub-millimetre precision, and a stray sample 10¹⁰ m away does not take it. Vertices
//! with a NaN or infinite coordinate, or too far from the origin for f32 offsets to
//! hold, are dropped together with every triangle that uses them, and counted.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::io::bounds::Bounds;
use crate::io::ply::faces::Faces;
use crate::io::rebase;
use crate::io::rows::{ColumnRows, Field, Flat, VertexFields, VertexRows};
use crate::io::scalar::Scalar;

/// A model ready for the surfel builder.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// Centre of `core`; every position below is relative to it.
    pub origin: DVec3,
    /// Bounding box of the kept vertices.
    pub bounds: Bounds,
    /// Bounding box of the kept vertices that are not outliers (`bounds` when none is):
    /// the size of the model, for its unit scale.
    pub core: Bounds,
    pub positions: Vec<Vec3>,
    /// Normals given by the file, unit length; zero where the file's normal was zero or
    /// not finite (the surfel builder recomputes those).
    pub normals: Option<Vec<Vec3>>,
    /// Colours given by the file, RGBA8 (alpha 255 when the file has none).
    pub colors: Option<Vec<[u8; 4]>>,
    pub triangles: Vec<[u32; 3]>,
    /// The file row of each kept vertex, when some rows were dropped (`None`: vertex i
    /// is row i). Organised clouds (an RGB-D frame's pixels) keep their grid through it.
    pub rows: Option<Vec<u32>>,
    /// LiDAR attributes of each kept vertex (LAS and LAZ files).
    pub attributes: Option<Vec<PointAttributes>>,
}

/// What LiDAR users read a point by (LAS): its intensity, ASPRS class, return number
/// and number of returns. 4 bytes, the layout of the `.spt` attribute section and of
/// the GPU's (`shaders/splat.wgsl`, `attributes`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PointAttributes {
    pub intensity: u16,
    /// ASPRS class (LAS 1.4 table 17: 2 ground, 6 building, 9 water…).
    pub class: u8,
    /// Return number (low 4 bits) and number of returns (high 4 bits), each 0–15.
    pub returns: u8,
}

impl PointAttributes {
    pub fn new(intensity: u16, class: u8, return_number: u8, returns: u8) -> Self {
        PointAttributes {
            intensity,
            class,
            returns: (return_number.min(15)) | (returns.min(15) << 4),
        }
    }

    pub fn return_number(self) -> u8 {
        self.returns & 15
    }

    pub fn number_of_returns(self) -> u8 {
        self.returns >> 4
    }
}

impl Geometry {
    /// The geometry of points given in file coordinates, without faces, normals or
    /// colours, rebased as a reader rebases a file's vertices (the same drops, counted).
    /// Fails when none can be kept.
    pub fn from_points(points: &[[f64; 3]]) -> Result<(Geometry, GeometryStats), String> {
        let columns = (0..3)
            .map(|k| points.iter().map(|p| p[k]).collect())
            .collect();
        let fields = VertexFields {
            fields: (0..3)
                .map(|property| Field {
                    property,
                    scalar: Scalar::F64,
                })
                .collect(),
            has_normals: false,
            color_channels: 0,
            z_absent: false,
        };
        assemble(&ColumnRows { columns }, &fields, None)
    }

    /// The invariants every reader guarantees: finite origin and boxes (empty ones when
    /// the file holds no vertex), every position
    /// finite and within [`rebase::MAX_OFFSET`] of the origin, given normals unit or
    /// zero, colours one per vertex, triangle indices in range.
    pub fn check(&self) -> Result<(), String> {
        let finite_box = |b: &Bounds| {
            (0..3).all(|k| b.min[k].is_finite() && b.max[k].is_finite() && b.min[k] <= b.max[k])
        };
        // A file without vertices has empty boxes (∞, −∞).
        let boxes =
            self.positions.is_empty() || (finite_box(&self.bounds) && finite_box(&self.core));
        if !self.origin.is_finite() || !boxes {
            return Err(format!(
                "origin {} bounds {:?} core {:?} not finite",
                self.origin, self.bounds, self.core
            ));
        }
        let n = self.positions.len();
        let limit = rebase::MAX_OFFSET as f32;
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.is_finite() || p.abs().max_element() > limit)
        {
            return Err(format!("position {i} is {}", self.positions[i]));
        }
        if let Some(normals) = &self.normals {
            let bad = |v: &Vec3| *v != Vec3::ZERO && (v.length() - 1.0).abs() > 1e-5;
            if normals.len() != n || normals.iter().any(bad) {
                return Err("given normals not one unit (or zero) vector per vertex".to_owned());
            }
        }
        if self.colors.as_ref().is_some_and(|c| c.len() != n) {
            return Err("not one colour per vertex".to_owned());
        }
        if let Some(t) = self
            .triangles
            .iter()
            .find(|t| t.iter().any(|&v| v as usize >= n))
        {
            return Err(format!("triangle {t:?} beyond the {n} vertices"));
        }
        if self.attributes.as_ref().is_some_and(|a| a.len() != n) {
            return Err("attributes not one per vertex".to_owned());
        }
        Ok(())
    }
}

/// What was read and what was dropped, and why.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct GeometryStats {
    pub vertices_in_file: u64,
    pub vertices_dropped_nonfinite: u64,
    /// Finite vertices further from the origin than f32 offsets can hold
    /// ([`super::rebase::MAX_OFFSET`]).
    pub vertices_dropped_out_of_range: u64,
    /// Kept vertices far outside the model's core (stray samples).
    pub outliers: u64,
    pub faces_in_file: u64,
    pub faces_with_fewer_than_3_vertices: u64,
    /// Rows of a `tristrips` element read (its triangles are counted in `triangles`).
    pub triangle_strips: u64,
    pub triangles: u64,
    /// Triangles that use a dropped vertex (non-finite or out of range).
    pub triangles_dropped_nonfinite: u64,
    pub normals_given_invalid: u64,
    /// The file gives colours, but black everywhere (a writer's empty fields): they
    /// are dropped, and the model is shaded as one without colours.
    pub colors_all_zero: bool,
    /// The vertices have x and y but no z: they lie in the plane z = 0.
    pub z_absent: bool,
}

/// `v` at unit length, in f32: divided by its largest component first and normalized
/// in f64, so that neither tiny nor huge vectors (whose squared length under- or
/// overflows) lose their direction or their unit length. `None` for a zero or
/// non-finite vector.
pub fn unit_vector(v: DVec3) -> Option<Vec3> {
    let m = v.abs().max_element();
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    (v / m).try_normalize().map(|u| u.as_vec3())
}

/// A colour channel of type `s` as 8 bits: integers are taken as 0–255 (ushort as
/// 0–65535), floats as 0–1.
pub(crate) fn channel(v: f64, s: Scalar) -> u8 {
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

/// Row `i`'s normal (fields [`VertexFields::NORMAL`]..+3) at unit length; zero where
/// the file's is zero or not finite.
#[inline]
pub(crate) fn row_normal<R: VertexRows>(rows: &R, i: usize) -> Vec3 {
    let k = VertexFields::NORMAL;
    let v = DVec3::new(rows.get(i, k), rows.get(i, k + 1), rows.get(i, k + 2));
    unit_vector(v).unwrap_or(Vec3::ZERO)
}

/// Row `i`'s colour as RGBA8 ([`channel`] per channel; alpha 255 when the file has none).
#[inline]
pub(crate) fn row_color<R: VertexRows>(rows: &R, fields: &VertexFields, i: usize) -> [u8; 4] {
    let c0 = fields.color_start();
    let mut c = [255u8; 4];
    for (k, f) in fields.fields[c0..].iter().enumerate() {
        c[k] = channel(rows.get(i, c0 + k), f.scalar);
    }
    c
}

const CHUNK: usize = 1 << 15;

/// Builds the geometry from decoded vertex rows and faces (rows without z in the plane
/// z = 0). Fails only when rows are given and none can be kept.
pub(crate) fn assemble<R: VertexRows>(
    rows: &R,
    fields: &VertexFields,
    faces: Option<Faces>,
) -> Result<(Geometry, GeometryStats), String> {
    let (geometry, mut stats) = if fields.z_absent {
        assemble_rows(&Flat(rows), fields, faces)
    } else {
        assemble_rows(rows, fields, faces)
    }?;
    stats.z_absent = fields.z_absent;
    Ok((geometry, stats))
}

fn assemble_rows<R: VertexRows>(
    rows: &R,
    fields: &VertexFields,
    faces: Option<Faces>,
) -> Result<(Geometry, GeometryStats), String> {
    let n = rows.len();
    let frame = rebase::frame(rows)?;
    let origin = frame.origin;
    let kept = frame.kept;
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
        vertices_dropped_nonfinite: frame.nonfinite,
        vertices_dropped_out_of_range: frame.out_of_range,
        outliers: frame.outliers,
        ..GeometryStats::default()
    };
    let normals = fields
        .has_normals
        .then(|| map_rows(&|i| row_normal(rows, i)));
    if let Some(ns) = &normals {
        stats.normals_given_invalid = ns.par_iter().filter(|v| **v == Vec3::ZERO).count() as u64;
    }
    let colors = (fields.color_channels > 0).then(|| {
        let color = |i: usize| row_color(rows, fields, i);
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
    let colors = colors.filter(|c: &Vec<[u8; 4]>| {
        stats.colors_all_zero = c.par_iter().all(|c| c[..3] == [0; 3]);
        !stats.colors_all_zero
    });
    let mut triangles = Vec::new();
    if let Some(f) = faces {
        stats.faces_in_file = f.polygons;
        stats.faces_with_fewer_than_3_vertices = f.too_short;
        stats.triangle_strips = f.strips;
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
            bounds: frame.bounds,
            core: frame.core,
            positions,
            normals,
            colors,
            triangles,
            rows: kept,
            attributes: None,
        },
        stats,
    ))
}
