//! Instances scattered over a surface: the texels-over-a-base-surface idea of
//! multi-scale volume textures, for models. Each instance stands at a point drawn
//! uniformly by area over the surface's triangles (those steeper than a bound left
//! out), its model picked at random among the given ones, turned about z by a random
//! yaw and scaled by a random factor, its foot (the bottom centre of its box, along its
//! up axis) on the point. The same seed gives the same instances.

use glam::{DQuat, DVec3};

use super::Instance;

/// A model to scatter: the rotation that stands it up (its up axis to +z) and its
/// foot (file coordinates).
#[derive(Debug, Clone, Copy)]
pub struct Standing {
    pub up_to_z: DQuat,
    pub foot: DVec3,
}

impl Standing {
    /// A model whose box is `[lo, hi]` (file coordinates) with up axis `up` (unit).
    pub fn of(lo: DVec3, hi: DVec3, up: DVec3) -> Standing {
        let centre = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo);
        // The box's lowest extent along up, through its centre.
        let down = half.dot(up.abs());
        Standing {
            up_to_z: DQuat::from_rotation_arc(up, DVec3::Z),
            foot: centre - up * down,
        }
    }
}

/// How instances are scattered.
#[derive(Debug, Clone)]
pub struct Spread {
    /// Instances per unit of surface area.
    pub density: f64,
    /// Or this many instances in all, whatever the area.
    pub count: Option<usize>,
    /// Yaw range (degrees) and scale range.
    pub yaw_deg: [f64; 2],
    pub scale: [f64; 2],
    /// Triangles steeper than this (degrees from level) get none.
    pub max_slope_deg: f64,
    pub seed: u64,
}

/// Instances of `models` (scene model indices `first_model`, `first_model` + 1, …)
/// scattered over the triangles of `positions` (world coordinates) by `spread`.
pub fn scatter(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    models: &[Standing],
    first_model: usize,
    spread: &Spread,
) -> Vec<Instance> {
    let min_up = spread.max_slope_deg.to_radians().cos();
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut total = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        let area = 0.5 * n.length();
        if area > 0.0 && n.normalize().z.abs() >= min_up {
            total += area;
        }
        cumulative.push(total);
    }
    let count = spread
        .count
        .unwrap_or((spread.density * total).round() as usize);
    if total <= 0.0 {
        return Vec::new();
    }
    let mut rng = SplitMix(spread.seed);
    let range = |rng: &mut SplitMix, [lo, hi]: [f64; 2]| lo + (hi - lo) * rng.uniform();
    let scene_models = first_model + models.len();
    (0..count)
        .filter_map(|_| {
            let at = rng.uniform() * total;
            let k = cumulative
                .partition_point(|&c| c <= at)
                .min(triangles.len() - 1);
            let [a, b, c] = triangles[k].map(|i| positions[i as usize]);
            let (mut u, mut v) = (rng.uniform(), rng.uniform());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let point = a + u * (b - a) + v * (c - a);
            let m = (rng.uniform() * models.len() as f64) as usize % models.len();
            let yaw = range(&mut rng, spread.yaw_deg).to_radians();
            let scale = range(&mut rng, spread.scale);
            let rotation = DQuat::from_rotation_z(yaw) * models[m].up_to_z;
            let translation = point - scale * (rotation * models[m].foot);
            Instance::checked(first_model + m, translation, rotation, scale, scene_models).ok()
        })
        .collect()
}

/// splitmix64, as uniform numbers in [0, 1): small, and the same sequence on every
/// machine (the scene generator in `tools/` draws its trees with it too).
pub struct SplitMix(pub u64);

impl SplitMix {
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 × 10 square in z = 5 and a wall beside it (two triangles each).
    fn ground_and_wall() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = [
            (0.0, 0.0, 5.0),
            (10.0, 0.0, 5.0),
            (10.0, 10.0, 5.0),
            (0.0, 10.0, 5.0),
            (20.0, 0.0, 0.0),
            (20.0, 10.0, 0.0),
            (20.0, 10.0, 10.0),
            (20.0, 0.0, 10.0),
        ];
        let positions = p.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
        (positions, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    }

    #[test]
    fn instances_stand_on_the_level_ground_at_the_asked_density() {
        let (positions, triangles) = ground_and_wall();
        // A model whose box is y-up, its foot at y = −1.
        let model = Standing::of(
            DVec3::new(-1.0, -1.0, -1.0),
            DVec3::new(1.0, 3.0, 1.0),
            DVec3::Y,
        );
        let spread = Spread {
            density: 2.0,
            count: None,
            yaw_deg: [0.0, 360.0],
            scale: [0.5, 2.0],
            max_slope_deg: 30.0,
            seed: 7,
        };
        let instances = scatter(&positions, &triangles, &[model], 1, &spread);
        assert_eq!(instances.len(), 200, "2 a unit² of the 100 level units²");
        for i in &instances {
            let s = i.similarity();
            let foot = s.apply(model.foot);
            assert!(
                (foot.z - 5.0).abs() < 1e-6, // the rotation is stored in f32
                "the foot stands on the ground: {foot}"
            );
            assert!((0.0..=10.0).contains(&foot.x) && (0.0..=10.0).contains(&foot.y));
            // Up (model y) is world z.
            assert!((s.direction(DVec3::Y) - DVec3::Z).length() < 1e-6);
            assert!((0.5..=2.0).contains(&s.scale) && i.model == 1);
        }
        let again = scatter(&positions, &triangles, &[model], 1, &spread);
        assert_eq!(instances, again, "the same seed, the same instances");
    }
}
