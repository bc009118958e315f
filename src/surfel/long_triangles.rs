//! Splats of a sensor frame's long triangles, each in its own plane (issue 13).
//!
//! A frame's grid triangles ([`super::grid`]) join neighbouring pixels. Where the
//! sensor quantises depth, or sees a surface nearly edge-on, neighbouring pixels lie
//! many pixel footprints apart: the triangles between them are long and thin (the
//! risers between two depth steps). A vertex's one-ring ellipse ([`super::ring`]) had
//! to reach along such a riser, in the plane of the vertex's normal, which blends the
//! step's and the riser's; seen from the side it stuck out of both as a needle.
//!
//! Here a triangle whose longest edge exceeds [`LONG_PITCHES`] pixel footprints at its
//! depth is drawn by a splat of its own: its Steiner circumellipse, the least-area
//! ellipse through its three corners, centred on its centroid g with conjugate
//! semi-diameters c − g and (a − b) / √3 (area 4π / (3√3) ≈ 2.42 times the
//! triangle's). The ellipse bulges beyond each edge by a third of the triangle's height
//! over that edge: barely beyond the long edges, by a third of the riser beyond the
//! short one, where it is clipped ([`Clip::Line`] through that edge). Its shading and
//! colour fields are fitted over the triangle as a vertex's are over its ring
//! ([`fit_field`], [`fit_color_field`]), so that it shades as the reference
//! interpolates. The vertices' ellipses then cover only their short triangles.

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

use super::Surfel;
use super::clip::Clip;
use super::field::{fit_color_field, fit_field, unit_rgb};
use super::mesh::{RADIUS_MARGIN, triangle_terms};
use super::shape::{Fit, Shape, tangent_frame};
use crate::io::PointAttributes;

/// Longest edge, in pixel footprints (pitch × depth), beyond which a frame's triangle
/// gets a splat of its own.
pub const LONG_PITCHES: f64 = 3.0;

/// `triangles` split into the short and the long ([`LONG_PITCHES`]), for a frame seen
/// from `sensor` (relative to the model origin, as `points`) with pixel `pitch`
/// (radians).
pub fn split(
    points: &[Vec3],
    sensor: Vec3,
    pitch: f32,
    triangles: &[[u32; 3]],
) -> (Vec<[u32; 3]>, Vec<[u32; 3]>) {
    let at = |v: u32| (points[v as usize] - sensor).as_dvec3();
    let long = |t: &[u32; 3]| {
        let depth = t.iter().map(|&v| at(v).length()).sum::<f64>() / 3.0;
        let longest = (0..3)
            .map(|k| at(t[k]).distance(at(t[(k + 1) % 3])))
            .fold(0.0, f64::max);
        longest > LONG_PITCHES * pitch as f64 * depth
    };
    triangles.par_iter().partition(|t| !long(t))
}

/// One splat per triangle of `long` (indices into `points`, relative to the model
/// origin; `scale` the model's unit scale): `normals` are the vertices' normals, as the
/// reference interpolates them, `colors` the file's (None: grey). A degenerate
/// triangle gets none.
pub fn splats(
    points: &[Vec3],
    scale: f32,
    long: &[[u32; 3]],
    normals: &[Vec3],
    colors: Option<&[[u8; 4]]>,
) -> Vec<Surfel> {
    let s = scale as f64;
    long.par_iter()
        .filter_map(|t| {
            let corners = t.map(|v| {
                let color = colors.map_or(DVec3::splat(0.5), |c| unit_rgb(c[v as usize]));
                Corner {
                    position: points[v as usize].as_dvec3() * s,
                    normal: normals[v as usize].as_dvec3(),
                    color,
                }
            });
            let mut surfel = triangle_splat(corners, colors.is_some())?;
            surfel.position = (surfel.position.as_dvec3() / s).as_vec3();
            surfel.radius = (surfel.radius as f64 / s) as f32;
            Some(surfel)
        })
        .collect()
}

/// A triangle's corner: unit-scaled position, vertex normal, RGB 0–1.
#[derive(Debug, Clone, Copy)]
struct Corner {
    position: DVec3,
    normal: DVec3,
    color: DVec3,
}

/// The splat of one triangle (see the module doc), in the corners' unit; None when it
/// is degenerate ([`super::mesh::DEGENERATE`]).
fn triangle_splat(corners: [Corner; 3], colored: bool) -> Option<Surfel> {
    let [a, b, c] = corners.map(|k| k.position);
    let (cross, _, degenerate) = triangle_terms(a, b, c);
    if degenerate {
        return None;
    }
    let face = cross.normalize();
    let g = (a + b + c) / 3.0;
    let (major, r, ratio) = steiner_ellipse(face, [a, b, c]);
    let shape = Shape::ellipse(face, major, ratio);
    let at = |k: &Corner| (k.position, k.normal);
    let (normal, mut shape) = fit_field(
        (g, face),
        (r, &shape),
        std::iter::once(corners.map(|k| at(&k))),
    )
    .unwrap_or((face, shape));
    let mut color = corners.iter().map(|k| k.color).sum::<DVec3>() / 3.0;
    if colored {
        let at = |k: &Corner| (k.position, k.color);
        if let Some((c0, field)) = fit_color_field(
            (g, normal),
            (r, &shape),
            std::iter::once(corners.map(|k| at(&k))),
        ) {
            (color, shape.color) = (c0, field);
        }
    }
    shape.clip = shortest_edge_clip((g, normal, r), &shape, [a, b, c]);
    let rgb = (color * 255.0)
        .to_array()
        .map(|x| x.round().clamp(0.0, 255.0) as u8);
    Some(Surfel {
        position: g.as_vec3(),
        radius: (r * (1.0 + RADIUS_MARGIN)) as f32,
        normal: normal.as_vec3(),
        color: [rgb[0], rgb[1], rgb[2], 255],
        shape: shape.pack(),
        attributes: PointAttributes::default(),
    })
}

