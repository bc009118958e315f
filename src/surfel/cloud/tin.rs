//! A terrain's shading from its triangulated irregular network (TIN): the 2.5D
//! Delaunay triangulation of its samples in x–y, long triangles dropped
//! ([`crate::io::triangulate::height_field`], the surface issue 13 measures a tile's
//! splats against and the one terrain tools hill-shade).
//!
//! * normal: a sample's vertex normal, normalize(Σ (b − a) × (c − a)) over its
//!   triangles (area-weighted, turned up), as the mesh pass shades a vertex
//!   (`surfel::mesh`);
//! * shading field: the least-squares fit of the TIN's interpolated normal over the part
//!   of the sample's one-ring its ellipse covers ([`fit_field`], as a mesh splat's).
//!
//! The ellipse stays the cloud's (its covering within the tile's spacing): the TIN's
//! one-ring ellipses span its long triangles between a roof and the street.
//!
//! Why (`cloud_quality --terrain`, 4 views, medians, lavapipe): a normal fitted to 24
//! neighbours and averaged over 24 more shades a tile's trees and roof edges as one
//! smooth slope, where the TIN shades each sample's own bumps; FLIP terrain_utm 0.1783 →
//! 0.1674 with the vertex normals, 0.1610 with their fields, 0.1542 with the samples
//! of a shared x–y on the kept one's vertex ([`Tin::vertex`]); autzen_trim 0.1728 →
//! 0.1607, 0.1622 and 0.1624. Smoothing the vertex normals over their one-rings first (1–5 rounds)
//! gave 0.1663–0.1667 on terrain_utm and 0.1681–0.1737 on autzen_trim.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::super::covering::Covering;
use super::super::field::fit_field;
use super::super::ring::corners_by_vertex;
use super::super::shape::Shape;
use crate::io::geometry::unit_vector;
use crate::io::triangulate::height_field;

/// A terrain splat's shading from its [`Tin`]: its normal, and its ellipse's major axis
/// (⟂ the normal) and normal field's gradient ([`Shape`]'s), kept in f32 (a [`Shape`]
/// is 150 bytes: about 50 MB more at terrain_utm's peak).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TinSplat {
    pub normal: Vec3,
    axis: Vec3,
    gradient: [f32; 3],
}

impl TinSplat {
    /// Its shape, an ellipse of minor over major semi-axis `ratio`.
    pub fn shape(&self, ratio: f64) -> Shape {
        Shape {
            gradient: self.gradient.map(f64::from),
            ..Shape::ellipse(self.normal.as_dvec3(), self.axis.as_dvec3(), ratio)
        }
    }
}

/// A terrain's triangles, each sample's vertex normal and its corners.
pub(super) struct Tin {
    triangles: Vec<[u32; 3]>,
    /// Each sample's vertex: itself, or the sample at the same x–y that the
    /// triangulation kept (it keeps one of coincident points: 215,298 of terrain_utm's
    /// 522,674 samples share their x–y with another, 3 cm apart in height at the median).
    vertex: Vec<u32>,
    /// Each sample's vertex's normal; zero for a sample no triangle holds.
    normals: Vec<Vec3>,
    /// Sample v's corners (triangle × 3 + its index in it) are
    /// `corners[start[v]..start[v + 1]]`.
    start: Vec<u32>,
    corners: Vec<u32>,
}

impl Tin {
    /// The TIN of `points` (all of them, any unit).
    pub fn of(points: &[Vec3]) -> Tin {
        let triangles = height_field(points);
        let (start, corners) = corners_by_vertex(points.len(), &triangles);
        let vertex = vertices(points, |v| start[v as usize] < start[v as usize + 1]);
        let normals = (0..points.len())
            .into_par_iter()
            .with_min_len(1 << 12)
            .map(|v| {
                let v = vertex[v] as usize;
                let sum: DVec3 = corners[start[v] as usize..start[v + 1] as usize]
                    .iter()
                    .map(|&c| {
                        let [a, b, c] =
                            triangles[c as usize / 3].map(|i| points[i as usize].as_dvec3());
                        let cross = (b - a).cross(c - a);
                        if cross.z < 0.0 { -cross } else { cross }
                    })
                    .sum();
                unit_vector(sum).unwrap_or(Vec3::ZERO)
            })
            .collect();
        Tin {
            triangles,
            vertex,
            normals,
            start,
            corners,
        }
    }

    /// The normal and shape of the splat of each sample of `which` whose normal is
    /// `estimated`, with `disks` its covering (unit-scaled by `scale`, as `points`): the
    /// ellipse in the plane of its vertex normal, and the shading field over its
    /// one-ring where the ellipse covers enough of it to fit one ([`fit_field`]). None
    /// where no triangle holds the sample.
    pub fn splats(
        &self,
        which: &[u32],
        (points, scale): (&[Vec3], f32),
        disks: &[(Vec3, Covering)],
        estimated: impl Fn(u32) -> bool + Sync,
    ) -> Vec<Option<TinSplat>> {
        which
            .par_iter()
            .zip(disks)
            .map(|(&v, (_, c))| {
                let normal = Some(self.normals[v as usize]).filter(|n| *n != Vec3::ZERO);
                let normal = normal.filter(|_| estimated(v))?;
                let ellipse = Shape::ellipse(normal.as_dvec3(), c.axis.as_dvec3(), c.ratio as f64);
                let shaded = self.shaded(v, (points, scale), (c.radius as f64, &ellipse));
                let (normal, shape) = shaded.unwrap_or((normal, ellipse));
                Some(TinSplat {
                    normal,
                    axis: shape.axis.as_vec3(),
                    gradient: shape.gradient.map(|g| g as f32),
                })
            })
            .collect()
    }

