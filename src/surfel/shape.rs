//! A splat's shape beyond its disk (docs/design.md §2): an ellipse in the tangent plane and a
//! linear normal field (Phong splatting: Botsch, Spernat and Kobbelt 2004).
//!
//! With n the splat's unit normal, R its radius (the ellipse's major semi-axis), u the
//! major axis (unit, ⟂ n) and v = n × u, the point p + R(x u + y v) of the splat's
//! plane lies in the ellipse iff x² + (y / ratio)² ≤ 1, and its normal is
//!
//! ```text
//! normalize(n + (a x + b y) u + (b x + c y) v),   G = [[a, b], [b, c]]
//! ```
//!
//! G is the change of the normal over one radius R along u and v: the (negated) shape
//! operator of the surface times R, dimensionless, symmetric as a shape operator is.
//!
//! A mesh splat may carry a linear colour field the same way: colour + cₓ x + c_y y,
//! with cₓ, c_y the change of the RGB colour (0–1) over one radius along u and v
//! (`field.rs` fits them to the triangles' interpolated colours; zero elsewhere).
//!
//! A splat on the mesh's border may also carry a [`Clip`] (a line or its fan's wedge,
//! `clip.rs`), so that it ends at the border instead of spilling past it.
//!
//! Stored as [`SplatShape`], 24 bytes: u octahedral in two snorm16 (≤ 3·10⁻⁵ rad off,
//! re-orthogonalised to n when drawn), the ratio and a, b, c as f16 (relative error
//! ≤ 2⁻¹¹; |G| is clamped to [`MAX_GRADIENT`]), the clip in one u32 (`clip.rs`), and
//! the colour field in two: its six components as snorm8 times a shared f16 scale
//! (their largest magnitude; error ≤ scale / 254).

use bytemuck::{Pod, Zeroable};
use glam::{DVec2, DVec3, Vec3};
use half::f16;

pub use crate::surfel::clip::Clip;
use crate::surfel::octahedral::{oct_decode, oct_encode};

/// The thinnest ellipse fitted to samples (a vertex's ring, a cloud's neighbours, a
/// node's children): minor / major semi-axis.
pub const MIN_RATIO: f64 = 0.25;
/// The thinnest ellipse [`SplatShape`] holds. A terrain's triangle draws its own splat
/// as thin as it is (`long_triangles`): a wall's or a mast's needle, 1/30 as wide as
/// long, made an ellipse [`MIN_RATIO`] thin a fat sail beside it.
pub const MIN_PACKED_RATIO: f64 = 1.0 / 256.0;
/// Largest |a|, |b|, |c|: a normal turning by more than about 60° over one radius is a
/// crease, not a curvature the field should follow.
pub const MAX_GRADIENT: f64 = 2.0;

/// The packed shape of one splat (see the module doc).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct SplatShape {
    /// The major axis u, octahedral snorm16 × 2.
    pub axis: u32,
    /// Minor / major semi-axis, f16 bits, in [MIN_PACKED_RATIO, 1].
    pub ratio: u16,
    /// a, b, c of G, f16 bits.
    pub gradient: [u16; 3],
    /// The clip, packed by [`Clip::pack`].
    pub clip: u32,
    /// The colour field: cₓ (r, g, b) and c_y r as snorm8 in the first word; c_y g, b
    /// as snorm8 in the low half of the second, the f16 scale in its high half.
    pub color: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<SplatShape>() == 24);

/// A splat's shape, unpacked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    /// Major axis: unit, ⟂ the splat's normal.
    pub axis: DVec3,
    pub ratio: f64,
    /// a, b, c of G.
    pub gradient: [f64; 3],
    pub clip: Option<Clip>,
    /// cₓ and c_y, the colour's change (RGB, 0–1) over one radius along u and v.
    pub color: [DVec3; 2],
}

impl Shape {
    /// A round splat of constant normal.
    pub fn circle(normal: DVec3) -> Shape {
        Shape {
            axis: normal.any_orthonormal_vector(),
            ratio: 1.0,
            gradient: [0.0; 3],
            clip: None,
            color: [DVec3::ZERO; 2],
        }
    }

