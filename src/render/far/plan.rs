//! What a frame's plan hands the GPU of one model's far instances.

use std::ops::Range;

use crate::tree::instances::groups::GROUP;

/// What a frame's plan hands the GPU of one model: its far groups' members
/// (model-local instance ranges) and the table slots they may reach.
#[derive(Debug, Clone, Default, PartialEq)]
pub(in crate::render) struct FarPlan {
    pub groups: Vec<[u32; 2]>,
    pub slots: Option<Range<usize>>,
}

impl FarPlan {
    /// Adds a group of at most [`GROUP`] members (model-local instance indices) whose
    /// rounded distances lie in `slots`.
    pub fn add(&mut self, members: Range<usize>, slots: Range<usize>) {
        self.groups.push([members.start as u32, members.end as u32]);
        self.reach(slots);
    }

    /// Adds member `k` (a far instance of a group planned on the CPU), joined to the
    /// last group where it follows it and that holds fewer than [`GROUP`].
    pub fn add_member(&mut self, k: usize, slots: Range<usize>) {
        let k = k as u32;
        match self.groups.last_mut() {
            Some([start, end]) if *end == k && ((k - *start) as usize) < GROUP => *end += 1,
            _ => self.groups.push([k, k + 1]),
        }
        self.reach(slots);
    }

    /// Appends `other`'s groups.
    pub fn join(&mut self, other: FarPlan) {
        self.groups.extend(other.groups);
        if let Some(slots) = other.slots {
            self.reach(slots);
        }
    }

    fn reach(&mut self, slots: Range<usize>) {
        self.slots = Some(match self.slots.take() {
            Some(s) => s.start.min(slots.start)..s.end.max(slots.end),
            None => slots,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn far_members_join_runs_of_at_most_a_group() {
        let mut plan = FarPlan::default();
        plan.add(0..64, 10..12);
        for k in 64..64 + 70 {
            plan.add_member(k, 11..14);
        }
        plan.add_member(200, 5..7);
        // 64 + 6 consecutive members: a run of 64, one of 6, then one alone.
        assert_eq!(plan.groups, [[0, 64], [64, 128], [128, 134], [200, 201]]);
        assert!(plan.groups.iter().all(|[a, b]| (b - a) as usize <= GROUP));
        assert_eq!(plan.slots, Some(5..14));
    }
}
