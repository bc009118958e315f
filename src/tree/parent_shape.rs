//! The ellipse and normal field of an internal node from its children's (docs/design.md §3),
//! so that level of detail keeps the shading of the leaves.
//!
//! Each child contributes its centre (with its normal) and [`RIM_SAMPLES`] points of its
//! ellipse's rim (with the normals of its field there), offsets taken in the parent's
//! tangent frame; their [`Fit`] gives the parent's axes, ratio and normal field as for a
//! mesh vertex's one-ring. The major semi-axis R is the smallest that holds every rim
//! sample pushed out by 1/cos(π/[`RIM_SAMPLES`]) from its child's centre: the polygon of
//! the samples, so enlarged, holds the child's ellipse (in the child's own affine frame,
//! and affine maps keep containment), and the parent's ellipse is convex. When that R
//! exceeds the same growth of the radius r of the circle that reaches every child
//! (`errors::parent_disk`), the node is that circle. The node's errors are computed for
//! its ellipse over its children's (`errors::Splat`).
//!
//! The normal field is fitted to each sample's tangential normal components over its
//! normal component (tan of its tilt), since pass 2 draws normalize(n + G d): an inner
//! node seen from far spans tens of degrees of the surface's normals, where fitting
//! their sine left it too flat. Far orbit (42 radii, 8 views, `--example quality
//! --distance 42.44`), FLIP at ε = 1 px over leaves only: knot 1.11 → 1.04, bunny
//! 1.27 → 1.28, dragon 1.26 → 1.25.
//!
//! Its colour field is fitted from the same samples: each child's colour plus its own
//! field at its centre and rim points, in least squares with an intercept
//! ([`field::color_field`]); the node's colour stays its children's mean. Fitted from
//! the children's centres alone, three children nearly on a line gave a steep,
//! ill-posed field that streaked a cloud's level of detail; the rims span the plane
//! wherever the children do. Knot, ε = 1 px, 8 views (`--example quality`): 0.0465
//! with one colour per inner node, 0.0449 with the field (leaves only: 0.0421).

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3};

use super::errors::{DIRECTION_COS, DIRECTION_SIN, Disk};
use super::hierarchy::MAX_CHILDREN;
use crate::surfel::field;
use crate::surfel::shape::{Fit, MIN_RATIO, Shape, rotate_gradient, tangent_frame};

/// Rim points sampled per child, at the directions of the errors' table.
pub const RIM_SAMPLES: usize = 16;
const _: () = assert!(RIM_SAMPLES == super::errors::DIRECTIONS);

/// 1 / cos(π / [`RIM_SAMPLES`]): how far each rim sample is pushed out from its child's
/// centre so that the polygon of the samples holds the child's ellipse.
const RIM_GROWTH: f64 = 1.019_591_158_208_318_4;

/// Samples tilted further than 60° from the parent's normal count as 60°: beyond that
/// a node straddles a crease, which no linear field follows (as `MAX_GRADIENT`).
const MIN_COS_TILT: f64 = 0.5;

/// A child as the parent's shape sees it: its disk and shape (a normal pointing away
/// from the parent's, in an unoriented cloud, is flipped where it is sampled).
#[derive(Debug, Clone, Copy)]
pub struct Child {
    pub disk: Disk,
    pub shape: Shape,
    /// RGB, 0–1: the colour at the child's centre (its field adds to it).
    pub color: DVec3,
}

/// A child's samples seen from its parent: its centre and its rim points, at plane
/// coordinates (x, y) = (cos θ, sin θ · ratio) of its ellipse for θ in the errors'
/// direction table. Each sample's position and normal direction are linear in (x, y):
/// the position p + r (x u + y v), the direction n + u g₁ + v g₂ with (g₁, g₂) = G (x,
/// y) ([`Shape::field_at`]; u, v the child's axes). So the child's vectors are projected
/// on the parent's axes once, and each sample combines the projections.
struct Seen {
    /// In the parent's tangent frame: the centre's offset, r u and r v.
    offset: DVec2,
    along: DVec2,
    across: DVec2,
    /// The normal's, u's and v's coordinates in the parent's frame and along its normal
    /// (an orthonormal basis, so lengths are kept), signed (turned toward the parent's
    /// normal).
    n: DVec3,
    u: DVec3,
    v: DVec3,
    /// The child's own field G (a, b, c), and its rim points' (x, y).
    gradient: [f64; 3],
    ratio: f64,
}

