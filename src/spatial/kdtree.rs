//! k-d tree over `Point3<f64>`: a thin wrapper over kiddo's immutable tree for the three queries
//! the pipeline needs (nearest point, k nearest, all within a radius). Items are the indices of
//! the points in the slice the tree was built from.

use crate::{Error, Result};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Point3;
use std::num::NonZeroUsize;

/// A static k-d tree over a point set.
pub struct KdTree {
    tree: ImmutableKdTree<f64, 3>,
    len: usize,
}

impl std::fmt::Debug for KdTree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KdTree").field("len", &self.len).finish()
    }
}

fn arr(p: &Point3<f64>) -> [f64; 3] {
    [p.x, p.y, p.z]
}

impl KdTree {
    /// Builds the tree. Errors on an empty set, non-finite coordinates, or more than `u32::MAX`
    /// points.
    pub fn build(points: &[Point3<f64>]) -> Result<KdTree> {
        if points.is_empty() {
            return Err(Error::Degenerate("k-d tree over no points".into()));
        }
        if points.len() > u32::MAX as usize {
            return Err(Error::Degenerate("too many points for a k-d tree".into()));
        }
        if points
            .iter()
            .any(|p| !p.coords.iter().all(|c| c.is_finite()))
        {
            return Err(Error::Degenerate("non-finite point coordinate".into()));
        }
        let entries: Vec<[f64; 3]> = points.iter().map(arr).collect();
        let tree = ImmutableKdTree::new_from_slice(&entries)
            .map_err(|e| Error::Degenerate(format!("k-d tree construction: {e:?}")))?;
        Ok(KdTree {
            tree,
            len: points.len(),
        })
    }

    /// Number of points in the tree.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false (a tree is never built over no points).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Index of the nearest point and its distance.
    pub fn nearest(&self, q: &Point3<f64>) -> (usize, f64) {
        let r = self
            .tree
            .query(&arr(q))
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        (r.item as usize, r.distance.max(0.0).sqrt())
    }

    /// The `k` nearest points as (index, distance), nearest first (fewer when the tree holds
    /// fewer points).
    pub fn knn(&self, q: &Point3<f64>, k: usize) -> Vec<(usize, f64)> {
        let Some(k) = NonZeroUsize::new(k.min(self.len)) else {
            return Vec::new();
        };
        self.tree
            .query(&arr(q))
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute()
            .into_iter()
            .map(|r| (r.item as usize, r.distance.max(0.0).sqrt()))
            .collect()
    }

    /// Indices of all points within distance `r` of `q` (inclusive), in increasing index order
    /// (deterministic, independent of the tree's traversal).
    pub fn within(&self, q: &Point3<f64>, r: f64) -> Vec<usize> {
        let mut out: Vec<usize> = self
            .tree
            .query(&arr(q))
            .within::<SquaredEuclidean<f64>>(r * r)
            .unsorted()
            .execute()
            .into_iter()
            .map(|r| r.item as usize)
            .collect();
        out.sort_unstable();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                for k in 0..10 {
                    v.push(Point3::new(i as f64, j as f64, k as f64));
                }
            }
        }
        v
    }

    #[test]
    fn queries_match_brute_force() {
        let pts = grid();
        let t = KdTree::build(&pts).unwrap();
        assert_eq!(t.len(), 1000);
        let q = Point3::new(3.2, 4.9, 7.1);
        let (i, d) = t.nearest(&q);
        assert_eq!(pts[i], Point3::new(3.0, 5.0, 7.0));
        assert!((d - (0.04f64 + 0.01 + 0.01).sqrt()).abs() < 1e-12);
        let nn = t.knn(&q, 7);
        assert_eq!(nn.len(), 7);
        assert!(nn.windows(2).all(|w| w[0].1 <= w[1].1));
        let w = t.within(&q, 1.5);
        let brute: Vec<usize> = (0..pts.len())
            .filter(|&i| (pts[i] - q).norm() <= 1.5)
            .collect();
        assert_eq!(w, brute);
    }

    #[test]
    fn rejects_bad_input() {
        assert!(KdTree::build(&[]).is_err());
        assert!(KdTree::build(&[Point3::new(f64::NAN, 0.0, 0.0)]).is_err());
    }

    #[test]
    fn duplicates_are_fine() {
        let pts = vec![Point3::new(1.0, 1.0, 1.0); 500];
        let t = KdTree::build(&pts).unwrap();
        assert_eq!(t.within(&Point3::new(1.0, 1.0, 1.0), 0.1).len(), 500);
        assert_eq!(t.knn(&Point3::origin(), 3).len(), 3);
    }
}