/// The Steiner circumellipse of triangle `[a, b, c]` in its plane (normal `face`): its
/// major axis (unit), major semi-axis and minor / major ratio. With f₁ = c − g and f₂ =
/// (a − b) / √3 its conjugate semi-diameters, the ellipse is {f₁ cos t + f₂ sin t}, whose
/// semi-axes are the square roots of the eigenvalues of f₁f₁ᵀ + f₂f₂ᵀ (the second
/// moment of the two, [`Fit::axes`]).
fn steiner_ellipse(face: DVec3, [a, b, c]: [DVec3; 3]) -> (DVec3, f64, f64) {
    let g = (a + b + c) / 3.0;
    let (t1, t2) = tangent_frame(face);
    let plane = |d: DVec3| DVec2::new(d.dot(t1), d.dot(t2));
    let mut moments = Fit::default();
    moments.add(plane(c - g), DVec2::ZERO);
    moments.add(plane(a - b) / 3f64.sqrt(), DVec2::ZERO);
    let (dir, l1, l2) = moments.axes();
    (t1 * dir.x + t2 * dir.y, l1.sqrt(), (l2 / l1).sqrt())
}

/// The line through the triangle's shortest edge as a clip of its splat (centre g,
/// normal n, major semi-axis r, `shape`), the side of the centre kept.
fn shortest_edge_clip(
    (g, n, r): (DVec3, DVec3, f64),
    shape: &Shape,
    corners: [DVec3; 3],
) -> Option<Clip> {
    let edge = (0..3)
        .map(|k| (corners[k], corners[(k + 1) % 3]))
        .min_by(|x, y| x.0.distance(x.1).total_cmp(&y.0.distance(y.1)))?;
    let plane = |p: DVec3| shape.along_axes(n, p - g) / r;
    Clip::line_through(plane(edge.0), plane(edge.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ρ² = x² + (y / ratio)² of `p` on the splat of centre `g`, normal `n`, major
    /// semi-axis `r` and `shape`.
    fn rho2(g: DVec3, n: DVec3, r: f64, shape: &Shape, p: DVec3) -> f64 {
        let xy = shape.along_axes(n, p - g) / r;
        xy.x * xy.x + (xy.y / shape.ratio).powi(2)
    }

    #[test]
    fn the_steiner_ellipse_passes_through_the_corners_and_holds_the_triangle() {
        let triangles = [
            [DVec3::ZERO, DVec3::X, DVec3::Y],
            // A riser: one pixel wide, twelve long, tilted out of every axis plane.
            [
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.1, 0.0),
                DVec3::new(0.3, 0.5, 12.0),
            ],
        ];
        for corners in triangles {
            let [a, b, c] = corners;
            let face = (b - a).cross(c - a).normalize();
            let g = (a + b + c) / 3.0;
            let (axis, r, ratio) = steiner_ellipse(face, corners);
            let shape = Shape::ellipse(face, axis, ratio);
            for p in corners {
                assert!((rho2(g, face, r, &shape, p) - 1.0).abs() < 1e-9);
            }
            for p in [g, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0] {
                assert!(rho2(g, face, r, &shape, p) < 1.0);
            }
            let area = std::f64::consts::PI * r * r * ratio;
            let triangle = 0.5 * (b - a).cross(c - a).length();
            let steiner = 4.0 * std::f64::consts::PI / (3.0 * 3f64.sqrt());
            assert!((area / triangle - steiner).abs() < 1e-9 * steiner);
        }
    }

    #[test]
    fn a_long_triangle_s_splat_is_clipped_beyond_its_short_edge_only() {
        let corner = |position: DVec3| Corner {
            position,
            normal: DVec3::Z,
            color: DVec3::splat(0.5),
        };
        let [a, b, c] = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 12.0, 0.0)];
        let s = triangle_splat([a, b, c].map(corner), false).unwrap();
        let n = s.normal.as_dvec3();
        let shape = s.shape.unpack(n);
        let g = s.position.as_dvec3();
        let kept = |p: DVec3| {
            let xy = shape.along_axes(n, p - g) / s.radius as f64;
            xy.x * xy.x + (xy.y / shape.ratio).powi(2) < 1.0
                && shape.clip.is_none_or(|clip| clip.keeps(xy))
        };
        assert!(
            (n - DVec3::Z).length() < 1e-9,
            "a flat triangle's normal {n}"
        );
        // Inside, near each corner and along each edge.
        for p in [g, a, b, c, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0] {
            assert!(kept(p + (g - p) * 0.01), "{p} cut");
        }
        // The ellipse bulges a third of the height (4) beyond the short edge a–b.
        assert!(!kept(DVec3::new(0.5, -1.0, 0.0)));
        assert!(shape.clip.is_some());
    }
}
