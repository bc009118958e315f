//! Cameras in the model's file coordinates (f64), turned into camera-relative f32
//! matrices per frame: the eye is the origin of view space and the model is offset by
//! (origin − eye) computed in f64, so a model far from the origin renders as well as one
//! at it. Reversed-Z with an infinite far plane.

use glam::{DVec3, Mat4};

use crate::io::up::UpAxis;
use crate::tree::TreeMeta;
use crate::tree::chunks::Chunk;
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

/// The axes an orbit turns about: the azimuth about `up`, from `north` toward east =
/// north × up, the elevation toward `up`. Azimuth 0, elevation 0 puts the eye on the
/// −north side, looking north. Unit and orthogonal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitAxes {
    pub north: DVec3,
    pub up: DVec3,
}

impl OrbitAxes {
    /// z up, azimuth 0 looking toward +y: a z-up model's, and a tree's without an axis
    /// that is no sensor frame (files written before the axis was stored).
    pub const Z_UP: OrbitAxes = OrbitAxes {
        north: DVec3::Y,
        up: DVec3::Z,
    };

    /// The axes about `up`: north the axis a viewer of such models faces at azimuth 0
    /// (z up: +y, the eye on the −y side; y up: −z, the eye on the +z side, as in
    /// OpenGL and MeshLab; x up: +y), so that east (the image's right) is +x for both
    /// usual ups. A negative up keeps its positive's north: the image turns over.
    pub fn about(up: UpAxis) -> OrbitAxes {
        let north = match up {
            UpAxis::Z | UpAxis::NegZ | UpAxis::X | UpAxis::NegX => DVec3::Y,
            UpAxis::Y | UpAxis::NegY => DVec3::NEG_Z,
        };
        OrbitAxes {
            north,
            up: up.vector(),
        }
    }

    /// The axes of a tree: about its up axis ([`TreeMeta::up`], [`OrbitAxes::about`]),
    /// or, for a tree without one, a sensor frame's ([`OrbitAxes::of_sensor`]) or
    /// [`OrbitAxes::Z_UP`].
    pub fn of(meta: &TreeMeta) -> OrbitAxes {
        match meta.up {
            Some(up) => OrbitAxes::about(up),
            None => OrbitAxes::of_sensor(meta),
        }
    }

    /// A sensor frame's ([`TreeMeta::sensor`]): north along its optical axis, the
    /// coordinate axis nearest the direction from the sensor to the model's centre, so
    /// that azimuth 0, elevation 0 looks the way the sensor did. Up, for an optical
    /// axis along ±z, is x × north, the image upright: both camera conventions with z
    /// on the axis put x to the image's right (OpenCV: y down, z forward, so up is −y;
    /// OpenGL: y up, z backward, so up is +y); with x or y on it (a robot's x forward),
    /// z. [`OrbitAxes::Z_UP`] for every other model.
    pub fn of_sensor(meta: &TreeMeta) -> OrbitAxes {
        let Some(sensor) = meta.sensor() else {
            return OrbitAxes::Z_UP;
        };
        let d = bounding_sphere(meta).0 - sensor;
        let axis = d.abs().max_position();
        let mut north = DVec3::ZERO;
        north[axis] = d[axis].signum();
        let up = if axis == 2 {
            DVec3::X.cross(north)
        } else {
            DVec3::Z
        };
        OrbitAxes { north, up }
    }

    pub fn east(&self) -> DVec3 {
        self.north.cross(self.up)
    }

    /// The unit vector from the target toward the eye at an azimuth and an elevation
    /// (degrees): east · sin az cos el − north · cos az cos el + up · sin el.
    pub fn toward_eye(&self, azimuth_deg: f64, elevation_deg: f64) -> DVec3 {
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        self.east() * (az.sin() * el.cos()) - self.north * (az.cos() * el.cos())
            + self.up * el.sin()
    }