impl Seen {
    /// The child as its parent (centre `at`, normal `normal`, frame (t1, t2)) sees it.
    fn of(child: &Child, (at, normal): (DVec3, DVec3), (t1, t2): (DVec3, DVec3)) -> Seen {
        let Child { disk, shape, .. } = child;
        let sign = if disk.n.dot(normal) < 0.0 { -1.0 } else { 1.0 };
        let minor = shape.minor_axis(disk.n);
        let frame = |d: DVec3| DVec2::new(d.dot(t1), d.dot(t2));
        let local = |d: DVec3| DVec3::new(d.dot(t1), d.dot(t2), d.dot(normal)) * sign;
        let (n, u, v) = (disk.n, shape.axis, minor);
        Seen {
            offset: frame(disk.p - at),
            along: frame(u * disk.r),
            across: frame(v * disk.r),
            n: local(n),
            u: local(u),
            v: local(v),
            gradient: shape.gradient,
            ratio: shape.ratio,
        }
    }

    /// The offset in the parent's frame of the child's point at plane coordinates
    /// (x, y), its ellipse `grow` times as large.
    #[inline(always)]
    fn offset_at(&self, (x, y): (f64, f64), grow: f64) -> DVec2 {
        self.offset + self.along * grow * x + self.across * grow * y
    }

    /// Rim sample `k`'s plane coordinates in the child's ellipse.
    #[inline(always)]
    fn rim_xy(&self, k: usize) -> (f64, f64) {
        (DIRECTION_COS[k], DIRECTION_SIN[k] * self.ratio)
    }

    /// The sample at plane coordinates (x, y) as the fit takes it: its offset in the
    /// parent's frame, and the tangent of its tilt ([`tilt`]).
    #[inline(always)]
    fn sample(&self, (x, y): (f64, f64)) -> (DVec2, DVec2) {
        let [a, b, c] = self.gradient;
        let (g1, g2) = (a * x + b * y, b * x + c * y);
        // A field that is not finite leaves the child's normal.
        let finite = g1.is_finite() & g2.is_finite();
        let (g1, g2) = (if finite { g1 } else { 0.0 }, if finite { g2 } else { 0.0 });
        let m = self.n + self.u * g1 + self.v * g2;
        (self.offset_at((x, y), 1.0), tilt(m))
    }

    /// Its rim samples as the fit takes them ([`Seen::sample`]), in columns: the
    /// offsets' x and y, the tilts' x and y.
    fn rim_samples(&self) -> [[f64; RIM_SAMPLES]; 4] {
        let mut columns = [[0.0; RIM_SAMPLES]; 4];
        // k indexes the direction table and the four columns alike.
        #[allow(clippy::needless_range_loop)]
        for k in 0..RIM_SAMPLES {
            let (d, t) = self.sample(self.rim_xy(k));
            [columns[0][k], columns[1][k]] = d.to_array();
            [columns[2][k], columns[3][k]] = t.to_array();
        }
        columns
    }

    /// The largest ρ² = (d·u)² + (d·v · stretch)² of its rim points d, its ellipse
    /// [`RIM_GROWTH`] times as large, offsets in the parent's frame.
    fn farthest_rim(&self, (u, v): (DVec2, DVec2), stretch: f64) -> f64 {
        let mut rho2 = [0.0f64; RIM_SAMPLES];
        for (k, rho2) in rho2.iter_mut().enumerate() {
            let d = self.offset_at(self.rim_xy(k), RIM_GROWTH);
            let (x, y) = (d.dot(u), d.dot(v) * stretch);
            *rho2 = x * x + y * y;
        }
        rho2.into_iter().fold(0.0, f64::max)
    }
}

/// The tangent of a sample's tilt from the parent's normal, for its direction `m` (any
/// length; x, y in the parent's frame, z along its normal): m_xy / m_z, its cosine
/// m_z / |m| taken as at least [`MIN_COS_TILT`]. Branch-free, so that a child's rim
/// samples run in vector lanes.
#[inline(always)]
fn tilt(m: DVec3) -> DVec2 {
    let (along, length2) = (m.z, m.length_squared());
    let unclamped = (along > 0.0) & (along * along >= MIN_COS_TILT * MIN_COS_TILT * length2);
    let denominator = if unclamped {
        along
    } else {
        MIN_COS_TILT * length2.sqrt()
    };
    m.truncate() * denominator.recip()
}

