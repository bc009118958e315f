//! A terrain's samples in layers that its TIN must not join. A 2.5D TIN holds one
//! height per x–y: between a tree's crown and the ground beside its trunk, or a bridge
//! deck's edge and the gully floor under it, it stands a wall that no sample saw
//! (docs/point-clouds.md, "Airborne scans against a known scene"). So:
//!
//! - **vegetation** (ASPRS classes 3–5; among the samples the file leaves
//!   unclassified, those whose 3D neighbourhood samples no surface,
//!   [`super::cloud::scattered`]; and the lone returns over the ground that hold no
//!   triangle of their own, [`super::free_roofs`]) gets a cloud's surfels among
//!   itself ([`super::vegetation`]);
//! - **bridge decks** (class 17), and the slabs (flat roofs, decks without their class)
//!   that no sample shows a wall under ([`super::free_roofs`]), get a TIN of their own,
//!   and the ground's TIN runs on under them;
//! - the rest (ground, roofs, walls, whatever else) keeps the TIN ([`super::terrain`]).

use glam::Vec3;
use rayon::prelude::*;

use super::cloud;
use super::free_roofs::{self, Standing};
use super::progress::{Listener, Progress, Stages};
use super::terrain::{self, Cover, TinSplats};
use super::{Surfel, SurfelStats};
use crate::io::Geometry;
use crate::io::delaunay::{self, delaunay_xy};

/// The layer a sample is drawn in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    Ground = 0,
    Deck = 1,
    Plants = 2,
}

/// ASPRS class of a bridge deck.
pub const BRIDGE_DECK: u8 = 17;

/// The layer of each sample of `g` (the first `own` its own): vegetation by its class
/// (3–5), or, for a sample its file leaves unclassified (class 0 or 1, or no classes
/// at all), by its geometry; decks by class; among the rest, the slabs that stand free
/// as decks and the lone returns as vegetation, by their geometry. A sample's layer
/// does not depend on which piece of an out-of-core job holds it but through its
/// neighbours. With them, the TIN that the slabs and lone returns were found on.
/// Its stages are told to `stages` ([`Weights`]); `scatter_tested`: [`tests_scatter`].
pub fn labels(
    g: &Geometry,
    (own, scale): (usize, f32),
    (stages, scatter_tested): (&Stages, bool),
) -> (Vec<Layer>, FirstTin) {
    let class = |i: usize| class_of(g, i);
    let unclassified = |i: usize| matches!(class(i), 0 | 1);
    let plants = if scatter_tested {
        let share = stages.share(WEIGHTS.scatter);
        cloud::scattered(&g.positions, scale, Progress::to(&share))
    } else {
        Vec::new()
    };
    let mut labels: Vec<Layer> = (0..g.positions.len())
        .map(|i| match class(i) {
            3..=5 => Layer::Plants,
            BRIDGE_DECK => Layer::Deck,
            _ if unclassified(i) && plants.get(i) == Some(&true) => Layer::Plants,
            _ => Layer::Ground,
        })
        .collect();
    let ground: Vec<u32> = (0..g.positions.len() as u32)
        .filter(|&i| labels[i as usize] == Layer::Ground)
        .collect();
    let positions = pick(&g.positions, &ground);
    let share = stages.share(WEIGHTS.first_tin);
    let delaunay = delaunay::delaunay_xy_telling(&positions, &|n| share.heard(n as u64));
    let ground_own = ground.partition_point(|&i| (i as usize) < own);
    let standing = free_roofs::free_standing(&positions, &delaunay, ground_own);
    stages.ended(WEIGHTS.free_standing);
    drop(positions);
    for (&i, standing) in ground.iter().zip(standing) {
        match standing {
            Standing::Joined => {}
            Standing::Slab => labels[i as usize] = Layer::Deck,
            Standing::Lone => labels[i as usize] = Layer::Plants,
        }
    }
    let first = FirstTin {
        which: ground,
        delaunay,
    };
    (labels, first)
}

/// The TIN [`labels`] found the slabs and lone returns on: the samples that the
/// classes and the geometry left on the ground, and their Delaunay triangulation.
pub struct FirstTin {
    /// Indices into the model, ascending.
    which: Vec<u32>,
    /// [`delaunay_xy`] of those samples (indices into `which`).
    delaunay: Vec<[u32; 3]>,
}

impl FirstTin {
    /// The Delaunay triangulation (long triangles kept) of the samples of `g` that
    /// `labels` leaves on the ground (`which`, ascending), as indices into `which`:
    /// this TIN less the samples taken off the ground ([`delaunay::without`]), or
    /// a new one where that cannot be.
    pub fn ground(self, g: &Geometry, labels: &[Layer], which: &[u32]) -> Vec<[u32; 3]> {
        let positions = pick(&g.positions, &self.which);
        let removed: Vec<bool> = (self.which.iter())
            .map(|&i| labels[i as usize] != Layer::Ground)
            .collect();
        let held = self
            .which
            .iter()
            .filter(|&&i| labels[i as usize] == Layer::Ground);
        let same = held.copied().eq(which.iter().copied());
        let rest = same.then(|| delaunay::without(&positions, self.delaunay, &removed));
        let Some(Some(mut rest)) = rest else {
            return delaunay_xy(&pick(&g.positions, which));
        };
        let mut renumber = vec![u32::MAX; positions.len()];
        let kept = (0..positions.len()).filter(|&k| !removed[k]);
        for (n, k) in kept.enumerate() {
            renumber[k] = n as u32;
        }
        // Triangle by triangle: rayon's `flatten` would drive each 3-array as a
        // parallel iterator of its own, at many times the cost.
        (rest.par_iter_mut()).for_each(|t| t.iter_mut().for_each(|v| *v = renumber[*v as usize]));
        rest
    }
}