    /// A constant-normal ellipse of major axis `axis` (made ⟂ `normal`) and `ratio`.
    pub fn ellipse(normal: DVec3, axis: DVec3, ratio: f64) -> Shape {
        Shape {
            axis: (axis - normal * axis.dot(normal))
                .try_normalize()
                .unwrap_or_else(|| normal.any_orthonormal_vector()),
            ratio,
            ..Shape::circle(normal)
        }
    }

    /// The minor axis v = n × u.
    pub fn minor_axis(&self, normal: DVec3) -> DVec3 {
        normal.cross(self.axis)
    }

    /// An offset `d` from the splat's centre along u and v: its plane coordinates times
    /// the radius R (divide by R for the module doc's x, y).
    pub fn along_axes(&self, normal: DVec3, d: DVec3) -> DVec2 {
        DVec2::new(d.dot(self.axis), d.dot(self.minor_axis(normal)))
    }

    /// The normal at plane coordinates (x, y) (in radii along u, v).
    pub fn normal_at(&self, normal: DVec3, x: f64, y: f64) -> DVec3 {
        self.field_at(normal, self.minor_axis(normal), (x, y))
            .normalize_or(normal)
    }

    /// The field's normal at plane coordinates (x, y) before it is normalized, n + G
    /// (x, y) in the frame (u, `minor`): a direction, no shorter than n where u and
    /// `minor` are ⟂ n (as `unpack` makes them), and finite where G is.
    pub fn field_at(&self, normal: DVec3, minor: DVec3, (x, y): (f64, f64)) -> DVec3 {
        let [a, b, c] = self.gradient;
        normal + self.axis * (a * x + b * y) + minor * (b * x + c * y)
    }

    pub fn pack(&self) -> SplatShape {
        let h = |x: f64| f16::from_f64(x).to_bits();
        SplatShape {
            axis: oct_encode(self.axis.as_vec3()),
            ratio: h(self.ratio.clamp(MIN_PACKED_RATIO, 1.0)),
            gradient: self
                .gradient
                .map(|g| h(g.clamp(-MAX_GRADIENT, MAX_GRADIENT))),
            clip: Clip::pack(self.clip),
            color: pack_color(self.color),
        }
    }
}

/// The colour field's words (see [`SplatShape::color`]).
fn pack_color([x, y]: [DVec3; 2]) -> [u32; 2] {
    let values = [x.x, x.y, x.z, y.x, y.y, y.z];
    let scale = f16::from_f64(values.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    let s = scale.to_f64();
    let q = |v: f64| {
        let n = if s > 0.0 {
            (v / s * 127.0).round().clamp(-127.0, 127.0)
        } else {
            0.0
        };
        (n as i8) as u8 as u32
    };
    [
        q(values[0]) | q(values[1]) << 8 | q(values[2]) << 16 | q(values[3]) << 24,
        q(values[4]) | q(values[5]) << 8 | (scale.to_bits() as u32) << 16,
    ]
}

/// Inverse of [`pack_color`].
fn unpack_color(words: [u32; 2]) -> [DVec3; 2] {
    let s = f16::from_bits((words[1] >> 16) as u16).to_f64();
    let v = |w: u32, k: u32| ((w >> (8 * k)) as u8 as i8) as f64 / 127.0 * s;
    [
        DVec3::new(v(words[0], 0), v(words[0], 1), v(words[0], 2)),
        DVec3::new(v(words[0], 3), v(words[1], 0), v(words[1], 1)),
    ]
}

impl SplatShape {
    /// The shape of a splat of unit normal `normal`; the axis is made ⟂ to it again.
    pub fn unpack(&self, normal: DVec3) -> Shape {
        let f = |b: u16| f16::from_bits(b).to_f64();
        let u = oct_decode(self.axis).as_dvec3();
        let axis = (u - normal * u.dot(normal))
            .try_normalize()
            .unwrap_or_else(|| normal.any_orthonormal_vector());
        Shape {
            axis,
            ratio: f(self.ratio),
            gradient: self.gradient.map(f),
            clip: Clip::unpack(self.clip),
            color: unpack_color(self.color),
        }
    }

    pub fn circle(normal: Vec3) -> SplatShape {
        Shape::circle(normal.as_dvec3()).pack()
    }
}

/// Least-squares sums over a splat's neighbourhood, in a tangent frame (t₁, t₂): the
/// 2×2 second moment S of the offsets d (the ellipse's shape), and the normal equations
/// of the symmetric G minimising Σ |G d − Δn|² (Δn: a neighbour's normal minus the
/// splat's, in the frame).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Fit {
    /// Σ d₁², Σ d₁d₂, Σ d₂².
    pub moments: [f64; 3],
    /// Σ d₁Δ₁, Σ (d₂Δ₁ + d₁Δ₂), Σ d₂Δ₂.
    pub rhs: [f64; 3],
}