/// The parent's shape and major semi-axis, given its disk `parent` (centre, normal and
/// the radius that reaches every child) and its children (at most
/// [`MAX_CHILDREN`], as the hierarchy makes them).
pub fn parent_shape(parent: &Disk, children: &[Child]) -> (Shape, f64) {
    assert!(
        children.len() <= MAX_CHILDREN,
        "{} children",
        children.len()
    );
    let (t1, t2) = tangent_frame(parent.n);
    let mut seen: ArrayVec<Seen, MAX_CHILDREN> = ArrayVec::new();
    let mut fit = Fit::default();
    for child in children {
        let s = Seen::of(child, (parent.p, parent.n), (t1, t2));
        // The field's normal is normalize(n + G d): G d must be the sample's
        // tangential part over its normal part, tan of its tilt (not its sine).
        let (d, t) = s.sample((0.0, 0.0));
        fit.add(d, t);
        let [dx, dy, tx, ty] = s.rim_samples();
        for k in 0..RIM_SAMPLES {
            fit.add(DVec2::new(dx[k], dy[k]), DVec2::new(tx[k], ty[k]));
        }
        seen.push(s);
    }
    let (dir, l1, l2) = fit.axes();
    let ratio = if l1 > 0.0 {
        (l2 / l1).sqrt().clamp(MIN_RATIO, 1.0)
    } else {
        1.0
    };
    let mut shape = Shape {
        axis: (t1 * dir.x + t2 * dir.y).normalize_or(t1),
        ratio,
        gradient: rotate_gradient(fit.gradient(), dir),
        // Children's clip lines are not merged: an inner node's ellipse holds them whole.
        clip: None,
        color: [DVec3::ZERO; 2],
    };
    // The ellipse's axes in the frame: each sample's offset along them.
    let (u, v) = (dir, dir.perp());
    // The largest ρ², then one root (√ is monotone and correctly rounded: the same
    // value as the largest root).
    let stretch = ratio.recip();
    let major2 = (seen.iter())
        .map(|s| s.farthest_rim((u, v), stretch))
        .fold(0.0, f64::max);
    let mut major = major2.sqrt();
    if !(major > 0.0 && major <= parent.r * RIM_GROWTH) {
        shape.ratio = 1.0;
        major = parent.r;
    }
    shape.gradient = shape.gradient.map(|g| g * major);
    shape.color = color_field((u, v), major, children, &seen);
    (shape, major)
}

