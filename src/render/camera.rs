//! Cameras in the model's file coordinates (f64), turned into camera-relative f32
//! matrices per frame: the eye is the origin of view space and the model is offset by
//! (origin − eye) computed in f64, so a model far from the origin renders as well as one
//! at it. Reversed-Z with an infinite far plane.

use glam::{DVec3, Mat4};

use crate::tree::TreeMeta;
use crate::tree::select::ViewCone;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye and target in the file's coordinates.
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view, radians.
    pub fov_y: f64,
}

/// Centre and radius of the sphere around the model's leaf-centre box (file coordinates).
pub fn bounding_sphere(meta: &TreeMeta) -> (DVec3, f64) {
    let lo = DVec3::from(meta.bounds.min);
    let hi = DVec3::from(meta.bounds.max);
    let radius = ((hi - lo).length() * 0.5).max(meta.error_scale as f64 * 0.5);
    ((lo + hi) * 0.5, radius)
}

impl Camera {
    /// Orbit around the model's centre: azimuth and elevation in degrees (azimuth 0,
    /// elevation 0 puts the eye on the −y side looking toward +y; z is up), distance in
    /// bounding-sphere radii.
    pub fn orbit(
        meta: &TreeMeta,
        azimuth_deg: f64,
        elevation_deg: f64,
        distance: f64,
        fov_y: f64,
    ) -> Camera {
        let (centre, radius) = bounding_sphere(meta);
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        let dir = DVec3::new(az.sin() * el.cos(), -az.cos() * el.cos(), el.sin());
        Camera {
            eye: centre + dir * distance * radius,
            target: centre,
            up: DVec3::Z,
            fov_y,
        }
    }

    /// The distance (in bounding-sphere radii) at which the sphere just fills the
    /// smaller of the two fields of view.
    pub fn framing_distance(fov_y: f64, aspect: f64) -> f64 {
        let half = (fov_y * 0.5).min(((fov_y * 0.5).tan() * aspect).atan());
        1.0 / half.sin()
    }

    /// The whole model framed, seen from a three-quarter view (from 45° above for a
    /// terrain, a box less than a quarter as high as it is wide, which a low view would
    /// see edge-on): the least distance at which all eight corners of the model's box
    /// fall inside both fields of view (a corner c, in view axes relative to the centre,
    /// needs d ≥ c_z + |c_x| / tan(fov_x/2) and d ≥ c_z + |c_y| / tan(fov_y/2)), with a
    /// 5 % margin.
    pub fn framed(meta: &TreeMeta, fov_y: f64, aspect: f64) -> Camera {
        let e = DVec3::from(meta.bounds.max) - DVec3::from(meta.bounds.min);
        let flat = e.z < 0.25 * e.x.max(e.y);
        Camera::framed_from(meta, 30.0, if flat { 45.0 } else { 20.0 }, fov_y, aspect)
    }

    /// [`Camera::framed`] seen from a given azimuth and elevation (degrees).
    pub fn framed_from(
        meta: &TreeMeta,
        azimuth_deg: f64,
        elevation_deg: f64,
        fov_y: f64,
        aspect: f64,
    ) -> Camera {
        let probe = Camera::orbit(meta, azimuth_deg, elevation_deg, 1.0, fov_y);
        let (centre, radius) = bounding_sphere(meta);
        let forward = (probe.target - probe.eye).normalize();
        let right = forward.cross(DVec3::Z).normalize_or(DVec3::X);
        let up = right.cross(forward);
        let (tan_y, tan_x) = ((fov_y * 0.5).tan(), (fov_y * 0.5).tan() * aspect);
        let (lo, hi) = (DVec3::from(meta.bounds.min), DVec3::from(meta.bounds.max));
        let mut distance = 0.0f64;
        for k in 0..8 {
            let corner = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ) - centre;
            let toward = -corner.dot(forward);
            distance = distance
                .max(toward + corner.dot(right).abs() / tan_x)
                .max(toward + corner.dot(up).abs() / tan_y);
        }
        let distance = (distance * 1.05).max(radius * 1e-3) / radius;
        Camera::orbit(meta, azimuth_deg, elevation_deg, distance, fov_y)
    }

    /// The near plane: a small fraction of the model, never beyond its nearest point.
    pub fn near_plane(&self, meta: &TreeMeta) -> f64 {
        let (centre, radius) = bounding_sphere(meta);
        (radius * 1e-4)
            .max((centre - self.eye).length() * 1e-6)
            .max(f64::MIN_POSITIVE)
    }

    /// Unit right, up and forward axes of the view (those of [`Camera::view_rotation`]).
    fn axes(&self) -> (DVec3, DVec3, DVec3) {
        let forward = (self.target - self.eye).normalize_or(DVec3::NEG_Y);
        let up = if forward.cross(self.up).length_squared() < 1e-12 {
            DVec3::Y
        } else {
            self.up
        };
        let right = forward.cross(up).normalize();
        (right, right.cross(forward), forward)
    }

    /// What the GPU's frustum test sees, relative to the model's origin, for an image of
    /// `aspect` (width / height) with splats scaled by `radius_scale`.
    pub fn view_cone(&self, meta: &TreeMeta, aspect: f64, radius_scale: f64) -> ViewCone {
        let (right, up, forward) = self.axes();
        let tan_y = (self.fov_y * 0.5).tan();
        ViewCone {
            eye: self.eye - DVec3::from(meta.origin),
            right,
            up,
            forward,
            tan_half_fov: [tan_y * aspect, tan_y],
            near: self.near_plane(meta),
            radius_scale,
        }
    }

    /// World-aligned camera-relative → view space (rotation only), f32.
    pub fn view_rotation(&self) -> Mat4 {
        let (_, up, forward) = self.axes();
        glam::camera::rh::view::look_to_mat4(glam::Vec3::ZERO, forward.as_vec3(), up.as_vec3())
    }

    /// Reversed-Z infinite projection.
    pub fn projection(&self, aspect: f64, near: f64) -> Mat4 {
        glam::camera::rh::proj::directx::perspective_infinite_reverse(
            self.fov_y as f32,
            aspect as f32,
            near as f32,
        )
    }
}
