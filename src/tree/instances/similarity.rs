//! An instance's transform: a similarity, x ↦ t + s R x (R a rotation, s > 0).
//!
//! **The selection test holds per instance.** A node of a model drawn at a similarity
//! has, in world units, the error s e, the parent error s e_p, the slack s δ and, seen
//! from a world eye E, the distance s d, where d is the distance in model units from
//! the model eye E′ = R⁻¹ (E − t) / s. The test of docs/design.md §5 in world units,
//! s e ≤ ε s d and ε (s d − s δ) < s e_p, is the test in model units at the same ε, with
//! the eye E′: dividing by s > 0 changes no inequality. So each instance selects from
//! its model's list with [`Similarity::eye_to_model`] and the frame's ε, and draws
//! exactly the nodes that one model made of the transformed copy would select (its
//! errors being s times the copy's own, up to the build's rounding): far instances
//! shrink to a few splats, near ones draw their leaves. A view cone maps the same way
//! ([`Similarity::cone_to_model`]), its angles unchanged.

use glam::{DQuat, DVec3};

use crate::tree::select::ViewCone;

/// x ↦ translation + scale · rotation(x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    pub translation: DVec3,
    /// A unit quaternion.
    pub rotation: DQuat,
    /// Positive.
    pub scale: f64,
}

impl Similarity {
    pub const IDENTITY: Similarity = Similarity {
        translation: DVec3::ZERO,
        rotation: DQuat::IDENTITY,
        scale: 1.0,
    };

    /// The world point of model point `x`.
    pub fn apply(&self, x: DVec3) -> DVec3 {
        self.translation + self.scale * (self.rotation * x)
    }

    /// The model point of world point `p` (the inverse map).
    pub fn eye_to_model(&self, p: DVec3) -> DVec3 {
        self.rotation.inverse() * (p - self.translation) / self.scale
    }

    /// The world direction of model direction `v` (rotated, not scaled).
    pub fn direction(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }

    /// `cone` (world) as the model sees it: apex mapped, axes rotated back, the near
    /// plane divided by the scale; a sphere of the model is seen by it iff its image is
    /// seen by `cone`.
    pub fn cone_to_model(&self, cone: &ViewCone) -> ViewCone {
        let back = self.rotation.inverse();
        ViewCone::new(
            self.eye_to_model(cone.eye),
            [back * cone.right, back * cone.up, back * cone.forward],
            cone.tan_half_fov,
            cone.near / self.scale,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::NodeRecord;
    use crate::tree::select::is_drawn;
    use glam::Vec3;

    fn similarity() -> Similarity {
        Similarity {
            translation: DVec3::new(1e6, -3.0, 20.0),
            rotation: DQuat::from_euler(glam::EulerRot::ZXY, 0.7, -0.3, 1.9),
            scale: 2.5,
        }
    }

    #[test]
    fn the_inverse_maps_back() {
        let s = similarity();
        let x = DVec3::new(0.3, -1.2, 4.0);
        assert!((s.eye_to_model(s.apply(x)) - x).length() < 1e-9);
    }

    /// The argument of the module doc, numerically: a node's world test (errors and
    /// distance times s) decides as its model test from the mapped eye, across ε and
    /// eyes near the decision's edge.
    #[test]
    fn the_selection_test_is_the_same_in_world_and_model_units() {
        let s = similarity();
        let mut node = NodeRecord::new(Vec3::new(0.1, 0.2, -0.3), 0.05, Vec3::Z, [200; 4]);
        node.error = half::f16::from_f32(0.02).to_bits();
        node.parent_error = half::f16::from_f32(0.08).to_bits();
        node.delta = half::f16::from_f32(0.01).to_bits();
        let world_drawn = |eye: DVec3, eps: f64| {
            let p = s.apply(node.position().as_dvec3());
            let d = (p - eye).length();
            let (e, ep, delta) = (
                s.scale * node.error(1.0),
                s.scale * node.parent_error(1.0),
                s.scale * node.delta(1.0),
            );
            e <= eps * d && eps * (d - delta) < ep
        };
        let mut agree = 0;
        for k in 0..400 {
            let eps = 0.001 * (1 + k % 20) as f64;
            let dir = DVec3::new((k as f64).sin(), (k as f64 * 0.3).cos(), 0.5).normalize();
            let eye = s.apply(node.position().as_dvec3()) + dir * (0.5 + k as f64 * 0.7);
            let model = is_drawn(&node, 1.0, s.eye_to_model(eye), eps);
            assert_eq!(world_drawn(eye, eps), model, "eye {eye}, ε {eps}");
            agree += model as usize;
        }
        assert!(
            agree > 10 && agree < 390,
            "the sweep crosses the edge: {agree}"
        );
    }
}
