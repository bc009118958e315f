//! Each instance's level of detail: the list ranges of its model that it hands to the
//! GPU, found in the model's own units ([`super::Similarity`]: the same ε, the eye
//! mapped into the model).
//!
//! An instance whose eye lies well outside its model's bounding sphere (nearly every
//! instance of a large scene) takes every chunk's prefix at one distance: d, the eye's
//! distance to the sphere in model units, rounded down to 1/16 of an octave. Every
//! chunk's box lies in the sphere, so its own distance is at least d, and a prefix at a
//! smaller distance holds the one at a larger (the argument of
//! `PrefixIndex::prefixes_at`): the ranges hold every node the exact test draws. They
//! depend on d and ε alone, so a model keeps them per rounded distance ([`ModelLod`]),
//! and a frame of 10⁵ instances searches a few dozen times. An instance whose eye is
//! near or within its sphere searches chunk by chunk, culled by the view cone mapped
//! into the model ([`ModelLod::near`]), as a model drawn alone does.

use std::ops::Range;
use std::sync::{Arc, Mutex, MutexGuard};

use glam::DVec3;

use crate::tree::scene::Scene;
use crate::tree::select::ViewCone;

/// Steps of the rounded distance per octave.
pub const STEPS_PER_OCTAVE: f64 = 16.0;
/// Rounded distances kept: 2⁻¹²⁸ to 2¹²⁸ sphere radii.
pub const STEPS: i32 = 128 * STEPS_PER_OCTAVE as i32;
/// Slots of a model's table: one per rounded distance (step + [`STEPS`]).
pub const SLOTS: usize = 2 * STEPS as usize + 1;

/// Tables kept for other ε than the current one.
const KEPT_EPS: usize = 8;

/// Ranges by rounded distance (step + STEPS), for one ε.
type Table = Vec<Option<Arc<[Range<usize>]>>>;

/// A model's ranges by rounded distance, for the ε they were found at, and the
/// tables of the last few other ε.
pub struct Kept {
    eps: f64,
    by_step: Table,
    others: Vec<(f64, Table)>,
}

/// The ranges a caller found for a few rounded distances of one model (slot, ranges):
/// instances of a spatial group lie at about the same distance.
#[derive(Default)]
pub struct NearBy(Vec<(usize, Arc<[Range<usize>]>)>);

/// One model's ranges by rounded distance.
pub struct ModelLod {
    /// The model's bounding sphere, relative to its origin.
    centre: DVec3,
    pub radius: f64,
    kept: Mutex<Kept>,
}

impl ModelLod {
    pub fn new(model: &Scene) -> ModelLod {
        let meta = model.meta();
        let (centre, radius) = super::model_sphere(meta);
        ModelLod {
            centre: centre - DVec3::from(meta.origin),
            radius,
            kept: Mutex::new(Kept {
                eps: f64::NAN,
                by_step: vec![None; SLOTS],
                others: Vec::new(),
            }),
        }
    }

    /// The kept ranges for ε = `eps` (the tables of the last few ε are kept: a frame
    /// that coarsens tries several).
    fn lock(&self, eps: f64) -> MutexGuard<'_, Kept> {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        if kept.eps != eps {
            let found = kept.others.iter().position(|(e, _)| *e == eps);
            let table = match found {
                Some(k) => kept.others.swap_remove(k).1,
                None => vec![None; SLOTS],
            };
            let old = (kept.eps, std::mem::replace(&mut kept.by_step, table));
            kept.eps = eps;
            if old.0.is_finite() {
                kept.others.push(old);
            }
            if kept.others.len() > KEPT_EPS {
                kept.others.remove(0);
            }
        }
        kept
    }

    /// The ranges at `eps` of an instance whose eye is `d` model units outside the
    /// sphere (d > 0, ε > 0): from `near_by` (what the caller found for instances near
    /// this one: a few rounded distances, without locking), else kept, else searched
    /// (without the lock held) and kept.
    pub fn far(
        &self,
        model: &Scene,
        d: f64,
        eps: f64,
        near_by: &mut NearBy,
    ) -> Arc<[Range<usize>]> {
        let slot = self.slot(d);
        if let Some((_, found)) = near_by.0.iter().find(|(s, _)| *s == slot) {
            return found.clone();
        }
        let found = self.far_kept(model, slot, eps);
        near_by.0.push((slot, found.clone()));
        found
    }

    /// The slot of an eye `d` model units outside the sphere: the rounded distance
    /// ⌊16 log₂(d / r)⌋ + [`STEPS`], clamped to the table.
    pub fn slot(&self, d: f64) -> usize {
        let step = ((d / self.radius).log2() * STEPS_PER_OCTAVE).floor();
        (step.clamp(-STEPS as f64, STEPS as f64) as i32 + STEPS) as usize
    }

    /// The ranges of rounded distance `slot` (step + STEPS): kept, or searched and kept.
    pub fn far_kept(&self, model: &Scene, slot: usize, eps: f64) -> Arc<[Range<usize>]> {
        if let Some(found) = &self.lock(eps).by_step[slot] {
            return found.clone();
        }
        let step = slot as i32 - STEPS;
        let rounded = self.radius * (step as f64 / STEPS_PER_OCTAVE).exp2();
        let index = &model.index;
        let prefixes = index.prefixes_at(rounded, eps);
        let found: Arc<[Range<usize>]> = index.refined(&prefixes, model.nodes(), |_| true).into();
        self.lock(eps).by_step[slot] = Some(found.clone());
        found
    }

    /// The ranges of an instance whose eye is `eye` (model units, relative to the
    /// origin), within or near its sphere, chunks culled by `cone` (the same units);
    /// each prefix ends at its node (`trim`) or its block.
    pub fn near(
        &self,
        model: &Scene,
        (eye, cone): (DVec3, &ViewCone),
        eps: f64,
        trim: bool,
    ) -> Vec<Range<usize>> {
        let index = &model.index;
        let prefixes = index.prefixes(eye, eps, Some(cone));
        match trim {
            true => index.refined(&prefixes, model.nodes(), |_| true),
            false => prefixes.bounds(),
        }
    }

    /// The eye's distance to the sphere, model units, from its world distance to the
    /// sphere's centre under scale `scale`.
    pub fn gap(&self, world_distance: f64, scale: f64) -> f64 {
        world_distance / scale - self.radius
    }

    /// The sphere's centre, relative to the model's origin.
    pub fn centre(&self) -> DVec3 {
        self.centre
    }
}
