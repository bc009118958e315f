//! Instances in spatial groups, so that a frame culls a group of at most [`GROUP`]
//! instances by one sphere test before testing its members: the instances are sorted by
//! model, then along a Morton curve of their centres, and each run of [`GROUP`] of one
//! model is a group, with the sphere that holds its members' spheres and their largest
//! scale. 10⁵ instances of one model make 1,563 groups; the table costs about half a
//! byte an instance.

use std::ops::Range;

use glam::DVec3;

use super::Instance;
use crate::tree::select::ViewCone;

/// Instances per group at most (`GROUP` in WGSL: a workgroup of the GPU's placement
/// pass places one group).
pub const GROUP: usize = 64;

/// One group: its members (instance indices), their model, the sphere holding theirs,
/// and their least and largest scales.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Group {
    pub centre: DVec3,
    pub radius: f64,
    pub start: u32,
    pub end: u32,
    pub model: u32,
    pub scale_min: f32,
    pub scale_max: f32,
}

impl Group {
    pub fn members(&self) -> Range<usize> {
        self.start as usize..self.end as usize
    }
}

/// The groups of a sorted instance list.
#[derive(Debug, Clone, Default)]
pub struct Groups {
    groups: Vec<Group>,
    /// Each instance's sphere radius is its model's times its scale; the models'.
    model_spheres: Vec<(DVec3, f64)>,
}

impl Groups {
    /// Sorts `instances` by model, then along a Morton curve of their centres, and
    /// groups them; the models' bounding spheres (file coordinates) are `spheres`.
    pub fn sort(instances: &mut [Instance], spheres: &[(DVec3, f64)]) -> Groups {
        // Each instance's sphere once: the sort key and its group's sphere both read it.
        let of_each: Vec<(DVec3, f64)> = instances.iter().map(|i| sphere(i, spheres)).collect();
        let (lo, hi) = of_each.iter().fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), (c, _)| (lo.min(*c), hi.max(*c)),
        );
        let extent = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let mut order: Vec<(u32, u64, u32)> = (instances.iter().zip(&of_each).enumerate())
            .map(|(k, (i, (c, _)))| (i.model, morton((*c - lo) / extent), k as u32))
            .collect();
        order.sort_unstable();
        let sorted: Vec<Instance> = order.iter().map(|o| instances[o.2 as usize]).collect();
        let of_each: Vec<(DVec3, f64)> = order.iter().map(|o| of_each[o.2 as usize]).collect();
        instances.copy_from_slice(&sorted);
        let mut groups = Vec::with_capacity(instances.len().div_ceil(GROUP));
        let mut start = 0;
        while start < instances.len() {
            let model = instances[start].model;
            let run = instances[start..].partition_point(|i| i.model == model);
            for members in (start..start + run).step_by(GROUP) {
                let end = (members + GROUP).min(start + run);
                let of = &instances[members..end];
                let (centre, radius) = enclosing(of_each[members..end].iter().copied());
                groups.push(Group {
                    centre,
                    radius,
                    start: members as u32,
                    end: end as u32,
                    model,
                    scale_min: of.iter().map(|i| i.scale).fold(f32::INFINITY, f32::min),
                    scale_max: of.iter().map(|i| i.scale).fold(0.0, f32::max),
                });
            }
            start += run;
        }
        Groups {
            groups,
            model_spheres: spheres.to_vec(),
        }
    }

    /// The groups `cone` may see.
    pub fn visible<'a>(&'a self, cone: &'a ViewCone) -> impl Iterator<Item = &'a Group> + 'a {
        (self.groups.iter()).filter(|g| cone.sees_sphere(g.centre, g.radius))
    }

    /// Instance `i`'s bounding sphere in the world.
    pub fn sphere_of(&self, i: &Instance) -> (DVec3, f64) {
        sphere(i, &self.model_spheres)
    }

    /// Bytes of the group table.
    pub fn bytes(&self) -> u64 {
        std::mem::size_of_val(self.groups.as_slice()) as u64
    }

    pub fn len(&self) -> usize {
        self.groups.len()
    }

    pub fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }
}

/// An instance's world sphere: its model's sphere transformed.
fn sphere(i: &Instance, spheres: &[(DVec3, f64)]) -> (DVec3, f64) {
    let (c, r) = spheres[i.model as usize];
    let s = i.similarity();
    (s.apply(c), r * s.scale)
}

/// A sphere holding all of `spheres` (about their centres' box centre).
fn enclosing(spheres: impl Iterator<Item = (DVec3, f64)> + Clone) -> (DVec3, f64) {
    let (lo, hi) = spheres.clone().fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), (c, _)| (lo.min(c), hi.max(c)),
    );
    let centre = 0.5 * (lo + hi);
    let radius = spheres
        .map(|(c, r)| (c - centre).length() + r)
        .fold(0.0, f64::max);
    (centre, radius)
}

/// The Morton code of a point in the unit cube (21 bits an axis).
fn morton(p: DVec3) -> u64 {
    let spread = |v: f64| {
        let mut x = (v.clamp(0.0, 1.0) * ((1u64 << 21) - 1) as f64) as u64;
        x = (x | (x << 32)) & 0x1f00000000ffff;
        x = (x | (x << 16)) & 0x1f0000ff0000ff;
        x = (x | (x << 8)) & 0x100f00f00f00f00f;
        x = (x | (x << 4)) & 0x10c30c30c30c30c3;
        (x | (x << 2)) & 0x1249249249249249
    };
    spread(p.x) | (spread(p.y) << 1) | (spread(p.z) << 2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn every_instance_lies_in_its_group_s_sphere() {
        let spheres = [(DVec3::ZERO, 1.0), (DVec3::new(0.0, 0.0, 5.0), 2.0)];
        let mut instances: Vec<Instance> = (0..1000)
            .map(|k| {
                let t = DVec3::new((k * 37 % 101) as f64, (k * 13 % 97) as f64, 0.0);
                let q = DQuat::from_rotation_z(k as f64);
                Instance::checked(k % 2, t, q, 0.5 + (k % 3) as f64, 2).unwrap()
            })
            .collect();
        let groups = Groups::sort(&mut instances, &spheres);
        // 500 instances of each model: 8 groups each.
        assert_eq!(groups.len(), 16);
        let mut covered = 0;
        for g in &groups.groups {
            assert_eq!(g.start as usize, covered);
            covered = g.end as usize;
            for (k, i) in instances[g.members()].iter().enumerate() {
                assert_eq!(i.model, g.model);
                assert!(g.scale_min <= i.scale && i.scale <= g.scale_max);
                let (c, r) = groups.sphere_of(i);
                assert!(
                    (c - g.centre).length() + r <= g.radius * (1.0 + 1e-12),
                    "instance {k}"
                );
            }
        }
        assert_eq!(covered, instances.len());
        // Sorted spatially: a group spans far less than the whole scene.
        let mean = groups.groups.iter().map(|g| g.radius).sum::<f64>() / groups.len() as f64;
        assert!(mean < 40.0, "mean group radius {mean}");
    }
}