    /// The azimuth and elevation (degrees) of the unit vector `toward_eye`.
    pub fn angles(&self, toward_eye: DVec3) -> (f64, f64) {
        let (x, y, z) = (
            toward_eye.dot(self.east()),
            toward_eye.dot(self.north),
            toward_eye.dot(self.up),
        );
        (
            x.atan2(-y).to_degrees(),
            z.clamp(-1.0, 1.0).asin().to_degrees(),
        )
    }
}

impl Camera {
    /// Orbit around the model's centre about its axes ([`OrbitAxes::of`]): azimuth and
    /// elevation in degrees, distance in bounding-sphere radii.
    pub fn orbit(
        meta: &TreeMeta,
        azimuth_deg: f64,
        elevation_deg: f64,
        distance: f64,
        fov_y: f64,
    ) -> Camera {
        let axes = OrbitAxes::of(meta);
        Camera::orbit_about(axes, meta, [azimuth_deg, elevation_deg, distance], fov_y)
    }

    /// [`Camera::orbit`] about the given axes: `[azimuth°, elevation°, distance]`.
    pub fn orbit_about(axes: OrbitAxes, meta: &TreeMeta, orbit: [f64; 3], fov_y: f64) -> Camera {
        let (centre, radius) = bounding_sphere(meta);
        let [azimuth_deg, elevation_deg, distance] = orbit;
        Camera {
            eye: centre + axes.toward_eye(azimuth_deg, elevation_deg) * distance * radius,
            target: centre,
            up: axes.up,
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
    /// see edge-on; a sensor frame from its sensor's side, as the sensor saw it): the
    /// least distance at which all eight corners of the model's box fall inside both
    /// fields of view (a corner c, in view axes relative to the centre, needs
    /// d ≥ c_z + |c_x| / tan(fov_x/2) and d ≥ c_z + |c_y| / tan(fov_y/2)), with a 5 %
    /// margin. With `chunks`, the corners of their boxes of node centres instead: the
    /// model's box holds empty space that a view from a frame's sensor sees at wide
    /// angles (its near face is as wide as its far one), the chunks' boxes hug the
    /// samples.
    pub fn framed(meta: &TreeMeta, chunks: &[Chunk], fov_y: f64, aspect: f64) -> Camera {
        let axes = OrbitAxes::of(meta);
        if meta.up.is_none() && meta.sensor().is_some() {
            return Camera::framed_from(axes, meta, chunks, [0.0, 0.0], fov_y, aspect);
        }
        Camera::framed_about(axes, meta, chunks, fov_y, aspect)
    }

    /// [`Camera::framed`] of a model turned about `axes` (not a sensor's): from
    /// elevation 45° for a terrain standing on z, 20° otherwise, at azimuth 30°.
    pub fn framed_about(
        axes: OrbitAxes,
        meta: &TreeMeta,
        chunks: &[Chunk],
        fov_y: f64,
        aspect: f64,
    ) -> Camera {
        let elevation = if meta.is_flat() && axes.up.z != 0.0 {
            45.0
        } else {
            20.0
        };
        Camera::framed_from(axes, meta, chunks, [30.0, elevation], fov_y, aspect)
    }

    /// [`Camera::framed`] about `axes`, seen from a given `[azimuth, elevation]`
    /// (degrees).
    pub fn framed_from(
        axes: OrbitAxes,
        meta: &TreeMeta,
        chunks: &[Chunk],
        [azimuth_deg, elevation_deg]: [f64; 2],
        fov_y: f64,
        aspect: f64,
    ) -> Camera {
        let probe = Camera::orbit_about(axes, meta, [azimuth_deg, elevation_deg, 1.0], fov_y);
        let (centre, radius) = bounding_sphere(meta);
        let forward = (probe.target - probe.eye).normalize();
        let right = forward.cross(probe.up).normalize_or(DVec3::X);
        let up = right.cross(forward);
        let (tan_y, tan_x) = ((fov_y * 0.5).tan(), (fov_y * 0.5).tan() * aspect);
        let mut distance = 0.0f64;
        let origin = DVec3::from(meta.origin);
        let chunk_corners = chunks.iter().flat_map(|c| {
            let at = |v: [f32; 3]| (origin + glam::Vec3::from(v).as_dvec3()).to_array();
            box_corners(at(c.centre_min), at(c.centre_max))
        });
        // The model's box only where there are no chunks.
        let model_corners = box_corners(meta.bounds.min, meta.bounds.max)
            .take(if chunks.is_empty() { 8 } else { 0 });
        for corner in chunk_corners.chain(model_corners) {
            let corner = corner - centre;
            let toward = -corner.dot(forward);
            distance = distance
                .max(toward + corner.dot(right).abs() / tan_x)
                .max(toward + corner.dot(up).abs() / tan_y);
        }
        let distance = (distance * 1.05).max(radius * 1e-3) / radius;
        Camera::orbit_about(axes, meta, [azimuth_deg, elevation_deg, distance], fov_y)
    }

    /// The near plane for an image of `aspect` (width / height): as far as it can be
    /// with nothing of the model nearer. Depth is near / view distance, and on a backend
    /// that remaps clip depth from [−1, 1] to [0, 1] (wgpu's GL) a tiny near left too few
    /// bits for the depth test of a distant mesh: seen from 42 radii, the knot's
    /// supersampled reference on GL differed from Vulkan's in 103 pixels by up to 46
    /// levels, and in none with this plane.
    ///
    /// Every node's disk lies within a few R of the bounding sphere's centre (R its
    /// radius): its centre is among its leaves' centres, within R, and its radius
    /// reaches its children's disks. Measured, (|c − centre| + r) / R is at most 1.00–1.12
    /// over the nodes of the knot, bunny, dragon, kinect_rgb and terrain_utm. From an
    /// eye at distance D, a point within 3R of the centre is at least D − 3R away, and
    /// inside the frustum at view depth at least (D − 3R) cos θ, θ the half-angle of
    /// the frustum's diagonal (cos θ = 1 / √(1 + tx² + ty²)). The plane is half that,
    /// nearer than every visible disk while the disks lie within (D + 3R) / 2 of the
    /// centre. Nearer than 3R it is a small fraction of the model.
    pub fn near_plane(&self, meta: &TreeMeta, aspect: f64) -> f64 {
        let (centre, radius) = bounding_sphere(meta);
        let distance = (centre - self.eye).length();
        let tan_y = (self.fov_y * 0.5).tan();
        let cos_diagonal = 1.0 / (1.0 + tan_y * tan_y * (1.0 + aspect * aspect)).sqrt();
        (radius * 1e-4)
            .max(distance * 1e-6)
            .max(0.5 * (distance - 3.0 * radius) * cos_diagonal)
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
    /// `aspect` (width / height).
    pub fn view_cone(&self, meta: &TreeMeta, aspect: f64) -> ViewCone {
        let (right, up, forward) = self.axes();
        let tan_y = (self.fov_y * 0.5).tan();
        ViewCone::new(
            self.eye - DVec3::from(meta.origin),
            [right, up, forward],
            [tan_y * aspect, tan_y],
            self.near_plane(meta, aspect),
        )
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

/// The node centres' lowest and highest heights along `up` (the camera's), relative to
/// the model's origin: what the elevation ramp spans.
pub fn heights(meta: &TreeMeta, up: DVec3) -> [f32; 2] {
    let (lo, hi) = (
        meta.centre_min.map(f64::from),
        meta.centre_max.map(f64::from),
    );
    let (low, high) = box_corners(lo, hi)
        .map(|c| c.dot(up))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(h), b.max(h))
        });
    [low as f32, high as f32]
}

/// The eight corners of the box `lo`–`hi`.
fn box_corners(lo: [f64; 3], hi: [f64; 3]) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |k| {
        DVec3::new(
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cloud of estimated normals in the box `min`–`max` (file coordinates), turned
    /// as its box tells (its core, here).
    fn cloud(min: [f64; 3], max: [f64; 3]) -> TreeMeta {
        let mut meta = TreeMeta::empty(1.0);
        (meta.bounds.min, meta.bounds.max) = (min, max);
        meta.origin = meta.bounds.center().to_array();
        meta.normals_turned = meta.normals_turned_by_leaf_box();
        meta
    }

    /// `meta` with given, oriented normals.
    fn oriented(mut meta: TreeMeta) -> TreeMeta {
        meta.oriented_normals = true;
        meta.normals_turned = crate::surfel::NormalsTurned::No;
        meta
    }

    #[test]
    fn a_far_eye_gets_a_far_near_plane_that_no_visible_point_crosses() {
        let meta = cloud([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]);
        let (centre, radius) = bounding_sphere(&meta);
        let fov = 45f64.to_radians();
        for (distance, aspect) in [(42.0, 1.0), (6.0, 16.0 / 9.0), (3.5, 0.5)] {
            let camera = Camera::orbit(&meta, 30.0, 20.0, distance, fov);
            let near = camera.near_plane(&meta, aspect);
            let cone = camera.view_cone(&meta, aspect);
            // Points within 3R of the centre: none inside the frustum is nearer.
            for i in 0..20_000u32 {
                let u = |k: u32| ((i * 3 + k) as f64 * 0.618_034).fract() * 2.0 - 1.0;
                let p = centre + DVec3::new(u(0), u(1), u(2)) * 3.0 * radius / 3f64.sqrt();
                let v = p - camera.eye;
                let depth = v.dot(cone.forward);
                let inside = v.dot(cone.right).abs() <= cone.tan_half_fov[0] * depth
                    && v.dot(cone.up).abs() <= cone.tan_half_fov[1] * depth;
                assert!(
                    !inside || depth >= near,
                    "{distance} radii: {depth} < {near}"
                );
            }
            // The nearest point of that ball, straight ahead.
            let nearest = (centre - camera.eye).length() - 3.0 * radius;
            assert!(nearest <= 0.0 || nearest >= near);
            if distance == 42.0 {
                // The depth buffer keeps its bits: near / depth ≈ 0.4, not 10⁻⁶.
                assert!(near > 10.0 * radius, "near {near} at {distance} radii");
            }
        }
        // From inside the model the plane is a small fraction of it.
        let inside = Camera::orbit(&meta, 30.0, 20.0, 0.5, fov);
        assert!(inside.near_plane(&meta, 1.0) <= 1e-3 * radius);
    }

    #[test]
    fn a_sensor_frame_is_seen_upright_from_its_sensor() {
        // An OpenCV-convention frame: the sensor at the origin looking along +z, y down.
        let frame = cloud([-1.0, -1.5, 0.8], [1.8, 0.4, 3.8]);
        let axes = OrbitAxes::of(&frame);
        assert_eq!(
            (axes.north, axes.up, axes.east()),
            (DVec3::Z, -DVec3::Y, DVec3::X)
        );
        // Framed looking along the optical axis, from the sensor's side.
        let camera = Camera::framed(&frame, &[], 45f64.to_radians(), 4.0 / 3.0);
        let view = (camera.target - camera.eye).normalize();
        assert!(view.dot(DVec3::Z) > 1.0 - 1e-12, "{camera:?}");
        assert!(camera.eye.z < 0.8 && camera.up == -DVec3::Y, "{camera:?}");
        // The angles round-trip.
        let d = axes.toward_eye(30.0, 20.0);
        let (az, el) = axes.angles(d);
        assert!(
            (az - 30.0).abs() < 1e-9 && (el - 20.0).abs() < 1e-9,
            "{az} {el}"
        );
        // An OpenGL-convention frame (looking along −z, y up) keeps +y up.
        let gl = cloud([-1.0, -0.4, -3.8], [1.8, 1.5, -0.8]);
        assert_eq!(OrbitAxes::of(&gl).up, DVec3::Y);
        // A robot's frame (x forward, z up) keeps z up.
        let robot = cloud([0.8, -1.0, -1.5], [3.8, 1.8, 0.4]);
        assert_eq!(OrbitAxes::of(&robot).north, DVec3::X);
        assert_eq!(OrbitAxes::of(&robot).up, DVec3::Z);
    }

    #[test]
    fn chunk_boxes_frame_the_samples_not_the_model_s_box() {
        // A box 2 wide whose samples all lie in one chunk 0.2 wide at its centre.
        let meta = oriented(cloud([-1.0; 3], [1.0; 3]));
        let chunk = Chunk {
            start: 0,
            count: 1,
            level: 0,
            centre_min: [-0.1; 3],
            centre_max: [0.1; 3],
            radius_max: 0.0,
            error_min: 0.0,
        };
        let distance = |chunks: &[Chunk]| {
            let c = Camera::framed(&meta, chunks, 1.0, 1.0);
            (c.eye - c.target).length()
        };
        let (whole, hugged) = (distance(&[]), distance(&[chunk]));
        assert!(hugged < 0.15 * whole, "{hugged} against {whole}");
        // Every corner of the chunk's box in view (fov 1 rad both ways).
        let c = Camera::framed(&meta, &[chunk], 1.0, 1.0);
        let (right, up, forward) = c.axes();
        for corner in box_corners([-0.1; 3], [0.1; 3]) {
            let d = corner - c.eye;
            let depth = d.dot(forward);
            assert!(d.dot(right).abs() < depth * 0.5f64.tan(), "{corner}");
            assert!(d.dot(up).abs() < depth * 0.5f64.tan(), "{corner}");
        }
    }

    #[test]
    fn heights_run_along_the_given_up() {
        let mut frame = cloud([-1.0, -1.5, 0.8], [1.8, 0.4, 3.8]);
        (frame.centre_min, frame.centre_max) = ([-1.0, -2.0, -1.5], [2.0, 3.0, 1.5]);
        assert_eq!(heights(&frame, -DVec3::Y), [-3.0, 2.0]);
        assert_eq!(heights(&frame, DVec3::Z), [-1.5, 1.5]);
    }

    #[test]
    fn models_orbit_about_their_up_axis_with_x_to_the_right() {
        // The shape's rule: a cloud around its origin and a mesh stand on y, a terrain
        // on z; a tree without an axis (an older file) orbits about z.
        let around = cloud([-1.0; 3], [1.0; 3]);
        assert_eq!(OrbitAxes::of(&around), OrbitAxes::Z_UP);
        assert_eq!(around.clone().with_file_up(None).up, Some(UpAxis::Y));
        let tile = cloud([500.0, 700.0, 10.0], [900.0, 1100.0, 40.0]).with_file_up(None);
        assert_eq!(OrbitAxes::of(&tile), OrbitAxes::Z_UP);
        let mesh = oriented(cloud([-1.0, -1.5, 0.8], [1.8, 0.4, 3.8])).with_file_up(None);
        assert_eq!(mesh.up, Some(UpAxis::Y));
        // The file's word wins.
        assert_eq!(
            mesh.clone().with_file_up(Some(UpAxis::Z)).up,
            Some(UpAxis::Z)
        );
        // y up: seen from +z, x to the right.
        let c = Camera::orbit(&mesh, 0.0, 0.0, 2.0, 1.0);
        assert!(c.eye.z > c.target.z && c.up == DVec3::Y, "{c:?}");
        for up in UpAxis::ALL {
            let axes = OrbitAxes::about(up);
            assert_eq!(axes.north.dot(axes.up), 0.0, "{up:?}");
            if matches!(up, UpAxis::Y | UpAxis::Z) {
                assert_eq!(axes.east(), DVec3::X, "{up:?}");
            }
        }
    }
}
