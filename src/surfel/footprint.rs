//! A sensor frame's splats kept within what its pixels saw. Each sample of an RGB-D
//! frame stands for the cone of one pixel; a splat that, seen from the sensor, covers
//! many pixels claims surface where those pixels' rays saw something else (a farther
//! wall behind a depth edge) or nothing at all. Without this bound the frame's
//! coverings (sized to close every gap of the sampling in the splat's own plane) grew
//! into discs tens of pixels wide along its depth edges and its far, sparse rows, and
//! a quarter to nearly half of the image error of `kinect_rgb` came from pixels they
//! drew where the frame's own triangulation shows the background.
//!
//! * [`angular_pitch`]: the sensor's pixel pitch, as the median angle between a sample
//!   and its nearest neighbour seen from the sensor (neighbouring pixels of one
//!   surface lie one pitch apart), if the samples lie on a grid of rays at all: a
//!   cloud that is no frame (a scanned mesh's vertices, whose file happens to leave
//!   its origin outside the box) has no pitch and keeps its splats;
//! * [`cap`]: each semi-axis of a splat's ellipse, projected across the ray from the
//!   sensor, at most [`MAX_PITCHES`] pitches at the sample's distance. Along the ray a
//!   splat is foreshortened, so a surface the sensor sees at a slant keeps its width
//!   along the slant.

use glam::Vec3;

use super::covering::Covering;
use super::shape::MIN_RATIO;

/// How many pixel pitches, seen from the sensor, a splat's semi-axis may span.
/// `cloud_quality ../shared/data/kinect_rgb.ply --grid 640x480` (4 views, medians;
/// FLIP, worst view's holes): no cap 0.2966, 0.067 %; 3 pitches 0.2593, 0.375 %; 2.5
/// pitches 0.2519, 0.645 %; 2 pitches 0.2455, 1.34 %; 1.5 pitches 0.2327, 2.87 %. Three
/// is the tightest that keeps every view's holes under 0.5 %.
pub const MAX_PITCHES: f32 = 3.0;

/// Largest ratio of the 90th to the 10th percentile of the angles between neighbours,
/// seen from the sensor, of samples on a grid of rays: kinect_rgb's is 1.23 (each
/// sample's nearest neighbour lies one pixel away, or a diagonal's √2 where rows
/// drop out); the Stanford bunny's vertices seen from their file's origin, 3.2.
pub const MAX_PITCH_SPREAD: f32 = 1.5;

/// The median angle (radians) between each position of `pairs` (a sample and its
/// nearest distinct neighbour) as seen from `sensor`: the pixel pitch of a sensor
/// whose samples lie on a grid of rays. `None` when they do not (the angles' 90th
/// percentile over [`MAX_PITCH_SPREAD`] times their 10th), or there are none.
pub fn angular_pitch(sensor: Vec3, pairs: impl Iterator<Item = (Vec3, Vec3)>) -> Option<f32> {
    let direction = |p: Vec3| (p - sensor).normalize_or_zero();
    let mut angles: Vec<f32> = pairs
        .map(|(p, q)| 2.0 * (0.5 * direction(p).distance(direction(q))).min(1.0).asin())
        .collect();
    angles.sort_unstable_by(f32::total_cmp);
    let last = angles.len().checked_sub(1)?;
    let at = |q: f32| angles.get((q * last as f32).round() as usize).copied();
    let (low, median, high) = (at(0.1)?, at(0.5)?, at(0.9)?);
    (high <= MAX_PITCH_SPREAD * low).then_some(median)
}

