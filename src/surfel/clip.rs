//! Where a splat on the mesh's border ends (Zwicker et al. 2002's clipped splats), in
//! its plane coordinates (x, y) (major radii along u and v = n × u, see `shape.rs`).
//!
//! * [`Clip::Line`]: the points with normal · (x, y) > offset are cut away;
//! * [`Clip::Wedge`]: the vertex's fan of triangles, the sweep counter-clockwise (seen
//!   from n) from the direction at angle `start` to that at `end`, each side moved out by
//!   [`WEDGE_MARGIN`]. A point is cut when it lies beyond the start side (its normal
//!   `start` turned clockwise) or beyond the end side (`end` turned counter-clockwise):
//!   beyond either on a convex fan (a sweep under 180°, which keeps the intersection
//!   of the two half-planes), beyond both on a reflex one (which keeps their union).
//!
//! Stored in one u32 (`SplatShape::clip`): a line as θ of its normal in 2π/65536 steps
//! (low 16 bits) and its offset as f16 bits (high 16 bits, +∞: no clip); a wedge as
//! the f16 bits 0b111111 on top (−∞ or a NaN, never a stored offset), then the angles
//! of `start` and `end` in 2π/8192 steps (13 bits each, `end` lowest), each rounded
//! outward so that the stored wedge holds the exact one.

use glam::DVec2;
use half::f16;
use std::f64::consts::TAU;

/// How far a wedge's sides lie outside the fan's border edges, major radii: a ray that
/// crosses a border triangle near its border edge meets the curved patch a little off
/// the triangle's plane position, and must still be kept.
pub const WEDGE_MARGIN: f32 = 1.0 / 32.0;

/// Where a splat ends (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Clip {
    Line {
        /// Unit, pointing out of the splat's kept side.
        normal: DVec2,
        /// Distance of the line from the centre, major radii (may be negative).
        offset: f64,
    },
    Wedge {
        /// Angles (radians, from u toward v) of the fan's first and last border edges:
        /// angles rather than unit vectors keep a shape as small as a line's.
        start: f64,
        end: f64,
    },
}

// `ring_shapes` holds a shape per vertex of the mesh (14 M on the Lucy-size model): a
// wedge no larger than a line keeps that memory where it was.
const _: () = assert!(std::mem::size_of::<Option<Clip>>() == 32);

/// The packed "no clip": a line at offset +∞ (the shader tests the offset's bits).
pub const NO_CLIP: u32 = (f16::INFINITY.to_bits() as u32) << 16;
/// Bits of each of a wedge's two angles (the shader reads this and [`WEDGE_TAG`]).
pub const WEDGE_ANGLE_BITS: u32 = 13;
/// The top bits that mark a wedge: f16 bits 0b111111 (−∞ or a NaN), never a line's
/// stored offset.
pub const WEDGE_TAG: u32 = !0 << (2 * WEDGE_ANGLE_BITS);
const WEDGE_STEPS: f64 = (1u32 << WEDGE_ANGLE_BITS) as f64;
const _: () = assert!(WEDGE_TAG == 0b111111 << 26);

/// The angle of `d` in turns, in [0, 1).
fn turns(d: DVec2) -> f64 {
    (d.to_angle() / TAU).rem_euclid(1.0)
}

impl Clip {
    /// The line through plane points `a` and `b` (major radii) as a clip that keeps the
    /// splat's centre; None when the line is degenerate or passes through the centre.
    pub fn line_through(a: DVec2, b: DVec2) -> Option<Clip> {
        let mut normal = (b - a).perp().try_normalize()?;
        if normal.dot(a) < 0.0 {
            normal = -normal;
        }
        let offset = normal.dot(a);
        (offset > 0.0).then_some(Clip::Line { normal, offset })
    }

    /// Whether the clip keeps plane point `p` (major radii).
    pub fn keeps(&self, p: DVec2) -> bool {
        match *self {
            Clip::Line { normal, offset } => normal.dot(p) <= offset,
            Clip::Wedge { start, end } => {
                let (start, end) = (DVec2::from_angle(start), DVec2::from_angle(end));
                let margin = WEDGE_MARGIN as f64;
                let beyond_start = DVec2::new(start.y, -start.x).dot(p) > margin;
                let beyond_end = DVec2::new(-end.y, end.x).dot(p) > margin;
                if start.perp_dot(end) >= 0.0 {
                    !(beyond_start || beyond_end)
                } else {
                    !(beyond_start && beyond_end)
                }
            }
        }
    }