/// Each layer's samples, its own (the first `own` of the model) first, then its
/// halo's, in the model's order, with how many are its own.
pub struct Layers {
    sets: [(Vec<u32>, usize); 3],
}

impl Layers {
    pub fn of(labels: &[Layer], own: usize) -> Layers {
        let mut sets: [(Vec<u32>, usize); 3] = Default::default();
        for (i, &l) in labels.iter().enumerate() {
            let set = &mut sets[l as usize];
            set.0.push(i as u32);
            set.1 += (i < own) as usize;
        }
        Layers { sets }
    }

    /// The samples of `layer` and how many of them are the model's own.
    pub fn get(&self, layer: Layer) -> (&[u32], usize) {
        let (set, own) = &self.sets[layer as usize];
        (set, *own)
    }

    /// Whether the ground holds every own sample.
    pub fn all_ground(&self) -> bool {
        self.sets[1..].iter().all(|s| s.1 == 0)
    }
}

/// ASPRS class of sample `i` of `g`; 0 (never classified) where the file has none.
fn class_of(g: &Geometry, i: usize) -> u8 {
    g.attributes.as_deref().map_or(0, |a| a[i].class)
}

/// Whether [`labels`] tests the samples for vegetation by their geometry: where one of
/// the first `own` is unclassified (class 0 or 1).
pub fn tests_scatter(g: &Geometry, own: usize) -> bool {
    (0..own).any(|i| matches!(class_of(g, i), 0 | 1))
}

/// Each stage's share of a terrain's surfels time, in percent, for its progress
/// ([`Stages`]): on a 2 M-point slice of the generated city (`gen_cloud --points
/// 2000000 --size 400`, classified, 2.47 s on 2 cores, Intel, 2026-12-04) the first
/// TIN took 0.57 s, its slabs and lone returns 0.45 s, the ground's TIN less them 0.20
/// s and the layers' TINs, rings and plants 1.25 s; on terrain_utm (unclassified) the
/// vegetation test took 0.28 s against the layers' 0.49 s.
pub struct Weights {
    /// The vegetation test of unclassified samples ([`cloud::scattered`]).
    pub scatter: u32,
    /// The first TIN ([`labels`]).
    pub first_tin: u32,
    /// Its slabs and lone returns ([`free_roofs::free_standing`]).
    pub free_standing: u32,
    /// The ground's TIN less them ([`FirstTin::ground`]).
    pub ground_tin: u32,
    /// Each layer's TIN and its rings ([`tin_among`]), and the plants.
    pub layers: u32,
}

/// See [`Weights`].
pub const WEIGHTS: Weights = Weights {
    scatter: 29,
    first_tin: 23,
    free_standing: 18,
    ground_tin: 8,
    layers: 51,
};

impl Weights {
    /// The sum of the weights of the stages that run, the vegetation test's where
    /// `scatter_tested`.
    pub fn running(&self, scatter_tested: bool) -> u32 {
        let scatter = if scatter_tested { self.scatter } else { 0 };
        scatter + self.first_tin + self.free_standing + self.ground_tin + self.layers
    }
}

/// The TIN's surfels of the samples `which` (of which the first `own` are the model's
/// own) among themselves, into `surfels` (one per sample of `g`), from their `delaunay`
/// triangulation (made here where None), keeping the long triangles under `cover`;
/// their long triangles' splats and spacing. None where they make no triangle. The
/// shaped samples are told to `progress`.
pub fn tin_among(
    (g, scale): (&Geometry, f32),
    (which, own): (&[u32], usize),
    (delaunay, cover): (Option<Vec<[u32; 3]>>, &Cover),
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> Option<TinSplats> {
    let given = g.normals.as_deref().map(|n| pick(n, which));
    let colors = g.colors.as_deref().map(|c| pick(c, which));
    let attributes = g.attributes.as_deref().map(|a| pick(a, which));
    let look = (given.as_deref(), (colors.as_deref(), attributes.as_deref()));
    let mut picked = pick(surfels, which);
    let positions: Vec<Vec3> = pick(&g.positions, which);
    let delaunay = delaunay.unwrap_or_else(|| delaunay_xy(&positions));
    let at = (&positions[..], delaunay, scale);
    let tin = terrain::terrain_disks(at, (own, cover), look, &mut picked, stats, progress)?;
    for (k, &i) in which.iter().enumerate() {
        surfels[i as usize] = picked[k];
    }
    Some(tin)
}

/// `values` at `indices`.
pub fn pick<T: Copy + Send + Sync>(values: &[T], indices: &[u32]) -> Vec<T> {
    indices.par_iter().map(|&i| values[i as usize]).collect()
}
