//! What `spt bench` measures (docs/design.md §9): camera paths and the ε sweep.
//!
//! Orbits at the distances where the model's bounding sphere fills about 100 %, 25 % and
//! 6 % of the image height: a sphere of radius R at distance d fills R / (d tan(fov/2))
//! of the height, so d = R / (f tan(fov/2)). A fly-through crosses from the far distance
//! to inside the bounding box, looking along its way.

use crate::render::camera::bounding_sphere;
use crate::render::{Camera, OrbitAxes};
use crate::tree::TreeMeta;

/// Fractions of the image height the model fills on the three orbits.
pub const ORBITS: [(&str, f64); 3] = [("near", 1.0), ("mid", 0.25), ("far", 0.06)];

/// Elevation of the orbits, degrees.
const ELEVATION_DEG: f64 = 20.0;

/// The axes the benchmark's cameras turn about: the model's up axis
/// ([`TreeMeta::up`]); z for a sensor frame (whose own view is one side of it only).
pub fn axes(meta: &TreeMeta) -> OrbitAxes {
    meta.up.map_or(OrbitAxes::Z_UP, OrbitAxes::about)
}

/// `views` cameras evenly spaced around the model at the distance where it fills
/// `fill` of the image height, about its [`axes`].
pub fn orbit(meta: &TreeMeta, fill: f64, views: usize, fov_y: f64) -> Vec<Camera> {
    let distance = 1.0 / (fill * (fov_y * 0.5).tan());
    (0..views)
        .map(|k| {
            let azimuth = 360.0 * k as f64 / views as f64;
            let orbit = [azimuth, ELEVATION_DEG, distance];
            Camera::orbit_about(axes(meta), meta, orbit, fov_y)
        })
        .collect()
}

/// `steps` cameras from the far orbit's distance to 0.3 radii from the centre (inside
/// the bounding box for any model whose box is not flat), geometrically spaced, each
/// looking along the way in (toward the centre and beyond).
pub fn fly_through(meta: &TreeMeta, steps: usize, fov_y: f64) -> Vec<Camera> {
    let (centre, radius) = bounding_sphere(meta);
    let far = 1.0 / (ORBITS[2].1 * (fov_y * 0.5).tan());
    let near = 0.3f64;
    let axes = axes(meta);
    let dir = axes.toward_eye(30.0, ELEVATION_DEG);
    (0..steps)
        .map(|k| {
            let t = k as f64 / (steps.max(2) - 1) as f64;
            let d = far * (near / far).powf(t);
            let eye = centre + dir * d * radius;
            Camera {
                eye,
                target: eye - dir * radius,
                up: axes.up,
                fov_y,
            }
        })
        .collect()
}