    /// [`Tin::splats`]'s shading field of `v`: `shape` (major radius `r`) fitted over
    /// `v`'s one-ring; None where the fit is undetermined.
    fn shaded(
        &self,
        v: u32,
        (points, scale): (&[Vec3], f32),
        (r, shape): (f64, &Shape),
    ) -> Option<(Vec3, Shape)> {
        let at = |w: u32| {
            let p = (points[w as usize] * scale).as_dvec3();
            (p, self.normals[w as usize].as_dvec3())
        };
        let w = self.vertex[v as usize] as usize;
        let corners = &self.corners[self.start[w] as usize..self.start[w + 1] as usize];
        let ring = corners.iter().map(|&c| {
            let (t, k) = (&self.triangles[c as usize / 3], c as usize % 3);
            [at(v), at(t[(k + 1) % 3]), at(t[(k + 2) % 3])]
        });
        let (normal, shape) = fit_field(at(v), (r, shape), ring)?;
        Some((normal.as_vec3(), shape))
    }
}

/// [`Tin::splats`] of a terrain's `points`, which it triangulates; none at all when no
/// sample's normal is `estimated` (the file gives them all).
pub(super) fn splats(
    which: &[u32],
    (points, scale): (&[Vec3], f32),
    disks: &[(Vec3, Covering)],
    estimated: impl Fn(u32) -> bool + Sync,
) -> Vec<Option<TinSplat>> {
    if !which.iter().any(|&i| estimated(i)) {
        return Vec::new();
    }
    Tin::of(points).splats(which, (points, scale), disks, estimated)
}

/// Each of `points`' vertex in a triangulation where `held(v)` says whether a triangle
/// holds v: v itself if one does or no sample at its x–y is held, else the first held
/// sample at its x–y.
fn vertices(points: &[Vec3], held: impl Fn(u32) -> bool + Sync) -> Vec<u32> {
    let xy = |v: &u32| {
        let p = points[*v as usize];
        (p.x.to_bits(), p.y.to_bits())
    };
    let mut by_xy: Vec<u32> = (0..points.len() as u32).collect();
    by_xy.par_sort_unstable_by_key(xy);
    let mut vertex: Vec<u32> = (0..points.len() as u32).collect();
    for run in by_xy
        .chunk_by(|a, b| xy(a) == xy(b))
        .filter(|r| r.len() > 1)
    {
        if let Some(&kept) = run.iter().find(|&&v| held(v)) {
            run.iter().for_each(|&v| vertex[v as usize] = kept);
        }
    }
    vertex
}

#[cfg(test)]
mod tests {
    use super::super::super::covering::{RadiusRule, covering};
    use super::*;

    /// A sloped grid (z = 0.5 x + 0.25 y) of 10 × 10 samples, those of its sixth row
    /// doubled 3 cm above (samples 100–109), and one sample far off that no triangle
    /// reaches (110).
    fn slope() -> Vec<Vec3> {
        let mut points = Vec::new();
        for j in 0..10 {
            for i in 0..10 {
                let (x, y) = (i as f32, j as f32 * 1.1);
                points.push(Vec3::new(x, y, 0.5 * x + 0.25 * y));
            }
        }
        let doubled: Vec<Vec3> = points[50..60].iter().map(|p| *p + 0.03 * Vec3::Z).collect();
        points.extend(doubled);
        points.push(Vec3::new(500.0, 500.0, 0.0));
        points
    }

    /// Circles of one spacing's radius.
    fn disks(points: &[Vec3]) -> Vec<(Vec3, Covering)> {
        let none = covering(Vec3::ZERO, Vec3::Z, &[], RadiusRule::Ranked);
        let c = Covering {
            radius: 1.0,
            axis: Vec3::X,
            ratio: 1.0,
            ..none
        };
        vec![(Vec3::Z, c); points.len()]
    }

    #[test]
    fn a_slope_s_samples_and_their_doubles_shade_with_its_plane() {
        let points = slope();
        let which: Vec<u32> = (0..points.len() as u32).collect();
        let splats = Tin::of(&points).splats(&which, (&points, 1.0), &disks(&points), |_| true);
        let plane = Vec3::new(-0.5, -0.25, 1.0).normalize();
        for (v, splat) in splats.iter().enumerate().take(110) {
            let splat = splat.expect("every grid sample and double is held");
            let (normal, shape) = (splat.normal, splat.shape(1.0));
            assert!(
                shape.axis.dot(normal.as_dvec3()).abs() < 1e-6,
                "{v}: {splat:?}"
            );
            let off = normal.angle_between(plane).to_degrees();
            // Two rows or more from the doubled one, the one-ring's vertices and their
            // neighbours lie in the plane.
            let far = v < 30 || (80..100).contains(&v);
            assert!(off < if far { 0.01 } else { 2.0 }, "sample {v}: {off}°");
            let flat = shape.gradient.iter().all(|g| g.abs() < 1e-5);
            assert!(!far || flat, "{v}: {shape:?}");
        }
        for v in 50..60 {
            let (own, double) = (splats[v].unwrap().normal, splats[v + 50].unwrap().normal);
            let apart = own.angle_between(double).to_degrees();
            assert!(apart < 0.5, "sample {v} and its double: {apart}°");
        }
        assert_eq!(splats[110], None, "the far sample is held by no triangle");
    }

    #[test]
    fn given_normals_are_left_to_the_file() {
        let points = slope();
        let which: Vec<u32> = (0..points.len() as u32).collect();
        let splats = Tin::of(&points).splats(&which, (&points, 1.0), &disks(&points), |v| v != 5);
        assert_eq!(splats[5], None);
        assert!(splats[4].is_some());
    }
}