impl Fit {
    pub fn add(&mut self, d: DVec2, dn: DVec2) {
        self.add_weighted(d, dn, 1.0);
    }

    /// [`Fit::add`] with weight `w`.
    pub fn add_weighted(&mut self, d: DVec2, dn: DVec2, w: f64) {
        self.moments[0] += w * d.x * d.x;
        self.moments[1] += w * d.x * d.y;
        self.moments[2] += w * d.y * d.y;
        self.rhs[0] += w * d.x * dn.x;
        self.rhs[1] += w * (d.y * dn.x + d.x * dn.y);
        self.rhs[2] += w * d.y * dn.y;
    }

    pub fn merge(&mut self, other: &Fit) {
        for k in 0..3 {
            self.moments[k] += other.moments[k];
            self.rhs[k] += other.rhs[k];
        }
    }

    /// G (a, b, c) per unit of length in the frame: the 3×3 normal equations
    /// [[S₁₁, S₁₂, 0], [S₁₂, S₁₁ + S₂₂, S₁₂], [0, S₁₂, S₂₂]] (a, b, c) = rhs, with a
    /// small ridge (10⁻⁶ of the trace) so that a neighbourhood on a line gets the
    /// least-norm answer along the other direction; zero when the sums are empty.
    pub fn gradient(&self) -> [f64; 3] {
        let [s11, s12, s22] = self.moments;
        let ridge = 1e-6 * (s11 + s22);
        if s11 + s22 <= 0.0 || !ridge.is_finite() {
            return [0.0; 3];
        }
        let m = glam::DMat3::from_cols_array_2d(&[
            [s11 + ridge, s12, 0.0],
            [s12, s11 + s22 + ridge, s12],
            [0.0, s12, s22 + ridge],
        ]);
        let det = m.determinant();
        if det.abs() <= f64::MIN_POSITIVE || !det.is_finite() {
            return [0.0; 3];
        }
        let g = m.inverse() * DVec3::from(self.rhs);
        if g.is_finite() {
            g.to_array()
        } else {
            [0.0; 3]
        }
    }

    /// The principal axes of S: (unit major direction in the frame, λ₁ ≥ λ₂ ≥ 0).
    pub fn axes(&self) -> (DVec2, f64, f64) {
        let [s11, s12, s22] = self.moments;
        let mean = 0.5 * (s11 + s22);
        let half_gap = (0.25 * (s11 - s22).powi(2) + s12 * s12).sqrt();
        let (l1, l2) = (mean + half_gap, (mean - half_gap).max(0.0));
        let dir = if s12.abs() > 1e-12 * (s11 + s22) {
            DVec2::new(l1 - s22, s12).normalize_or(DVec2::X)
        } else if s11 >= s22 {
            DVec2::X
        } else {
            DVec2::Y
        };
        (dir, l1, l2)
    }
}

/// G = [[a, b], [b, c]] of the frame (t₁, t₂) expressed in the frame rotated to the unit
/// direction `u` (its coordinates in the old frame): Rᵀ G R, R = [u, u⊥].
pub fn rotate_gradient(g: [f64; 3], u: DVec2) -> [f64; 3] {
    let (c, s) = (u.x, u.y);
    let [a, b, d] = g;
    [
        c * c * a + 2.0 * c * s * b + s * s * d,
        (c * c - s * s) * b + c * s * (d - a),
        s * s * a - 2.0 * c * s * b + c * c * d,
    ]
}

