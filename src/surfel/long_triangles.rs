//! Splats of a mesh's long triangles, each in its own plane: a sensor
//! frame's grid ([`super::grid`]) and a terrain's TIN ([`super::terrain`]).
//!
//! A frame's grid triangles join neighbouring pixels. Where the sensor quantises depth,
//! or sees a surface nearly edge-on, neighbouring pixels lie many pixel footprints
//! apart: the triangles between them are long and thin (the risers between two depth
//! steps). A vertex's one-ring ellipse ([`super::ring`]) had to reach along such a
//! riser, in the plane of the vertex's normal, which blends the step's and the riser's;
//! seen from the side it stuck out of both as a needle. A terrain's walls, between a
//! roof's edge and the street, are such triangles too.
//!
//! So [`disks`] draws a long triangle (the caller says which: [`LONG_PITCHES`] pixel
//! footprints on a frame) by a splat of its own ([`splats`]): an ellipse of its second
//! moments centred on its centroid g, the Steiner family with conjugate semi-diameters
//! c − g and (a − b) / √3 ([`Reach`]). The circumellipse, through the corners, bulges
//! beyond each edge by a third of the triangle's height over that edge: barely beyond
//! the long edges, by a third of the riser beyond the short one, where it is clipped
//! ([`Clip::Line`] through that edge). Its shading and colour fields are fitted over
//! the triangle as a vertex's are over its ring ([`fit_field`], [`fit_color_field`]),
//! so that it shades as the reference interpolates. The vertices' ellipses then cover
//! only their short triangles.

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

use super::clip::Clip;
use super::corners::Rings;
use super::field::{fit_color_field, fit_field, unit_rgb};
use super::mesh::face_disks;
use super::progress::Progress;
use super::ring::{clip_at_border, ring_shapes};
use super::shape::{Fit, MIN_RATIO, Shape, tangent_frame};
use super::triangle::{RADIUS_MARGIN, triangle_terms};
use super::{DEFAULT_COLOR, Surfel, SurfelStats};
use crate::io::PointAttributes;

/// Longest edge, in pixel footprints (pitch × depth), beyond which a frame's triangle
/// gets a splat of its own.
pub const LONG_PITCHES: f32 = 3.0;

/// The splats of a mesh (a frame's grid, a terrain's TIN) whose long triangles are
/// drawn by splats of their own: each vertex's normal from all its triangles, its
/// ellipse and shading field from its short ones, clipped at their border, and no
/// colour field; a vertex on long triangles only is a circle of `lone_radius(position)`.
/// Fills `surfels` (one per point; `given` normals kept; only the first `kept` get
/// ellipses and clips, [`ring_shapes`]) and returns the isolated
/// vertices (ascending), the long triangles and the vertex normals that
/// [`splats`] interpolates over them. The shaped vertices are told to `progress`.
pub fn disks(
    (points, scale): (&[Vec3], f32),
    triangles: &[[u32; 3]],
    (is_long, lone_radius): (impl Fn(&[u32; 3]) -> bool + Sync, impl Fn(Vec3) -> f32),
    given: Option<&[Vec3]>,
    (surfels, kept): (&mut [Surfel], usize),
    stats: &mut SurfelStats,
    progress: Progress,
) -> Split {
    let isolated = face_disks(points, scale, triangles, given, surfels, stats);
    let (short, long): (Vec<[u32; 3]>, Vec<[u32; 3]>) =
        triangles.par_iter().partition(|t| !is_long(t));
    let mut in_short = vec![false; points.len()];
    short
        .iter()
        .flatten()
        .for_each(|&v| in_short[v as usize] = true);
    // The vertices keep their own colours, without fields: fitted over a ring cut at a
    // step's edge, a field ran on across the step in saturated specks.
    let rings = Rings::of(points.len(), &short);
    let normals = ring_shapes(
        points,
        scale,
        (&short, &rings),
        (surfels, kept),
        false,
        progress,
    );
    for (v, s) in surfels.iter_mut().enumerate() {
        if !in_short[v] && s.radius > 0.0 {
            s.radius = s.radius.min(lone_radius(s.position));
        }
    }
    stats.clipped_boundaries += clip_at_border(points, (&short, &rings), (surfels, kept));
    Split {
        isolated,
        long,
        normals,
    }
}