    /// The counter-clockwise sweep from `start` to `end`, radians in [0, 2π).
    pub fn sweep(start: DVec2, end: DVec2) -> f64 {
        (turns(end) - turns(start)).rem_euclid(1.0) * TAU
    }

    pub fn pack(clip: Option<Clip>) -> u32 {
        match clip {
            Some(Clip::Line { normal, offset }) if offset < 1.0 && normal.is_finite() => {
                let angle = (turns(normal) * 65536.0).round() as u32 & 0xffff;
                angle | (f16_at_least(offset).to_bits() as u32) << 16
            }
            Some(Clip::Wedge { start, end }) if start.is_finite() && end.is_finite() => {
                let mask = WEDGE_STEPS as u32 - 1;
                let steps = |angle: f64| (angle / TAU).rem_euclid(1.0) * WEDGE_STEPS;
                let start = steps(start).floor() as u32 & mask;
                let end = steps(end).ceil() as u32 & mask;
                WEDGE_TAG | start << WEDGE_ANGLE_BITS | end
            }
            _ => NO_CLIP,
        }
    }

    pub fn unpack(bits: u32) -> Option<Clip> {
        if bits & WEDGE_TAG == WEDGE_TAG {
            let mask = WEDGE_STEPS as u32 - 1;
            let at = |k: u32| (k & mask) as f64 / WEDGE_STEPS * TAU;
            return Some(Clip::Wedge {
                start: at(bits >> WEDGE_ANGLE_BITS),
                end: at(bits),
            });
        }
        let offset = f16::from_bits((bits >> 16) as u16).to_f64();
        if !offset.is_finite() {
            return None;
        }
        Some(Clip::Line {
            normal: DVec2::from_angle((bits & 0xffff) as f64 / 65536.0 * TAU),
            offset,
        })
    }
}

/// The least f16 ≥ x (x finite, |x| < 65504): a stored clip line never cuts what the
/// exact one kept.
fn f16_at_least(x: f64) -> f16 {
    let h = f16::from_f64(x);
    if h.to_f64() >= x {
        h
    } else if !h.is_sign_negative() {
        f16::from_bits(h.to_bits() + 1)
    } else if h.to_bits() == 0x8000 {
        f16::from_bits(1)
    } else {
        // Negative: one step toward zero.
        f16::from_bits(h.to_bits() - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(clip: Clip) -> Clip {
        Clip::unpack(Clip::pack(Some(clip))).expect("a clip")
    }

    #[test]
    fn a_line_keeps_its_side_after_packing() {
        let line = Clip::Line {
            normal: DVec2::from_angle(2.0),
            offset: -0.3,
        };
        let Clip::Line { normal, offset } = round_trip(line) else {
            panic!("a line")
        };
        assert!(normal.angle_to(DVec2::from_angle(2.0)).abs() < 1e-4);
        assert!((-0.3..-0.3 + 1e-3).contains(&offset), "{offset}");
        assert_eq!(Clip::unpack(Clip::pack(None)), None);
    }

    /// A convex fan keeps only its sector, a reflex one all but the sector it leaves
    /// out; packing keeps every point the exact wedge keeps.
    #[test]
    fn wedges_keep_their_fan() {
        for (a, b) in [(0.3, 1.9), (0.3, 4.9), (5.5, 0.4), (2.0, 1.0)] {
            let exact = Clip::Wedge { start: a, end: b };
            let stored = round_trip(exact);
            let sweep = Clip::sweep(DVec2::from_angle(a), DVec2::from_angle(b));
            for k in 0..720 {
                let phi = k as f64 / 720.0 * TAU;
                let p = DVec2::from_angle(phi) * 0.9;
                let inside = Clip::sweep(DVec2::from_angle(a), p) <= sweep;
                assert!(!inside || exact.keeps(p), "{a} {b}: {phi} cut");
                assert!(!exact.keeps(p) || stored.keeps(p), "{a} {b}: {phi} lost");
                let away = (phi - a).sin().abs().min((phi - b).sin().abs());
                if !inside && away > 0.1 {
                    assert!(!stored.keeps(p), "{a} {b}: {phi} kept");
                }
            }
        }
    }
}
