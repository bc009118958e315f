//! Axis-aligned boxes in a file's own coordinates.

use glam::DVec3;
use serde::Serialize;

/// Axis-aligned box in the file's own coordinates, at full f64 precision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct Bounds {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Bounds {
    /// Centre, as min/2 + max/2: finite for any finite box (min + max may overflow).
    pub fn center(&self) -> DVec3 {
        DVec3::from(self.min) * 0.5 + DVec3::from(self.max) * 0.5
    }

    pub fn extent(&self) -> DVec3 {
        DVec3::from(self.max) - DVec3::from(self.min)
    }

    /// Whether `p` lies in the box (faces included).
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|k| self.min[k] <= p[k] && p[k] <= self.max[k])
    }

    pub(crate) fn empty() -> Self {
        Bounds {
            min: [f64::INFINITY; 3],
            max: [f64::NEG_INFINITY; 3],
        }
    }

    pub(crate) fn grow(mut self, p: [f64; 3]) -> Self {
        self.min = std::array::from_fn(|a| self.min[a].min(p[a]));
        self.max = std::array::from_fn(|a| self.max[a].max(p[a]));
        self
    }

    pub(crate) fn union(self, o: Self) -> Self {
        self.grow(o.min).grow(o.max)
    }
}
