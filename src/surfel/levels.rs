//! Quantised depth: an RGB-D sensor stores depth in steps (the Kinect in disparity, so
//! a few centimetres apart at 3 m), and a frame's points then lie on a few hundred
//! planes across its depth axis. A neighbourhood that lies on one such plane sees the
//! step's tread, not the surface: its fit faces along the depth axis whatever the
//! surface's slope, and on a floor seen at a slant such splats read as bright dashes
//! once lit (`kinect_rgb`: 18,061 of its 259,847 fits). The surface's slope
//! shows only across steps, in the fits of the neighbourhoods that span two or more.
//!
//! * [`quantised_axis`]: the coordinate axis a frame's depth is stored along, when its
//!   values take few distinct steps and the sensor looks along it;
//! * [`one_level`]: whether a neighbourhood lies on one step of that axis.

use glam::Vec3;

/// Largest share of distinct values among a sample of a coordinate for that
/// coordinate to be quantised: `kinect_rgb`'s depth takes 317 values over 259,847
/// points, its x and y about one per point.
pub const MAX_DISTINCT_SHARE: f64 = 1.0 / 16.0;

/// How many positions [`quantised_axis`] samples (evenly strided).
const SAMPLE: usize = 65_536;

/// Fewest positions a cloud needs for its steps to tell anything.
const MIN_POSITIONS: usize = 1024;

/// Least cosine between the quantised axis and the direction from the sensor to the
/// cloud's centre: the sensor must look along it (within 45°).
const MIN_LOOK_COS: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// The axis (0, 1, 2 for x, y, z) along which the distinct `coords` of a frame seen
/// from `sensor` (same coordinates) take at most [`MAX_DISTINCT_SHARE`] distinct values
/// in an evenly strided sample, and which the sensor looks along; the one with fewest
/// values if several do, `None` if none does. A cloud sampled on a regular grid has
/// quantised axes too; the look test keeps a grid's faces out unless the sensor looks
/// straight at one.
pub fn quantised_axis(coords: &[[f32; 3]], sensor: Vec3) -> Option<usize> {
    if coords.len() < MIN_POSITIONS {
        return None;
    }
    let stride = coords.len().div_ceil(SAMPLE);
    let sample: Vec<[f32; 3]> = coords.iter().step_by(stride).copied().collect();
    let centre = sample.iter().map(|c| Vec3::from(*c)).sum::<Vec3>() / sample.len() as f32;
    let look = (centre - sensor).normalize_or_zero();
    (0..3)
        .filter(|&axis| look[axis].abs() >= MIN_LOOK_COS)
        .map(|axis| (axis, distinct(&sample, axis)))
        .filter(|&(_, n)| n as f64 <= MAX_DISTINCT_SHARE * sample.len() as f64)
        .min_by_key(|&(_, n)| n)
        .map(|(axis, _)| axis)
}

/// How many distinct values coordinate `axis` takes among `sample` (−0 as +0).
fn distinct(sample: &[[f32; 3]], axis: usize) -> usize {
    let mut values: Vec<u32> = sample
        .iter()
        .map(|c| if c[axis] == 0.0 { 0 } else { c[axis].to_bits() })
        .collect();
    values.sort_unstable();
    values.dedup();
    values.len()
}

/// Whether the positions `found` (indices into `coords`, the point's own first) all
/// share its value of coordinate `axis`: a neighbourhood on one depth step.
pub fn one_level(coords: &[[f32; 3]], axis: usize, found: &[u32]) -> bool {
    let Some(&own) = found.first() else {
        return false;
    };
    let level = coords[own as usize][axis];
    found.iter().all(|&f| coords[f as usize][axis] == level)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A floor seen by a sensor at the origin looking along +z, with a millimetre of
    /// noise, its depth z rounded to `step`, on a 100 × 100 grid of rays.
    fn stepped_floor(step: f32) -> Vec<[f32; 3]> {
        let mut out = Vec::new();
        for row in 0..100 {
            for col in 0..100 {
                let (u, v) = (col as f32 / 100.0 - 0.5, row as f32 / 200.0);
                // The ray (u, v, 1) meets the plane y = 1 − 0.5 z at z = 1 / (v + 0.5).
                let noise = ((row * 100 + col) * 7919 % 1000) as f32 * 1e-6;
                let z = 1.0 / (v + 0.5) + noise;
                let z = (z / step).round() * step;
                out.push([u * z, v * z, z]);
            }
        }
        out
    }

    #[test]
    fn a_stepped_depth_is_found_and_a_fine_one_is_not() {
        assert_eq!(quantised_axis(&stepped_floor(0.02), Vec3::ZERO), Some(2));
        assert_eq!(quantised_axis(&stepped_floor(1e-6), Vec3::ZERO), None);
        // Seen from the side (looking along x), the same steps are not its depth.
        assert_eq!(
            quantised_axis(&stepped_floor(0.02), Vec3::new(-10.0, 0.5, 1.5)),
            None
        );
        // Too few positions to tell.
        assert_eq!(
            quantised_axis(&stepped_floor(0.02)[..500], Vec3::ZERO),
            None
        );
    }

    #[test]
    fn one_level_needs_every_neighbour_on_the_point_s_step() {
        let coords = [[0.0, 0.0, 1.0], [0.1, 0.0, 1.0], [0.0, 0.1, 1.02]];
        assert!(one_level(&coords, 2, &[0, 1]));
        assert!(!one_level(&coords, 2, &[0, 1, 2]));
        assert!(!one_level(&coords, 2, &[]));
    }
}
