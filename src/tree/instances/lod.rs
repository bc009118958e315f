//! Each instance's level of detail: the list ranges of its model that it hands to the
//! GPU, found in the model's own units ([`super::Similarity`]: the same ε, the eye
//! mapped into the model).
//!
//! An instance whose eye lies outside its model's bounding sphere (nearly every
//! instance of a large scene) takes every chunk's prefix at one distance: d, the eye's
//! distance to the sphere, rounded down to 1/16 of an octave. Every chunk's box lies
//! in the sphere, so its own distance is at least d, and a prefix at a smaller
//! distance holds the one at a larger (the argument of `PrefixIndex::prefixes_at`):
//! the ranges hold every node the exact test draws. They depend on d and ε alone, so a
//! model keeps them per rounded distance ([`ModelLod`]), and a frame of 10⁵ instances
//! searches a few dozen times. An instance whose eye is within its sphere searches
//! chunk by chunk, culled by the view cone mapped into the model.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::{Arc, Mutex};

use glam::DVec3;

use crate::tree::scene::Scene;
use crate::tree::select::ViewCone;

/// Ranges by rounded distance (its step), for one ε.
type Kept = (f64, HashMap<i32, Arc<[Range<usize>]>>);

/// Steps of the rounded distance per octave.
const STEPS_PER_OCTAVE: f64 = 16.0;

/// One model's ranges by rounded distance, for the ε they were found at.
pub struct ModelLod {
    /// The model's bounding sphere, relative to its origin.
    centre: DVec3,
    radius: f64,
    cache: Mutex<Kept>,
}

impl ModelLod {
    pub fn new(model: &Scene) -> ModelLod {
        let meta = model.meta();
        let (centre, radius) = super::model_sphere(meta);
        ModelLod {
            centre: centre - DVec3::from(meta.origin),
            radius,
            cache: Mutex::new((f64::NAN, HashMap::new())),
        }
    }

    /// The ranges of `model`'s list an instance hands over with its eye at `eye`
    /// (model units, relative to the model's origin) at `eps`; `cone` (in the same
    /// units) culls chunks when the eye is within the model's sphere.
    pub fn ranges(
        &self,
        model: &Scene,
        eye: DVec3,
        cone: &ViewCone,
        eps: f64,
    ) -> Arc<[Range<usize>]> {
        let d = (eye - self.centre).length() - self.radius;
        if d <= 0.0 || eps <= 0.0 {
            let index = &model.index;
            let prefixes = index.prefixes(eye, eps, Some(cone));
            return index.refined(&prefixes, model.nodes(), |_| true).into();
        }
        let step = (d / self.radius).log2() * STEPS_PER_OCTAVE;
        let key = step.floor().clamp(-4096.0, 4096.0) as i32;
        let rounded = self.radius * (key as f64 / STEPS_PER_OCTAVE).exp2();
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if cache.0 != eps {
            *cache = (eps, HashMap::new());
        }
        cache
            .1
            .entry(key)
            .or_insert_with(|| {
                let index = &model.index;
                let prefixes = index.prefixes_at(rounded.min(d), eps);
                index.refined(&prefixes, model.nodes(), |_| true).into()
            })
            .clone()
    }

    /// Rounded distances kept (for the memory report).
    pub fn kept(&self) -> usize {
        self.cache.lock().map_or(0, |c| c.1.len())
    }
}