/// Shrinks the ellipse `c` of normal `n` at `p` so that, seen from `sensor`, each
/// semi-axis spans at most [`MAX_PITCHES`] × `pitch`: a semi-axis s along the unit u
/// spans s·|u × d| / |p − sensor| radians across the ray d (to first order). Where the
/// minor axis alone shrinks past [`MIN_RATIO`] of the major, the ratio stays at that
/// bound (the shapes' thinnest). Returns whether it shrank.
pub fn cap(c: &mut Covering, n: Vec3, p: Vec3, sensor: Vec3, pitch: f32) -> bool {
    let d = (p - sensor).normalize_or_zero();
    let limit = MAX_PITCHES * pitch * (p - sensor).length();
    if limit.is_nan() || limit <= 0.0 || c.radius <= 0.0 {
        return false;
    }
    let (u, v) = (c.axis, n.cross(c.axis).normalize_or_zero());
    let capped = |s: f32, axis: Vec3| {
        let across = s * axis.cross(d).length();
        if across > limit {
            s * limit / across
        } else {
            s
        }
    };
    let (a, b) = (c.radius, c.radius * c.ratio);
    let (a2, b2) = (capped(a, u), capped(b, v));
    if a2 >= a && b2 >= b {
        return false;
    }
    let (major, minor, axis) = if a2 >= b2 { (a2, b2, u) } else { (b2, a2, v) };
    c.radius = major;
    c.axis = axis;
    c.ratio = (minor / major).clamp(MIN_RATIO as f32, 1.0);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(radius: f32, axis: Vec3, ratio: f32) -> Covering {
        Covering {
            radius,
            axis,
            ratio,
            capped: false,
            open: None,
            spacing: 0.0,
        }
    }

    #[test]
    fn the_pitch_is_the_median_angle_between_neighbours_on_a_grid_of_rays() {
        // Samples 1 mrad apart on rays from the origin, one pair 10 mrad apart.
        let at = |angle: f32, depth: f32| Vec3::new(angle.sin(), 0.0, angle.cos()) * depth;
        let mut pairs: Vec<(Vec3, Vec3)> = (0..9)
            .map(|k| (at(k as f32 * 1e-3, 2.0), at((k + 1) as f32 * 1e-3, 2.5)))
            .collect();
        pairs.push((at(0.0, 1.0), at(0.01, 1.0)));
        let pitch = angular_pitch(Vec3::ZERO, pairs.iter().copied()).unwrap();
        assert!((pitch - 1e-3).abs() < 1e-6, "{pitch}");
        assert_eq!(angular_pitch(Vec3::ZERO, std::iter::empty()), None);
        // Neighbours 1 to 4 mrad apart: no grid of rays.
        let spread = (0..10).map(|k| (at(0.0, 1.0), at(1e-3 * (1.0 + k as f32 / 3.0), 1.0)));
        assert_eq!(angular_pitch(Vec3::ZERO, spread), None);
    }

    #[test]
    fn a_disc_facing_the_sensor_spans_at_most_its_pixels_and_a_slanted_one_keeps_its_slant() {
        let (sensor, p, pitch) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 4.0), 1e-3);
        let limit = MAX_PITCHES * pitch * 4.0;
        // Facing the sensor, 10 limits wide: both axes shrink to the limit.
        let mut c = disc(10.0 * limit, Vec3::X, 1.0);
        assert!(cap(&mut c, -Vec3::Z, p, sensor, pitch));
        assert!((c.radius - limit).abs() < 1e-6 * limit && c.ratio == 1.0);
        // Seen at 80° from its normal, its major axis along the slant: the slant's
        // projection is cos 80° = 0.17 of it, so 4 limits along it stay.
        let n = Vec3::new(0.0, 80f32.to_radians().sin(), -80f32.to_radians().cos());
        let slant = n.cross(Vec3::X);
        let mut c = disc(4.0 * limit, slant, 0.5);
        assert!(cap(&mut c, n, p, sensor, pitch));
        assert!(
            (c.radius - 4.0 * limit).abs() < 1e-5 * limit,
            "{}",
            c.radius
        );
        assert!((c.radius * c.ratio - limit).abs() < 1e-5 * limit);
        // A small disc is left alone.
        let mut c = disc(0.5 * limit, Vec3::X, 0.7);
        assert!(!cap(&mut c, -Vec3::Z, p, sensor, pitch));
        assert_eq!((c.radius, c.ratio), (0.5 * limit, 0.7));
    }
}