/// What [`disks`] leaves to its caller.
pub struct Split {
    /// The vertices no triangle holds, ascending.
    pub isolated: Vec<u32>,
    pub long: Vec<[u32; 3]>,
    /// Each vertex's normal, from all its triangles.
    pub normals: Vec<Vec3>,
}

/// The length of triangle `t`'s longest edge.
pub fn longest_edge(points: &[Vec3], t: &[u32; 3]) -> f32 {
    (0..3)
        .map(|k| points[t[k] as usize].distance(points[t[(k + 1) % 3] as usize]))
        .fold(0.0, f32::max)
}

/// One splat per triangle of `long` (indices into `points`, relative to the model
/// origin; `scale` the model's unit scale): `normals` are the vertices' normals, as the
/// reference interpolates them, `colors` the file's (None: [`DEFAULT_COLOR`], the vertices'). A degenerate
/// triangle gets none.
pub fn splats(
    points: &[Vec3],
    scale: f32,
    long: &[[u32; 3]],
    normals: &[Vec3],
    ((colors, attributes), reach): (Looks, Reach),
) -> Vec<Surfel> {
    let s = scale as f64;
    long.par_iter()
        .filter_map(|t| {
            let corners = t.map(|v| {
                let color = unit_rgb(colors.map_or(DEFAULT_COLOR, |c| c[v as usize]));
                Corner {
                    position: points[v as usize].as_dvec3() * s,
                    normal: normals[v as usize].as_dvec3(),
                    color,
                }
            });
            let mut surfel = triangle_splat(corners, colors.is_some(), reach)?;
            surfel.position = (surfel.position.as_dvec3() / s).as_vec3();
            surfel.radius = (surfel.radius as f64 / s) as f32;
            if let Some(a) = attributes {
                // The LiDAR attributes of the corner nearest the splat's centre.
                let g = surfel.position;
                let near = t.iter().min_by(|&&u, &&v| {
                    let d = |w: u32| points[w as usize].distance_squared(g);
                    d(u).total_cmp(&d(v))
                });
                surfel.attributes = a[*near.unwrap_or(&t[0]) as usize];
            }
            Some(surfel)
        })
        .collect()
}

/// The file's colours and LiDAR attributes per sample, where it has them.
pub type Looks<'a> = (Option<&'a [[u8; 4]]>, Option<&'a [PointAttributes]>);

/// Which ellipse of a triangle's second moments (the Steiner family, centred on its
/// centroid: the circumellipse scaled) draws it, and how thin it may be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// Its semi-axes over the circumellipse's, which passes through the corners and
    /// covers the triangle with 4π / (3√3) ≈ 2.42 times its area; s² times that.
    pub scale: f64,
    /// Its scale where the triangle is a wall (its unit normal's z under
    /// [`WALL_NORMAL_Z`]).
    pub wall_scale: f64,
    /// Its least minor / major semi-axis ([`super::shape::MIN_PACKED_RATIO`]: as thin
    /// as the triangle's circumellipse, up to what the format holds).
    pub min_ratio: f64,
    /// Whether a wall (a triangle whose unit normal's z is under [`WALL_NORMAL_Z`])
    /// takes the colour of its corners in the upper half of its height, without a
    /// field: a terrain's ([`super::terrain`]), whose walls join a roof's edge to the
    /// street and were shaded from the roof's colour to the street's.
    pub wall_colour_from_above: bool,
}

/// A wall's largest |z| of its unit normal: steeper than 60°.
pub const WALL_NORMAL_Z: f64 = 0.5;