/// A tangent frame of `normal`: the same for the same normal on every machine.
pub fn tangent_frame(normal: DVec3) -> (DVec3, DVec3) {
    let t1 = normal.any_orthonormal_vector();
    (t1, normal.cross(t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_recovers_a_paraboloid_s_shape_operator() {
        // Principal curvatures k₁, k₂ along e₁ (30° in the frame) and e₂: at offset d the
        // normal changes by −k₁ (d·e₁) e₁ − k₂ (d·e₂) e₂.
        let (k1, k2) = (0.8, -0.3);
        let e1 = DVec2::from_angle(30f64.to_radians());
        let e2 = e1.perp();
        let mut fit = Fit::default();
        for i in 0..12 {
            let d = DVec2::from_angle(i as f64 * std::f64::consts::FRAC_PI_6)
                * (0.05 + 0.01 * (i % 3) as f64);
            fit.add(d, e1 * (-k1 * d.dot(e1)) + e2 * (-k2 * d.dot(e2)));
        }
        let g = rotate_gradient(fit.gradient(), e1);
        assert!((g[0] + k1).abs() < 1e-5, "{g:?}");
        assert!(g[1].abs() < 1e-5, "{g:?}");
        assert!((g[2] + k2).abs() < 1e-5, "{g:?}");
    }

    #[test]
    fn axes_of_an_anisotropic_neighbourhood() {
        let u = DVec2::from_angle(0.4);
        let mut fit = Fit::default();
        for s in [-2.0, -1.0, 1.0, 2.0] {
            fit.add(u * s, DVec2::ZERO);
            fit.add(u.perp() * s * 0.5, DVec2::ZERO);
        }
        let (dir, l1, l2) = fit.axes();
        assert!(dir.dot(u).abs() > 1.0 - 1e-9, "{dir} vs {u}");
        assert!((l2 / l1 - 0.25).abs() < 1e-9, "{l1} {l2}");
        assert_eq!(Fit::default().gradient(), [0.0; 3]);
    }

    #[test]
    fn packing_keeps_the_shape() {
        let n = DVec3::new(0.3, -0.4, 0.8).normalize();
        let (t1, t2) = tangent_frame(n);
        let shape = Shape {
            axis: (t1 * 0.6 + t2 * 0.8).normalize(),
            ratio: 0.4,
            gradient: [0.5, -0.25, 1.5],
            clip: Some(Clip::Line {
                normal: DVec2::from_angle(2.0),
                offset: -0.3,
            }),
            color: [DVec3::new(0.2, -0.05, 0.0), DVec3::new(-0.1, 0.4, 0.01)],
        };
        let back = shape.pack().unpack(n);
        for (a, b) in back.color.iter().zip(shape.color) {
            // snorm8 of the largest component, 0.4: 0.4 / 254 at most.
            assert!(
                (*a - b).abs().max_element() <= 0.4 / 254.0 + 1e-6,
                "{a} against {b}"
            );
        }
        assert!(back.axis.dot(shape.axis) > 1.0 - 1e-8);
        assert!(back.axis.dot(n).abs() < 1e-12);
        assert!((back.ratio - 0.4).abs() < 1e-3);
        for (a, b) in back.gradient.iter().zip(shape.gradient) {
            assert!((a - b).abs() <= b.abs() * 1e-3);
        }
        assert!(matches!(back.clip, Some(Clip::Line { .. })), "{back:?}");
        let none = Shape {
            clip: None,
            ..shape
        }
        .pack()
        .unpack(n);
        assert_eq!(none.clip, None);
        let circle = SplatShape::circle(Vec3::Z).unpack(DVec3::Z);
        assert_eq!(circle.normal_at(DVec3::Z, 0.7, -0.2), DVec3::Z);
    }
}
