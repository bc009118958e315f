//! The node record: one entry of the sequential list, as stored in `.spt` files and
//! uploaded to the GPU. 32 bytes (docs/design.md §6).
//!
//! Errors are stored as IEEE half floats of `value / error_scale` (the model's size),
//! always rounded *up*: a node never looks finer than it is, `δ` never shrinks (the
//! hole-free argument needs δ ≥ |p − p_parent|), and rounding keeps `e_child ≤ e_parent`.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::surfel::octahedral::{oct_decode, oct_encode};
use half::f16;

/// One node of the sequential list.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct NodeRecord {
    /// Disk centre relative to the model origin (f32 bits).
    pub position: [u32; 3],
    /// Disk radius (f32 bits).
    pub radius: u32,
    /// Unit normal, octahedral, two snorm16 (x in the low half).
    pub normal: u32,
    /// RGBA8.
    pub color: [u8; 4],
    /// Node error e / error_scale, f16 bits, rounded up. 0 for leaves.
    pub error: u16,
    /// The parent's `error` bits (bit-identical copy); +∞ for the root.
    pub parent_error: u16,
    /// |p − p_parent| / error_scale, f16 bits, rounded up; 0 for the root.
    pub delta: u16,
    /// Depth in the tree: 0 for the root.
    pub level: u16,
}

const _: () = assert!(std::mem::size_of::<NodeRecord>() == 32);

impl NodeRecord {
    pub fn new(position: Vec3, radius: f32, normal: Vec3, color: [u8; 4]) -> Self {
        NodeRecord {
            position: position.to_array().map(f32::to_bits),
            radius: radius.to_bits(),
            normal: oct_encode(normal),
            color,
            error: 0,
            parent_error: 0,
            delta: 0,
            level: 0,
        }
    }

    pub fn position(&self) -> Vec3 {
        Vec3::from_array(self.position.map(f32::from_bits))
    }

    pub fn radius(&self) -> f32 {
        f32::from_bits(self.radius)
    }

    pub fn normal(&self) -> Vec3 {
        oct_decode(self.normal)
    }

    /// The node error in model units (exact: a half times an f32 fits in an f64).
    pub fn error(&self, error_scale: f32) -> f64 {
        decode(self.error, error_scale)
    }

    pub fn parent_error(&self, error_scale: f32) -> f64 {
        decode(self.parent_error, error_scale)
    }

    pub fn delta(&self, error_scale: f32) -> f64 {
        decode(self.delta, error_scale)
    }
}

/// A stored half `bits` back in model units: bits × scale, exactly.
pub fn decode(bits: u16, error_scale: f32) -> f64 {
    half_value(bits) as f64 * error_scale as f64
}

/// f16 bits of the smallest half h with h × `error_scale` ≥ `value` (model units, ≥ 0):
/// decoding never gives less than the value encoded.
pub fn encode_up(value: f64, error_scale: f32) -> u16 {
    let mut bits = half_up((value / error_scale as f64) as f32);
    while decode(bits, error_scale) < value && bits < f16::INFINITY.to_bits() {
        bits += 1;
    }
    bits
}

/// f16 bits of the smallest half ≥ `x` (x ≥ 0; +∞ stays +∞, NaN becomes +∞).
pub fn half_up(x: f32) -> u16 {
    if x.is_nan() {
        return f16::INFINITY.to_bits();
    }
    let h = f16::from_f32(x.max(0.0));
    if h.to_f32() >= x {
        h.to_bits()
    } else {
        h.to_bits() + 1
    }
}

pub fn half_value(bits: u16) -> f32 {
    f16::from_bits(bits).to_f32()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_up_never_rounds_down() {
        for x in [
            0.0f32,
            1e-9,
            6e-8,
            1e-5,
            0.1,
            0.3333,
            1.0,
            1000.7,
            65504.0,
            1e6,
            f32::INFINITY,
        ] {
            let h = half_value(half_up(x));
            assert!(h >= x, "{x} -> {h}");
            assert!(h <= x * 1.001 + 6e-8 || x > 65504.0, "{x} -> {h} too far");
        }
        // Monotone: a ≤ b ⇒ half_up(a) ≤ half_up(b).
        let mut prev = 0;
        for i in 0..10_000 {
            let h = half_up(i as f32 * 0.0137);
            assert!(h >= prev);
            prev = h;
        }
    }

    #[test]
    fn encode_up_decodes_to_at_least_the_value() {
        for scale in [1e-7f32, 0.157, 1.0, 6.64, 1133.0, 3e7] {
            for i in 0..5000 {
                let v = (i as f64 * 0.000731).powi(3) * scale as f64;
                let bits = encode_up(v, scale);
                assert!(decode(bits, scale) >= v, "{v} at scale {scale}");
                assert!(decode(bits, scale) <= v * 1.0011 + 6e-8 * scale as f64);
            }
        }
    }
}
