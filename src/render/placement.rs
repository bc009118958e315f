//! Where a model is drawn: [`Placement`] (`struct Placement` in `shaders/common.wgsl`),
//! one per instance of a frame, or the one of a model drawn alone. The passes read a
//! node at placement p as the point offset + scale · R x (world axes, relative to the
//! eye), its radius and errors times scale: the selection test of docs/design.md §5
//! then runs in world units, and gives what it gives in the model's own units, since
//! a similarity scales every distance and every error alike
//! ([`crate::tree::instances::Similarity`]).

use bytemuck::{Pod, Zeroable};
use glam::{DQuat, DVec3};

use crate::tree::instances::Similarity;

/// Mirrors `struct Placement` in common.wgsl (32 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub(crate) struct Placement {
    /// Where the model's origin lies, world axes, relative to the eye: computed in f64,
    /// rounded to f32 last.
    pub offset: [f32; 3],
    pub scale: f32,
    /// The unit quaternion of the rotation, (x, y, z, w) as four snorm16, two a word.
    pub rotation: [u32; 2],
    /// The model's error scale times `scale`.
    pub error_scale: f32,
    /// A far instance placed by the GPU: its model's table slot (`render/far.rs`);
    /// else 0.
    pub slot: u32,
}

/// `v` in −1..1 as snorm16 (WGSL's `unpack2x16snorm` inverts it).
pub(super) fn snorm16(v: f64) -> u32 {
    ((v.clamp(-1.0, 1.0) * 32767.0).round() as i32 as u32) & 0xffff
}

impl Placement {
    /// The placement of a model whose origin is `origin` (its stored positions are
    /// relative to it) under `to_world`, seen from `eye`, its stored errors relative to
    /// `error_scale`.
    pub fn new(to_world: &Similarity, origin: DVec3, eye: DVec3, error_scale: f32) -> Placement {
        let q: DQuat = to_world.rotation;
        let offset = to_world.apply(origin) - eye;
        Placement {
            offset: offset.as_vec3().to_array(),
            scale: to_world.scale as f32,
            rotation: [
                snorm16(q.x) | (snorm16(q.y) << 16),
                snorm16(q.z) | (snorm16(q.w) << 16),
            ],
            error_scale: (error_scale as f64 * to_world.scale) as f32,
            slot: 0,
        }
    }

    /// A model drawn alone, as it is stored: offset = origin − eye.
    pub fn alone(origin: DVec3, eye: DVec3, error_scale: f32) -> Placement {
        Placement::new(&Similarity::IDENTITY, origin, eye, error_scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_placement_has_the_size_of_the_wgsl_struct() {
        super::super::shaders::assert_wgsl_size::<Placement>("common", "Placement");
    }

    #[test]
    fn a_model_alone_has_the_identity_rotation_and_its_offset() {
        let p = Placement::alone(
            DVec3::new(1e6, 2.0, 3.0),
            DVec3::new(1e6 - 1.0, 0.0, 0.0),
            0.5,
        );
        assert_eq!(p.offset, [1.0, 2.0, 3.0]);
        assert_eq!((p.scale, p.error_scale), (1.0, 0.5));
        // x = y = z = 0, w = 32767 (1.0).
        assert_eq!(p.rotation, [0, 32767 << 16]);
    }

    #[test]
    fn negative_quaternion_parts_pack_as_twos_complement() {
        assert_eq!(snorm16(-1.0), 0x8001);
        assert_eq!(snorm16(0.5), 16384);
    }
}
