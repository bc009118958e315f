//! The random-subset level of detail that SPT is compared with (docs/design.md §9): `n`
//! leaves drawn uniformly at random without replacement (seeded, so runs repeat), their
//! radii scaled by √(L / n) so that the n disks cover the area the L leaves covered,
//! each with its own shape (ellipse, normal field and clip line over the scaled radius).

use crate::surfel::shape::{Clip, SplatShape};
use crate::tree::chunks::Chunk;
use crate::tree::record::NodeRecord;
use crate::tree::scene::Scene;
use crate::tree::{SequentialList, TreeMeta};

/// f16 +∞: every subset node is a root, drawn at any ε.
const ROOT_PARENT_ERROR: u16 = 0x7C00;

/// SplitMix64: a small, seeded, good-enough generator for sampling.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// The leaves of a scene's list (nodes of error 0), with their shapes.
pub fn leaves(scene: &Scene) -> Vec<(NodeRecord, SplatShape)> {
    scene
        .nodes()
        .iter()
        .zip(scene.shapes())
        .filter(|(r, _)| r.error == 0)
        .map(|(r, s)| (*r, *s))
        .collect()
}

/// A scene of `n` random leaves of `leaves` (all of them when n ≥ their count), radii
/// scaled to keep the coverage, every node drawn at any ε.
pub fn random_subset(
    meta: &TreeMeta,
    leaves: &[(NodeRecord, SplatShape)],
    n: usize,
    seed: u64,
) -> Scene {
    let total = leaves.len();
    let n = n.clamp(1, total.max(1)).min(total);
    // A partial Fisher–Yates shuffle of the indices picks n of them.
    let mut order: Vec<u32> = (0..total as u32).collect();
    let mut rng = SplitMix(seed);
    for i in 0..n {
        let j = i + (rng.next() % (total - i) as u64) as usize;
        order.swap(i, j);
    }
    let scale = (total as f32 / n.max(1) as f32).sqrt();
    let (nodes, shapes): (Vec<NodeRecord>, Vec<SplatShape>) = order[..n]
        .iter()
        .map(|&i| {
            let (mut r, shape) = leaves[i as usize];
            r.radius = (r.radius() * scale).to_bits();
            r.parent_error = ROOT_PARENT_ERROR;
            r.delta = 0;
            r.level = 0;
            let mut shape = shape.unpack(r.normal().as_dvec3());
            shape.gradient = shape.gradient.map(|g| g * scale as f64);
            // The border stays where it was: the same line, in the larger radius (a
            // wedge's sides pass through the centre already).
            if let Some(Clip::Line { offset, .. }) = &mut shape.clip {
                *offset /= scale as f64;
            }
            (r, shape.pack())
        })
        .unzip();
    let mut meta = meta.clone();
    meta.node_count = nodes.len() as u64;
    meta.leaf_count = nodes.len() as u64;
    meta.depth = 0;
    // Compared in shaded mode only: the subset leaves the LiDAR attributes behind.
    meta.has_attributes = false;
    let parents = vec![u32::MAX; nodes.len()];
    let chunks = vec![Chunk::of(0, &nodes)];
    Scene::from_list(
        SequentialList {
            meta,
            nodes,
            shapes,
            attributes: Vec::new(),
            parents,
            chunks,
        },
        None,
    )
}
