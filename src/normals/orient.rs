//! Consistent orientation of normals.
//!
//! [`orient_mst`] (Hoppe et al. 1992): on the symmetric k-nearest-neighbour graph, a minimum
//! spanning tree with edge cost `1 - |n_i . n_j|` is grown from a point whose outward direction is
//! known, and each normal is flipped to agree with its parent's. The cost also includes
//! `|n_i . e| + |n_j . e|` (e: the unit edge direction), which is large for edges that jump across
//! a thin part (from one side of a sheet to the other) and small along a surface, so the tree
//! prefers to propagate along the surface. The root of every connected component is its extreme
//! point along one of the axes, whose outward normal must point along that axis (the global
//! outward check).
//!
//! [`repair_flips`] flips normals that disagree with most of their neighbours (for normals that
//! came with the input).

use crate::spatial::KdTree;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Symmetric k-nearest-neighbour graph as compressed rows.
fn knn_graph(points: &[Point3<f64>], kd: &KdTree, k: usize) -> (Vec<u32>, Vec<u32>) {
    let lists: Vec<Vec<u32>> = points
        .par_iter()
        .map(|p| {
            kd.knn(p, k + 1)
                .into_iter()
                .map(|(j, _)| j as u32)
                .collect()
        })
        .collect();
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(points.len() * k * 2);
    for (i, l) in lists.iter().enumerate() {
        for &j in l {
            if j as usize != i {
                pairs.push((i as u32, j));
                pairs.push((j, i as u32));
            }
        }
    }
    pairs.par_sort_unstable();
    pairs.dedup();
    let mut start = vec![0u32; points.len() + 1];
    for &(i, _) in &pairs {
        start[i as usize + 1] += 1;
    }
    for i in 0..points.len() {
        start[i + 1] += start[i];
    }
    (start, pairs.into_iter().map(|(_, j)| j).collect())
}

/// Orients `normals` consistently (see the module docs); zero normals are left as they are and do
/// not propagate. Returns the number of connected components of the neighbour graph.
pub fn orient_mst(
    points: &[Point3<f64>],
    normals: &mut [Vector3<f64>],
    kd: &KdTree,
    k: usize,
) -> usize {
    let n = points.len();
    if n == 0 || normals.len() != n {
        return 0;
    }
    let (start, adj) = knn_graph(points, kd, k.max(3));
    let nb = |i: usize| &adj[start[i] as usize..start[i + 1] as usize];
    // Components (BFS); each gets as root the one of its six extreme points (largest and
    // smallest x, y, z) whose normal is best aligned with its axis, oriented outwards there.
    let mut comp = vec![u32::MAX; n];
    let mut roots: Vec<(usize, Vector3<f64>)> = Vec::new();
    for s in 0..n {
        if comp[s] != u32::MAX {
            continue;
        }
        let id = roots.len() as u32;
        let mut stack = vec![s];
        comp[s] = id;
        let mut ext = [s; 6];
        while let Some(i) = stack.pop() {
            for a in 0..3 {
                let (x, hi, lo) = (
                    points[i][a],
                    points[ext[2 * a]][a],
                    points[ext[2 * a + 1]][a],
                );
                if x > hi || (x == hi && i < ext[2 * a]) {
                    ext[2 * a] = i;
                }
                if x < lo || (x == lo && i < ext[2 * a + 1]) {
                    ext[2 * a + 1] = i;
                }
            }
            for &j in nb(i) {
                if comp[j as usize] == u32::MAX {
                    comp[j as usize] = id;
                    stack.push(j as usize);
                }
            }
        }
        let mut best = (ext[0], Vector3::x(), -1.0);
        for (e, &i) in ext.iter().enumerate() {
            let mut dir = Vector3::zeros();
            dir[e / 2] = if e % 2 == 0 { 1.0 } else { -1.0 };
            let align = normals[i].dot(&dir).abs();
            if align > best.2 {
                best = (i, dir, align);
            }
        }
        roots.push((best.0, best.1));
    }
    let cost = |i: usize, j: usize, normals: &[Vector3<f64>]| -> f64 {
        let (a, b) = (normals[i], normals[j]);
        let e = (points[j] - points[i]).try_normalize(1e-300);
        let geo = e.map_or(0.0, |e| a.dot(&e).abs() + b.dot(&e).abs());
        (1.0 - a.dot(&b).abs()).max(0.0) + 0.5 * geo
    };
    let mut done = vec![false; n];
    for &(root, outward) in &roots {
        if normals[root].dot(&outward) < 0.0 {
            normals[root] = -normals[root];
        }
        // Prim's algorithm; ties broken by indices so the tree is deterministic.
        let mut heap: BinaryHeap<Reverse<(u64, u32, u32)>> = BinaryHeap::new();
        heap.push(Reverse((0, root as u32, root as u32)));
        while let Some(Reverse((_, parent, v))) = heap.pop() {
            let v = v as usize;
            if done[v] {
                continue;
            }
            done[v] = true;
            let p = parent as usize;
            if p != v && normals[p].dot(&normals[v]) < 0.0 {
                normals[v] = -normals[v];
            }
            // Zero normals do not carry an orientation further.
            let source = if normals[v].norm_squared() > 0.0 {
                v
            } else {
                p
            };
            for &j in nb(v) {
                if !done[j as usize] {
                    let c = cost(v, j as usize, normals);
                    heap.push(Reverse((c.to_bits(), source as u32, j)));
                }
            }
        }
    }
    roots.len()
}

