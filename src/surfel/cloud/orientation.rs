//! Which way a cloud's estimated normals are turned: up on a terrain, toward the
//! sensor on a frame, decided from the cloud's boxes and its file's origin.

use glam::Vec3;

/// Which way a cloud's estimated normals face, where the data tells: sign consistency
/// lets the tree's inner nodes average their children's normals without cancelling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// An airborne tile (far wider than it is high): +z.
    Up,
    /// A sensor frame: toward the sensor, at this point (relative to the model origin).
    Toward(Vec3),
    /// Nothing known: drawn two-sided as they are.
    Unknown,
}

/// Which way a model's normals were turned when its surfels were estimated: what the
/// renderer must know of the [`Orientation`] (a `.spt` file stores it from version 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalsTurned {
    /// Not turned: a mesh's, given ones, or a cloud's of unknown orientation (drawn
    /// two-sided).
    #[default]
    No,
    /// A terrain's, up: a splat's underside is the ground's, weighed as a mesh's back.
    Up,
    /// A sensor frame's, toward the file's origin, where the sensor stood.
    TowardOrigin,
}

impl NormalsTurned {
    /// How estimated normals facing `orientation` were turned.
    pub fn of(orientation: Orientation) -> NormalsTurned {
        match orientation {
            Orientation::Up => NormalsTurned::Up,
            Orientation::Toward(_) => NormalsTurned::TowardOrigin,
            Orientation::Unknown => NormalsTurned::No,
        }
    }
}

/// A model whose core is less than a quarter as high as it is wide is a terrain.
const TERRAIN_ASPECT: f64 = 0.25;

impl Orientation {
    /// The orientation of a cloud with core box `core`, whole box `bounds` and
    /// `origin`: up for a terrain; toward the file's origin (where a sensor writes its
    /// frame from) when that lies outside the box and within 100 core extents of it.
    pub fn of(core: &crate::io::Bounds, bounds: &crate::io::Bounds, origin: glam::DVec3) -> Self {
        let e = core.extent();
        let width = e.x.max(e.y);
        if width > 0.0 && e.z < TERRAIN_ASPECT * width {
            return Orientation::Up;
        }
        let sensor = -origin;
        let far = sensor.length() > 100.0 * e.max_element();
        if bounds.contains([0.0; 3]) || far || !sensor.is_finite() {
            return Orientation::Unknown;
        }
        Orientation::Toward(sensor.as_vec3())
    }

    /// `normal` flipped, if need be, to face this way from `position`.
    pub fn apply(self, position: Vec3, normal: Vec3) -> Vec3 {
        let facing = match self {
            Orientation::Up => Vec3::Z,
            Orientation::Toward(sensor) => sensor - position,
            Orientation::Unknown => return normal,
        };
        if normal.dot(facing) < 0.0 {
            -normal
        } else {
            normal
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_tile_faces_up_and_a_sensor_frame_faces_its_sensor() {
        use crate::io::Bounds;
        let tile = Bounds {
            min: [500.0, 700.0, 10.0],
            max: [900.0, 1100.0, 40.0],
        };
        let o = Orientation::of(&tile, &tile, tile.center());
        assert_eq!(o, Orientation::Up);
        assert_eq!(o.apply(Vec3::ZERO, -Vec3::Z), Vec3::Z);
        let frame = Bounds {
            min: [-1.0, -1.0, 1.0],
            max: [1.0, 1.0, 3.0],
        };
        let o = Orientation::of(&frame, &frame, frame.center());
        assert_eq!(o, Orientation::Toward(Vec3::new(0.0, 0.0, -2.0)));
        assert_eq!(o.apply(Vec3::ZERO, Vec3::Z), -Vec3::Z);
        let around = Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        };
        assert_eq!(
            Orientation::of(&around, &around, glam::DVec3::ZERO),
            Orientation::Unknown
        );
    }
}
