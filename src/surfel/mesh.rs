//! Surfels of a triangle mesh, one per vertex (DESIGN.md §2).
//!
//! * normal: normalize(Σ over incident triangles of (b − a) × (c − a)), the
//!   area-weighted face normals; a file's non-zero normal is kept instead.
//! * radius: the disks of a triangle's three vertices must cover it. The point of a
//!   triangle farthest from its nearest vertex is the circumcentre when the triangle
//!   is acute, and lies on the longest edge otherwise, at most half its length away
//!   from an endpoint. So each vertex takes the maximum over its triangles of
//!   R = abc / (4·area) (acute) or L/2 (right or obtuse, and zero-area triangles).
//!
//! Per-triangle terms are computed in f64 from the unit-scaled f32 positions and the
//! radius is rounded up by [`RADIUS_MARGIN`] so that f32 storage never loses coverage.

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use super::SurfelStats;
use super::cloud::neighbour_disks;

/// Relative growth of every radius, above f32 rounding (2⁻²⁴).
pub const RADIUS_MARGIN: f64 = 1e-6;
/// A triangle is degenerate when |(b−a)×(c−a)| ≤ DEGENERATE · L², L its longest edge:
/// its smallest angle is below about 10⁻⁶ rad, below what f32 positions resolve.
pub const DEGENERATE: f64 = 1e-6;
/// A vertex's face normals cancel when |Σ cross| ≤ CANCELLED · Σ |cross|.
pub const CANCELLED: f32 = 1e-5;

/// Cross product and covering radius of one triangle (f64).
#[inline]
fn triangle_terms(a: Vec3, b: Vec3, c: Vec3) -> (DVec3, f64, bool) {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let cross = (b - a).cross(c - a);
    let mut l2 = [(b - a).length_squared(), (c - b).length_squared(), (a - c).length_squared()];
    l2.sort_by(f64::total_cmp);
    let twice_area = cross.length();
    let degenerate = twice_area <= DEGENERATE * l2[2];
    let acute = !degenerate && l2[0] + l2[1] > l2[2];
    let radius = if acute {
        // R = abc / (4·area) = abc / (2·|cross|)
        (l2[0] * l2[1] * l2[2]).sqrt() / (2.0 * twice_area)
    } else {
        0.5 * l2[2].sqrt()
    };
    (cross, radius, degenerate)
}

/// Normals and radii (unit-scaled) of the vertices of a mesh.
pub fn vertex_disks(
    points: &[Vec3],
    triangles: &[[u32; 3]],
    given: Option<&[Vec3]>,
    stats: &mut SurfelStats,
) -> (Vec<Vec3>, Vec<f32>) {
    let n = points.len();
    let mut normal_sum = vec![Vec3::ZERO; n];
    let mut area_sum = vec![0.0f32; n];
    let mut radius = vec![0.0f32; n];
    for t in triangles {
        let [a, b, c] = t.map(|i| points[i as usize]);
        let (cross, r, degenerate) = triangle_terms(a, b, c);
        let r = (r * (1.0 + RADIUS_MARGIN)) as f32;
        let (cross, area) = (cross.as_vec3(), cross.length() as f32);
        stats.degenerate_triangles += degenerate as u64;
        for &v in t {
            let v = v as usize;
            radius[v] = radius[v].max(r);
            if !degenerate {
                normal_sum[v] += cross;
                area_sum[v] += area;
            }
        }
    }
    let mut normals = vec![Vec3::ZERO; n];
    let mut cancelled = Vec::new();
    let mut without_faces = Vec::new();
    for v in 0..n {
        let given_n = given.map_or(Vec3::ZERO, |g| g[v]);
        if given_n != Vec3::ZERO {
            normals[v] = given_n;
        } else if area_sum[v] == 0.0 {
            without_faces.push(v as u32);
        } else if normal_sum[v].length() <= CANCELLED * area_sum[v] {
            cancelled.push(v as u32);
        } else {
            normals[v] = normal_sum[v].normalize();
        }
        if radius[v] == 0.0 && area_sum[v] == 0.0 {
            stats.isolated_vertices += 1;
        }
    }
    if !cancelled.is_empty() {
        // Normal of the largest incident face (the sign of a fold is arbitrary).
        let mut best: HashMap<u32, (f32, Vec3)> = cancelled.iter().map(|&v| (v, (0.0, Vec3::Z))).collect();
        for t in triangles {
            let (cross, _, degenerate) = triangle_terms(points[t[0] as usize], points[t[1] as usize], points[t[2] as usize]);
            if degenerate {
                continue;
            }
            let area = cross.length() as f32;
            for v in t {
                if let Some(b) = best.get_mut(v)
                    && area > b.0
                {
                    *b = (area, cross.normalize().as_vec3());
                }
            }
        }
        for (v, (_, nrm)) in best {
            normals[v as usize] = nrm;
        }
        stats.cancelled_normals = cancelled.len() as u64;
    }
    // Vertices no (non-degenerate) triangle uses: from their neighbours, like a cloud.
    neighbour_disks(points, &without_faces, given, &mut normals, &mut radius, stats);
    (normals, radius)
}
