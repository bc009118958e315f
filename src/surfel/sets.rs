//! Disjoint sets of `0..n` (union–find with path halving), each named by its least
//! member: the connected pieces of a graph given as its edges, one join each.

pub struct Sets {
    /// Each member's parent, a lesser member or itself (a root, the set's name).
    parent: Vec<u32>,
}

impl Sets {
    /// `n` sets of one member each; `n` fits in a u32 (members are vertex indices).
    pub fn new(n: usize) -> Sets {
        debug_assert!(n <= u32::MAX as usize + 1);
        Sets {
            parent: (0..n as u64).map(|k| k as u32).collect(),
        }
    }

    /// The name of `k`'s set: its least member.
    pub fn root(&mut self, k: usize) -> usize {
        let mut k = k as u32;
        while self.parent[k as usize] != k {
            let grand = self.parent[self.parent[k as usize] as usize];
            self.parent[k as usize] = grand;
            k = grand;
        }
        k as usize
    }

    /// Joins the sets of `a` and `b`.
    pub fn join(&mut self, a: usize, b: usize) {
        let (a, b) = (self.root(a), self.root(b));
        self.parent[a.max(b)] = a.min(b) as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joined_members_share_the_least_as_their_name() {
        let mut sets = Sets::new(6);
        sets.join(4, 2);
        sets.join(5, 4);
        sets.join(1, 3);
        let names: Vec<usize> = (0..6).map(|k| sets.root(k)).collect();
        assert_eq!(names, [0, 1, 2, 1, 2, 2]);
    }
}
