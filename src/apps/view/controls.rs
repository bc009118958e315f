//! The viewer's camera, free of any window system: an orbit camera (a target, a
//! distance, azimuth and elevation about the model's axes, [`OrbitAxes`]: its up axis, or a
//! sensor frame's own) that mouse drags, the wheel and held
//! keys move. Speeds scale with the distance to the target, so they suit a model of any
//! size and stay usable close up.

use glam::DVec3;

use crate::render::{Camera, OrbitAxes};

/// Degrees of orbit per pixel dragged.
const ORBIT_DEG_PER_PX: f64 = 0.3;
/// Distance factor per wheel notch (zoom in: × this; out: ÷ this).
const ZOOM_PER_NOTCH: f64 = 0.85;
/// Degrees per second of orbit with the arrow keys.
const KEY_ORBIT_DEG_PER_S: f64 = 90.0;
/// Elevation stays this far from the poles, where the azimuth is undefined.
const MAX_ELEVATION_DEG: f64 = 89.5;

/// Eye = target + distance · [`OrbitAxes::toward_eye`], as [`Camera::orbit`] places it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    pub target: DVec3,
    pub distance: f64,
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    pub fov_y: f64,
    /// The least distance to the target (a small fraction of the model's size).
    pub min_distance: f64,
    pub axes: OrbitAxes,
}

impl OrbitCamera {
    /// The orbit camera about `axes` that looks as `camera` does.
    pub fn from_camera(camera: &Camera, axes: OrbitAxes, model_radius: f64) -> OrbitCamera {
        let offset = camera.eye - camera.target;
        let distance = offset.length();
        let (azimuth_deg, elevation_deg) = axes.angles(offset / distance);
        OrbitCamera {
            target: camera.target,
            distance,
            azimuth_deg,
            elevation_deg,
            fov_y: camera.fov_y,
            min_distance: (model_radius * 1e-5).min(distance),
            axes,
        }
    }

    /// Unit vector from the target toward the eye.
    fn toward_eye(&self) -> DVec3 {
        self.axes.toward_eye(self.azimuth_deg, self.elevation_deg)
    }

    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.target + self.toward_eye() * self.distance,
            target: self.target,
            up: self.axes.up,
            fov_y: self.fov_y,
        }
    }

    /// Forward, right and up axes of the view (not the orbit's `axes`).
    fn view_axes(&self) -> (DVec3, DVec3, DVec3) {
        let forward = -self.toward_eye();
        let right = forward.cross(self.axes.up).normalize_or(self.axes.east());
        (forward, right, right.cross(forward))
    }

    /// Model units per pixel at the target's distance, for a viewport `height` pixels tall.
    fn units_per_px(&self, height: f64) -> f64 {
        2.0 * self.distance * (self.fov_y * 0.5).tan() / height.max(1.0)
    }

    /// Turns around the target: dragging right turns the model right, dragging down
    /// tilts it toward the viewer.
    pub fn orbit(&mut self, dx_px: f64, dy_px: f64) {
        self.azimuth_deg = (self.azimuth_deg - dx_px * ORBIT_DEG_PER_PX).rem_euclid(360.0);
        self.elevation_deg = (self.elevation_deg + dy_px * ORBIT_DEG_PER_PX)
            .clamp(-MAX_ELEVATION_DEG, MAX_ELEVATION_DEG);
    }

    /// Moves eye and target in the view plane so that the point under the pointer
    /// follows it.
    pub fn pan(&mut self, dx_px: f64, dy_px: f64, viewport: (u32, u32)) {
        let (_, right, up) = self.view_axes();
        let k = self.units_per_px(viewport.1 as f64);
        self.target += (-dx_px * right + dy_px * up) * k;
    }

    /// Zooms by `notches` of the wheel (positive: in) toward the point under the pointer
    /// at `at` (pixels from the top left) on the target's plane: that point stays under
    /// the pointer, and the distance scales by 0.85 per notch.
    pub fn zoom_at(&mut self, notches: f64, at: (f64, f64), viewport: (u32, u32)) {
        let factor = ZOOM_PER_NOTCH.powf(notches);
        let new_distance = (self.distance * factor).max(self.min_distance);
        let factor = new_distance / self.distance;
        let (w, h) = (viewport.0.max(1) as f64, viewport.1.max(1) as f64);
        let (_, right, up) = self.view_axes();
        let k = self.units_per_px(h);
        let under = self.target + (at.0 - w * 0.5) * k * right - (at.1 - h * 0.5) * k * up;
        // Scale the eye and target about the point under the pointer.
        self.target = under + (self.target - under) * factor;
        self.distance = new_distance;
    }

    /// Moves eye and target together by `forward`, `right` and `up` times the distance
    /// to the target (WASD, Q/E).
    pub fn walk(&mut self, forward: f64, right: f64, up: f64) {
        let (f, r, u) = self.view_axes();
        self.target += (f * forward + r * right + u * up) * self.distance;
    }

    /// Orbits for `seconds` at the arrow keys' rate; `dx`, `dy` in −1..1.
    pub fn turn(&mut self, dx: f64, dy: f64, seconds: f64) {
        let px = KEY_ORBIT_DEG_PER_S * seconds / ORBIT_DEG_PER_PX;
        self.orbit(dx * px, dy * px);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> OrbitCamera {
        OrbitCamera::from_camera(
            &Camera {
                eye: DVec3::new(3.0, -4.0, 2.0),
                target: DVec3::new(0.5, 0.25, -0.5),
                up: DVec3::Z,
                fov_y: 0.8,
            },
            OrbitAxes::Z_UP,
            1.0,
        )
    }

    #[test]
    fn from_camera_round_trips() {
        let c = sample().camera();
        assert!((c.eye - DVec3::new(3.0, -4.0, 2.0)).length() < 1e-12);
        assert!((c.target - DVec3::new(0.5, 0.25, -0.5)).length() < 1e-12);
    }

    #[test]
    fn zoom_keeps_the_point_under_the_pointer() {
        let viewport = (800, 600);
        let at = (600.0, 150.0);
        let before = sample();
        let mut after = before;
        after.zoom_at(3.0, at, viewport);
        assert!((after.distance - before.distance * 0.85f64.powi(3)).abs() < 1e-12);
        // The point under the pointer on the old target plane projects to the same pixel.
        let (_, right, up) = before.view_axes();
        let k = before.units_per_px(600.0);
        let p = before.target + (at.0 - 400.0) * k * right - (at.1 - 300.0) * k * up;
        let project = |o: &OrbitCamera| {
            let cam = o.camera();
            let (f, r, u) = o.view_axes();
            let v = p - cam.eye;
            let t = (o.fov_y * 0.5).tan() * v.dot(f);
            (400.0 + v.dot(r) / t * 300.0, 300.0 - v.dot(u) / t * 300.0)
        };
        let (x, y) = project(&after);
        assert!(
            (x - at.0).abs() < 1e-6 && (y - at.1).abs() < 1e-6,
            "{x} {y}"
        );
    }

    #[test]
    fn zoom_stops_at_the_least_distance() {
        let mut o = sample();
        o.zoom_at(1e4, (400.0, 300.0), (800, 600));
        assert_eq!(o.distance, o.min_distance);
        assert!(o.camera().eye.is_finite());
    }

    #[test]
    fn orbit_never_flips_over_the_pole() {
        let mut o = sample();
        o.orbit(0.0, 1e6);
        assert_eq!(o.elevation_deg, MAX_ELEVATION_DEG);
        let c = o.camera();
        assert!(c.view_rotation().is_finite());
    }
}