impl Reach {
    /// The circumellipse, no thinner than [`MIN_RATIO`]: a sensor frame's
    /// ([`super::grid`]). Its risers are needles a sensor pixel wide; as thin as they
    /// are, they missed the pixel centres that the triangulation at 1× covers, on
    /// orbits beside the sensor (kinect_rgb's worst view's holes 0.39 → 0.86 %, over
    /// the bound of 0.5 %, for FLIP 0.118 → 0.108).
    pub const CORNERS: Reach = Reach {
        scale: 1.0,
        wall_scale: 1.0,
        min_ratio: MIN_RATIO,
        wall_colour_from_above: false,
    };
}

/// A triangle's corner: unit-scaled position, vertex normal, RGB 0–1.
#[derive(Debug, Clone, Copy)]
struct Corner {
    position: DVec3,
    normal: DVec3,
    color: DVec3,
}

/// The splat of one triangle (see the module doc), in the corners' unit; None when it
/// is degenerate ([`super::triangle::DEGENERATE`]).
fn triangle_splat(corners: [Corner; 3], colored: bool, reach: Reach) -> Option<Surfel> {
    let [a, b, c] = corners.map(|k| k.position);
    let (cross, _, degenerate) = triangle_terms(a, b, c);
    if degenerate {
        return None;
    }
    let face = cross.normalize();
    let g = (a + b + c) / 3.0;
    let (major, r, ratio) = steiner_ellipse(face, [a, b, c]);
    let wall = face.z.abs() < WALL_NORMAL_Z;
    let r = r * if wall { reach.wall_scale } else { reach.scale };
    let shape = Shape::ellipse(face, major, ratio.max(reach.min_ratio));
    let at = |k: &Corner| (k.position, k.normal);
    let fan = (at(&corners[0]), |k: u32| at(&corners[k as usize]));
    let (normal, mut shape) =
        fit_field((g, face), (r, &shape), fan, std::iter::once((1, 2))).unwrap_or((face, shape));
    let mut color = corners.iter().map(|k| k.color).sum::<DVec3>() / 3.0;
    if reach.wall_colour_from_above && wall {
        color = colour_from_above(&corners);
    } else if colored {
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

/// The mean colour of the `corners` in the upper half of their heights (z).
fn colour_from_above(corners: &[Corner; 3]) -> DVec3 {
    let z = corners.map(|k| k.position.z);
    let middle = 0.5 * (z[0].max(z[1]).max(z[2]) + z[0].min(z[1]).min(z[2]));
    let upper = corners.iter().filter(|k| k.position.z >= middle);
    let (sum, n) = upper.fold((DVec3::ZERO, 0.0), |(s, n), k| (s + k.color, n + 1.0));
    sum / n
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

    /// A corner of a level, grey triangle.
    fn flat_corner(position: DVec3) -> Corner {
        Corner {
            position,
            normal: DVec3::Z,
            color: DVec3::splat(0.5),
        }
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
        let [a, b, c] = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 12.0, 0.0)];
        let s = triangle_splat([a, b, c].map(flat_corner), false, Reach::CORNERS).unwrap();
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

    #[test]
    fn a_smaller_reach_scales_the_ellipse_s_area_and_leaves_a_needle_s_tip_out() {
        // Thick enough that its ellipse is over MIN_RATIO.
        let [a, b, c] = [DVec3::ZERO, 4.0 * DVec3::X, DVec3::new(2.0, 12.0, 0.0)];
        let reach = Reach {
            scale: 0.8,
            ..Reach::CORNERS
        };
        let s = triangle_splat([a, b, c].map(flat_corner), false, reach).unwrap();
        let shape = s.shape.unpack(DVec3::Z);
        let r = s.radius as f64 / (1.0 + RADIUS_MARGIN);
        let area = std::f64::consts::PI * r * r * shape.ratio;
        let steiner = 4.0 * std::f64::consts::PI / (3.0 * 3f64.sqrt());
        let expected = 0.8 * 0.8 * steiner * 24.0;
        assert!(
            (area / expected - 1.0).abs() < 2e-3,
            "ellipse {area}, expected {expected}"
        );
        assert!(s.covers(((a + b + c) / 3.0).as_vec3()));
        assert!(!s.covers((c + (a - c) * 0.1).as_vec3()), "the tip");
    }

    #[test]
    fn a_wall_takes_the_wall_s_reach_and_a_level_needle_reaches_its_tip() {
        // The same needle lying level and standing as a wall.
        let level = [DVec3::ZERO, 4.0 * DVec3::X, DVec3::new(2.0, 12.0, 0.0)];
        let standing = level.map(|p| DVec3::new(p.x, 0.0, p.y));
        let reach = Reach {
            wall_scale: 0.8,
            ..Reach::CORNERS
        };
        let tip = |[a, _, c]: [DVec3; 3]| (c + (a - c) * 0.1).as_vec3();
        let lying = triangle_splat(level.map(flat_corner), false, reach).unwrap();
        assert!(lying.covers(tip(level)), "a level needle's tip");
        let corners = standing.map(|position| Corner {
            normal: DVec3::Y,
            ..flat_corner(position)
        });
        let wall = triangle_splat(corners, false, reach).unwrap();
        assert!(wall.covers(((standing[0] + standing[1] + standing[2]) / 3.0).as_vec3()));
        assert!(!wall.covers(tip(standing)), "a wall's tip");
    }

    #[test]
    fn a_needle_s_splat_is_as_thin_as_its_reach_lets_it_be() {
        // A mast's needle, 1 wide and 24 high: its circumellipse is 0.036 as wide as
        // long. At MIN_RATIO it would reach 4 beside the needle's axis.
        let [a, b, c] = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 24.0, 0.0)];
        let thin = Reach {
            min_ratio: crate::surfel::shape::MIN_PACKED_RATIO,
            ..Reach::CORNERS
        };
        let beside = DVec3::new(2.0, 8.0, 0.0).as_vec3();
        let on_axis = DVec3::new(0.5, 8.0, 0.0).as_vec3();
        let s = triangle_splat([a, b, c].map(flat_corner), false, thin).unwrap();
        assert!(s.covers(on_axis) && !s.covers(beside));
        assert!(s.shape.unpack(DVec3::Z).ratio < 0.05);
        let fat = triangle_splat([a, b, c].map(flat_corner), false, Reach::CORNERS).unwrap();
        assert!(fat.covers(beside), "MIN_RATIO's sail");
    }

    #[test]
    fn a_terrain_s_wall_takes_its_upper_corners_colour() {
        // A wall 0.5 wide and 6 high: two corners on a red roof's edge, one on the
        // grey street below.
        let corner = |position: DVec3, color: DVec3| Corner {
            position,
            normal: DVec3::Y,
            color,
        };
        let (red, grey) = (DVec3::new(0.8, 0.2, 0.2), DVec3::splat(0.6));
        let wall = [
            corner(DVec3::new(0.0, 0.0, 6.0), red),
            corner(DVec3::new(0.5, 0.0, 6.0), red),
            corner(DVec3::new(0.2, 0.1, 0.0), grey),
        ];
        let from_above = Reach {
            wall_colour_from_above: true,
            ..Reach::CORNERS
        };
        let s = triangle_splat(wall, true, from_above).unwrap();
        assert_eq!(s.color, [204, 51, 51, 255]);
        assert_eq!(s.shape.unpack(s.normal.as_dvec3()).color, [DVec3::ZERO; 2]);
        let blended = triangle_splat(wall, true, Reach::CORNERS).unwrap();
        assert!(blended.color[1] > 80, "{:?}", blended.color);
    }
}