/// Flips every normal whose `k` nearest neighbours mostly point the other way (one Jacobi pass
/// over the input orientation). Returns how many were flipped.
pub fn repair_flips(
    points: &[Point3<f64>],
    normals: &mut [Vector3<f64>],
    kd: &KdTree,
    k: usize,
) -> usize {
    let flips: Vec<bool> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut agree = 0i64;
            for (j, _) in kd.knn(p, k + 1) {
                if j != i {
                    let d = normals[i].dot(&normals[j]);
                    agree += (d > 0.0) as i64 - (d < 0.0) as i64;
                }
            }
            agree < 0
        })
        .collect();
    let mut count = 0;
    for (n, f) in normals.iter_mut().zip(flips) {
        if f {
            *n = -*n;
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::normals::pca::estimate_normals;

    fn torus(n: usize) -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n / 3 {
                let (u, w) = (
                    i as f64 / n as f64 * std::f64::consts::TAU,
                    j as f64 / (n / 3) as f64 * std::f64::consts::TAU,
                );
                let r = 1.0 + 0.3 * w.cos();
                v.push(Point3::new(r * u.cos(), r * u.sin(), 0.3 * w.sin()));
            }
        }
        v
    }

    fn torus_normal(p: &Point3<f64>) -> Vector3<f64> {
        let c = Vector3::new(p.x, p.y, 0.0).normalize();
        (p.coords - c).normalize()
    }

    #[test]
    fn mst_orients_a_torus_outwards() {
        let pts = torus(120);
        let kd = KdTree::build(&pts).unwrap();
        let mut n = estimate_normals(&pts, &kd, 10);
        let comps = orient_mst(&pts, &mut n, &kd, 10);
        assert_eq!(comps, 1);
        for (p, x) in pts.iter().zip(&n) {
            assert!(x.dot(&torus_normal(p)) > 0.9);
        }
    }

    #[test]
    fn thin_plate_keeps_two_sides_apart() {
        // Two parallel sheets 0.05 apart (spacing 0.04), joined along one rounded edge.
        let mut pts = Vec::new();
        let mut truth = Vec::new();
        for i in 0..50 {
            for j in 0..25 {
                let (x, y) = (i as f64 * 0.04, j as f64 * 0.04);
                pts.push(Point3::new(x, y, 0.025));
                truth.push(Vector3::z());
                pts.push(Point3::new(x, y, -0.025));
                truth.push(-Vector3::z());
            }
            for a in 1..4 {
                let t = std::f64::consts::PI * (0.5 - a as f64 / 4.0);
                pts.push(Point3::new(
                    i as f64 * 0.04,
                    0.96 + 0.025 * t.cos(),
                    0.025 * t.sin(),
                ));
                truth.push(Vector3::new(0.0, t.cos(), t.sin()));
            }
        }
        let kd = KdTree::build(&pts).unwrap();
        let mut n = estimate_normals(&pts, &kd, 8);
        orient_mst(&pts, &mut n, &kd, 8);
        let wrong = n.iter().zip(&truth).filter(|(a, b)| a.dot(b) < 0.0).count();
        assert!(wrong * 50 < pts.len(), "{wrong} of {}", pts.len());
    }

    #[test]
    fn isolated_flips_are_repaired() {
        let pts = torus(90);
        let kd = KdTree::build(&pts).unwrap();
        let mut n: Vec<_> = pts.iter().map(torus_normal).collect();
        for i in (0..n.len()).step_by(17) {
            n[i] = -n[i];
        }
        let flipped = repair_flips(&pts, &mut n, &kd, 8);
        assert!(flipped > 0);
        for (p, x) in pts.iter().zip(&n) {
            assert!(x.dot(&torus_normal(p)) > 0.0);
        }
    }
}