/// The parent's colour field: the least squares ([`field::color_field`]) of its
/// children's colours (each its colour plus its own field) at their centres and rim
/// points (`seen`), in the parent's ellipse frame (its axes `u`, `v` in its tangent
/// frame; major radii), each child weighing its ellipse's area r² · ratio. Zero where
/// the samples do not span the plane.
fn color_field(
    (u, v): (DVec2, DVec2),
    major: f64,
    children: &[Child],
    seen: &[Seen],
) -> [DVec3; 2] {
    // One colour and no field over every child (every node of a model without colours)
    // is a constant: its least squares has no slope.
    let first = children.first().map(|c| c.color);
    if children
        .iter()
        .all(|c| Some(c.color) == first && c.shape.color == [DVec3::ZERO; 2])
    {
        return [DVec3::ZERO; 2];
    }
    let points = children.iter().zip(seen).flat_map(|(child, s)| {
        let Child {
            disk,
            shape: own,
            color,
        } = child;
        let w = disk.r * disk.r * own.ratio;
        let rim = (0..RIM_SAMPLES).map(|k| s.rim_xy(k));
        std::iter::once((0.0, 0.0)).chain(rim).map(move |(x, y)| {
            let d = s.offset_at((x, y), 1.0);
            let xy = DVec2::new(d.dot(u), d.dot(v)) / major;
            (xy, *color + own.color[0] * x + own.color[1] * y, w)
        })
    });
    field::color_field(points).map_or([DVec3::ZERO; 2], |(_, field)| field)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn child(p: [f64; 3], r: f64, ratio: f64) -> Child {
        let n = DVec3::Z;
        Child {
            disk: Disk {
                p: DVec3::from(p),
                n,
                r,
            },
            shape: Shape {
                axis: DVec3::X,
                ratio,
                gradient: [0.0; 3],
                clip: None,
                color: [DVec3::ZERO; 2],
            },
            color: DVec3::ZERO,
        }
    }

    #[test]
    fn the_rim_growth_is_the_polygon_s() {
        let want = 1.0 / (std::f64::consts::PI / RIM_SAMPLES as f64).cos();
        assert!(
            (RIM_GROWTH - want).abs() <= f64::EPSILON,
            "{RIM_GROWTH} against {want}"
        );
    }

    #[test]
    fn a_row_of_children_gives_an_elongated_ellipse_that_holds_them() {
        let children: Vec<Child> = (0..4)
            .map(|i| child([i as f64 - 1.5, 0.0, 0.0], 0.6, 0.5))
            .collect();
        let parent = Disk {
            p: DVec3::ZERO,
            n: DVec3::Z,
            r: 2.1,
        };
        let (shape, major) = parent_shape(&parent, &children);
        assert!(shape.axis.dot(DVec3::X).abs() > 0.999, "{shape:?}");
        assert!(shape.ratio < 0.5, "{shape:?}");
        assert!(major <= parent.r * 1.02);
        // Every child's rim (densely sampled) lies in the parent's ellipse.
        let minor = shape.minor_axis(DVec3::Z);
        for c in &children {
            for k in 0..360 {
                let (s, co) = (k as f64).to_radians().sin_cos();
                let q = c.disk.p + (DVec3::X * co + DVec3::Y * s * 0.5) * c.disk.r;
                let rho = q.dot(shape.axis).hypot(q.dot(minor) / shape.ratio) / major;
                assert!(rho <= 1.0 + 1e-9, "rim point {q} at ρ = {rho}");
            }
        }
    }

    #[test]
    fn children_on_a_sphere_give_its_curvature() {
        // Children on the unit sphere around the north pole, each with the sphere's
        // field (G = identity per unit length, times its radius): the parent's is too.
        let mut children = Vec::new();
        for (x, y) in [(0.1, 0.0), (-0.1, 0.0), (0.0, 0.1), (0.0, -0.1)] {
            let n = DVec3::new(x, y, 1.0).normalize();
            children.push(Child {
                disk: Disk { p: n, n, r: 0.08 },
                shape: Shape {
                    gradient: [0.08, 0.0, 0.08],
                    ..Shape::circle(n)
                },
                color: DVec3::ZERO,
            });
        }
        let parent = Disk {
            p: DVec3::new(0.0, 0.0, 0.995),
            n: DVec3::Z,
            r: 0.2,
        };
        let (shape, major) = parent_shape(&parent, &children);
        let [a, b, c] = shape.gradient.map(|g| g / major);
        assert!(
            (a - 1.0).abs() < 0.1 && (c - 1.0).abs() < 0.1 && b.abs() < 0.05,
            "{a} {b} {c}"
        );
    }

    #[test]
    fn a_wide_node_s_field_turns_its_normal_as_far_as_its_children_s() {
        // Children 40° from the pole of the unit sphere: the field normalize(n + G d)
        // must tilt by tan 40° over their offset sin 40° (fitting the normals' sine
        // instead would give atan(sin 40°) = 33°).
        let angle = 40f64.to_radians();
        let children: Vec<Child> = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
            .map(|(x, y)| {
                let n = DVec3::new(x * angle.sin(), y * angle.sin(), angle.cos());
                Child {
                    disk: Disk { p: n, n, r: 0.1 },
                    shape: Shape {
                        gradient: [0.1, 0.0, 0.1],
                        ..Shape::circle(n)
                    },
                    color: DVec3::ZERO,
                }
            })
            .into();
        let parent = Disk {
            p: DVec3::new(0.0, 0.0, angle.cos()),
            n: DVec3::Z,
            r: angle.sin() + 0.1,
        };
        let (shape, major) = parent_shape(&parent, &children);
        let v = shape.minor_axis(DVec3::Z);
        for c in &children {
            let d = c.disk.p - parent.p;
            let n = shape.normal_at(DVec3::Z, d.dot(shape.axis) / major, d.dot(v) / major);
            let off = n.angle_between(c.disk.n).to_degrees();
            assert!(off < 2.0, "{off}° from the child's normal");
        }
    }

    #[test]
    fn children_on_a_colour_ramp_give_the_ramp() {
        // Colour 0.5 + 0.2 x (per unit length) sampled by four children, each with its
        // own field (0.2 r along its axis X): the parent's field is the same ramp.
        let ramp = |x: f64| 0.5 + 0.2 * x;
        let (r, ratio) = (0.6, 0.8);
        let children: Vec<Child> = [(-0.5, -0.4), (0.5, -0.4), (-0.5, 0.4), (0.5, 0.4)]
            .map(|(x, y)| Child {
                color: DVec3::splat(ramp(x)),
                shape: Shape {
                    color: [DVec3::splat(0.2 * r), DVec3::ZERO],
                    ..child([x, y, 0.0], r, ratio).shape
                },
                ..child([x, y, 0.0], r, ratio)
            })
            .into();
        let parent = Disk {
            p: DVec3::ZERO,
            n: DVec3::Z,
            r: 1.3,
        };
        let (shape, major) = parent_shape(&parent, &children);
        let v = shape.minor_axis(DVec3::Z);
        for q in [DVec3::new(0.7, 0.2, 0.0), DVec3::new(-0.3, -0.6, 0.0)] {
            let (x, y) = (q.dot(shape.axis) / major, q.dot(v) / major);
            let got = ramp(0.0) + shape.color[0].x * x + shape.color[1].x * y;
            assert!(
                (got - ramp(q.x)).abs() < 1e-9,
                "{got} at {q}, not {}",
                ramp(q.x)
            );
        }
    }
}
