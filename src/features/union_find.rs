//! Disjoint sets (union-find with path halving), for grouping faces, points and regions.
//! Roots are always the smallest member, so the grouping is deterministic whatever the order
//! of the unions.

/// Disjoint sets over `0..n`.
#[derive(Debug, Clone)]
pub struct DisjointSets {
    parent: Vec<u32>,
}

impl DisjointSets {
    /// `n` singletons.
    pub fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n as u32).collect(),
        }
    }

    /// The smallest member of `i`'s set.
    pub fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let p = self.parent[i as usize];
            self.parent[i as usize] = self.parent[p as usize];
            i = p;
        }
        i
    }

    /// Joins the sets of `a` and `b`; true when they were apart.
    pub fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.parent[ra.max(rb) as usize] = ra.min(rb);
        true
    }

    /// Set id per element, numbered 0.. in order of first appearance, and the number of sets.
    pub fn labels(&mut self) -> (Vec<u32>, usize) {
        let n = self.parent.len();
        let mut id = vec![u32::MAX; n];
        let mut out = vec![0u32; n];
        let mut count = 0u32;
        for (i, o) in out.iter_mut().enumerate() {
            let r = self.find(i as u32) as usize;
            if id[r] == u32::MAX {
                id[r] = count;
                count += 1;
            }
            *o = id[r];
        }
        (out, count as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_and_numbers_in_order() {
        let mut d = DisjointSets::new(6);
        assert!(d.union(4, 1));
        assert!(d.union(5, 3));
        assert!(!d.union(1, 4));
        assert!(d.union(3, 0));
        let (l, n) = d.labels();
        assert_eq!(n, 3);
        assert_eq!(l, vec![0, 1, 2, 0, 1, 0]);
    }
}
