//! A target edge length that shrinks along curved creases and grows gradually away from them
//! (the sizing field of adaptive remeshing, Dunyach et al. 2013, "Adaptive remeshing for
//! real-time mesh deformation", with the crease's curvature in place of the surface's).
//!
//! A crease of radius R drawn with chords of length s is off by the sagitta s^2 / (8 R), so
//! within a tolerance t it needs s_c = sqrt(8 R t) (clamped to [L / 16, L]). R is measured at
//! every input crease vertex v as the radius of the circle through v and the two crease points
//! a half window w away along the crease (w = L / 2 each way; the walk stops at corners and
//! pinned turns: on a crease between two corners, a fillet's quarter circle, the ends serve;
//! a closed crease shorter than a window ends its walk where it started). The size at x is
//! then
//!
//! s(x) = min(L, min_c (s_c + g |x - c|)),
//!
//! over the crease samples c, so that it changes by at most g per unit length (g = grade):
//! the triangles beside a finely split crease grow to L over a few rings instead of fanning
//! out to it in one.
//!
//! Inside a region the same holds with the surface's curvature ([`surface_samples`]): across
//! an input edge whose two triangles lie in one region, with unit normals n_a, n_b and
//! centroids c_a, c_b, the normal curvature is about k = |n_a - n_b| / |c_a - c_b| (the normal
//! turns by the angle theta = 2 asin(|n_a - n_b| / 2) over that distance); a vertex takes the
//! mean k of its edges, averaged over its ring twice (against the noise of a fine mesh; a
//! cylinder's vertex then gets about 2 / (pi R) rather than 1 / R, the mean over directions
//! of its normal curvature), and a chord of length s across a surface of curvature k is off
//! by k s^2 / 8, so within t it needs s = sqrt(8 t / k). Computed once on the input, this
//! replaces a test of every edge's chord against the input triangles in every pass.

use crate::spatial::KdTree;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// Rounds of averaging the surface curvature over a vertex's ring ([`surface_samples`]).
const SMOOTHING_ROUNDS: usize = 2;

/// Crease samples examined per query.
const CANDIDATES: usize = 16;

/// The sizing field.
pub struct Sizing {
    samples: Vec<(Point3<f64>, f64)>,
    tree: Option<KdTree>,
    target: f64,
    grade: f64,
}

impl Sizing {
    /// From the input's crease edges `creases` (vertex pairs into `positions`), with
    /// `stops[v]` true where a walk along a crease must stop (corners, pinned turns); `target`
    /// L, `tolerance` t, `grade` g, `min_fraction` the smallest size as a fraction of L.
    pub fn new(
        positions: &[Point3<f64>],
        creases: &[[u32; 2]],
        stops: &[bool],
        target: f64,
        tolerance: f64,
        grade: f64,
        min_fraction: f64,
    ) -> Sizing {
        let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
        for &[a, b] in creases {
            next.entry(a).or_default().push(b);
            next.entry(b).or_default().push(a);
        }
        let half = 0.5 * target;
        // The crease point a half window from v through `first`, or the last one before a
        // stop (a short crease between two corners: a fillet's quarter circle).
        let walk = |v: u32, first: u32| -> Point3<f64> {
            let (mut prev, mut at, mut length) = (v, first, 0.0);
            loop {
                length += (positions[at as usize] - positions[prev as usize]).norm();
                let ns = next.get(&at).map_or(&[][..], |n| n.as_slice());
                let stop = stops.get(at as usize).copied().unwrap_or(true);
                if length >= half || stop || ns.len() != 2 || at == v {
                    return positions[at as usize];
                }
                let n = if ns[0] == prev { ns[1] } else { ns[0] };
                (prev, at) = (at, n);
            }
        };
        let mut samples = Vec::new();
        for v in 0..positions.len() as u32 {
            let Some(ns) = next.get(&v) else {
                continue;
            };
            if ns.len() != 2 || stops.get(v as usize).copied().unwrap_or(true) {
                continue;
            }
            let (a, b) = (walk(v, ns[0]), walk(v, ns[1]));
            let p = positions[v as usize];
            let r = circumradius(&a, &p, &b);
            let size = (8.0 * r * tolerance)
                .sqrt()
                .clamp(target * min_fraction, target);
            if size < target {
                samples.push((p, size));
            }
        }
        let points: Vec<Point3<f64>> = samples.iter().map(|s| s.0).collect();
        let tree = KdTree::build(&points).ok();
        Sizing {
            samples,
            tree,
            target,
            grade,
        }
    }

    /// Adds `extra` samples (a point and its size) to the field.
    pub fn with_samples(mut self, extra: Vec<(Point3<f64>, f64)>) -> Sizing {
        self.samples.extend(extra);
        let points: Vec<Point3<f64>> = self.samples.iter().map(|s| s.0).collect();
        self.tree = KdTree::build(&points).ok();
        self
    }

    /// Samples finer than L.
    pub fn samples(&self) -> usize {
        self.samples.len()
    }

    /// The target length at `x`.
    pub fn at(&self, x: &Point3<f64>) -> f64 {
        let Some(tree) = &self.tree else {
            return self.target;
        };
        tree.knn(x, CANDIDATES)
            .into_iter()
            .map(|(i, d)| self.samples[i].1 + self.grade * d)
            .fold(self.target, f64::min)
    }
}

/// The samples of the surface's curvature inside the regions (module doc): every vertex of
/// `triangles` (labelled `labels`, their undirected edges -> their one or two triangles in
/// `edges`, the remesh's topology of the input) whose size sqrt(8 t / k) under `tolerance` t
/// is below `target` (clamped to `min_fraction` of it).
pub(super) fn surface_samples(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    labels: &[u32],
    edges: &HashMap<(u32, u32), [u32; 2]>,
    target: f64,
    tolerance: f64,
    min_fraction: f64,
) -> Vec<(Point3<f64>, f64)> {
    let unit = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        (b - a).cross(&(c - a)).try_normalize(0.0)
    };
    let centroid = |t: &[u32; 3]| {
        Point3::from(
            t.iter()
                .map(|&v| positions[v as usize].coords)
                .sum::<Vector3<f64>>()
                / 3.0,
        )
    };
    let mut sum = vec![0.0f64; positions.len()];
    let mut count = vec![0usize; positions.len()];
    let mut ring: Vec<(u32, u32)> = Vec::new();
    for (&(a, b), &[f, g]) in edges {
        if g == super::NONE || labels.get(f as usize) != labels.get(g as usize) {
            continue;
        }
        let (f, g) = (f as usize, g as usize);
        let (Some(nf), Some(ng)) = (unit(&triangles[f]), unit(&triangles[g])) else {
            continue;
        };
        let d = (centroid(&triangles[f]) - centroid(&triangles[g])).norm();
        if d <= 0.0 {
            continue;
        }
        let k = (nf - ng).norm() / d;
        for v in [a, b] {
            sum[v as usize] += k;
            count[v as usize] += 1;
        }
        ring.push((a, b));
    }
    let mut curvature: Vec<f64> = sum
        .iter()
        .zip(&count)
        .map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
        .collect();
    // The noise of a fine mesh (a noisy cloud's marching cubes) makes single edges bend:
    // averaged over the vertex's region edges and then over its ring, twice.
    for _ in 0..SMOOTHING_ROUNDS {
        let mut sum = curvature.clone();
        let mut count = vec![1usize; positions.len()];
        for &(a, b) in &ring {
            sum[a as usize] += curvature[b as usize];
            sum[b as usize] += curvature[a as usize];
            count[a as usize] += 1;
            count[b as usize] += 1;
        }
        curvature = sum.iter().zip(&count).map(|(s, &c)| s / c as f64).collect();
    }
    curvature
        .iter()
        .zip(positions)
        .filter(|(k, _)| **k > 0.0)
        .filter_map(|(k, p)| {
            let size = (8.0 * tolerance / k)
                .sqrt()
                .clamp(target * min_fraction, target);
            (size < target).then_some((*p, size))
        })
        .collect()
}

/// Radius of the circle through a, b, c: |ab| |bc| |ca| / (4 area); infinite when they are
/// collinear.
fn circumradius(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> f64 {
    let twice_area = (b - a).cross(&(c - a)).norm();
    if twice_area <= 0.0 {
        return f64::INFINITY;
    }
    (b - a).norm() * (c - b).norm() * (a - c).norm() / (2.0 * twice_area)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circle of radius 2 as a closed crease of 200 edges, and a straight one: the circle's
    /// samples get sqrt(8 R t), the line none, and the size grows by g away from the circle.
    #[test]
    fn circle_gets_its_chord_size_and_a_line_none() {
        let n = 200;
        let mut positions: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                Point3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0)
            })
            .collect();
        let mut creases: Vec<[u32; 2]> = (0..n as u32).map(|i| [i, (i + 1) % n as u32]).collect();
        for i in 0..50 {
            positions.push(Point3::new(10.0 + 0.1 * i as f64, 0.0, 0.0));
            if i > 0 {
                creases.push([n as u32 + i - 1, n as u32 + i]);
            }
        }
        let stops = vec![false; positions.len()];
        let (l, t, g) = (1.0, 1e-3, 0.5);
        let s = Sizing::new(&positions, &creases, &stops, l, t, g, 1.0 / 16.0);
        assert_eq!(s.samples(), n);
        let want = (8.0 * 2.0 * t).sqrt();
        let on = s.at(&Point3::new(2.0, 0.0, 0.0));
        assert!((on - want).abs() < 1e-3 * want, "{on} {want}");
        let off = s.at(&Point3::new(2.0, 0.0, 0.5));
        assert!((off - (want + g * 0.5)).abs() < 1e-3, "{off}");
        assert_eq!(s.at(&Point3::new(12.0, 0.0, 0.0)), l);
        assert_eq!(s.at(&Point3::new(0.0, 0.0, 30.0)), l);
    }

    /// A grid of `nu` x `nv` quads (two triangles each) through `at(u, v)`, labelled `label`,
    /// appended to `positions` and `triangles`.
    fn grid(
        positions: &mut Vec<Point3<f64>>,
        triangles: &mut Vec<[u32; 3]>,
        labels: &mut Vec<u32>,
        (nu, nv, label): (usize, usize, u32),
        at: impl Fn(f64, f64) -> Point3<f64>,
    ) {
        let base = positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                positions.push(at(i as f64 / nu as f64, j as f64 / nv as f64));
            }
        }
        let id = |i: usize, j: usize| base + (j * (nu + 1) + i) as u32;
        for j in 0..nv {
            for i in 0..nu {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        labels.resize(triangles.len(), label);
    }

    /// Half a cylinder of radius 2 (region 0) and a flat strip (region 1): the cylinder's
    /// inner vertices get sqrt(8 t / k), the plane none. On this grid the quads between two
    /// generators are flat, so only the edges along the generators see the curvature: a third
    /// of a vertex's edges, k between 1 / (3 R) and 1 / R (about 2 / (pi R) on an even mesh,
    /// module doc).
    #[test]
    fn a_cylinder_gets_its_chord_size_and_a_plane_none() {
        let (r, t, target) = (2.0, 1e-3, 1.0);
        let (mut p, mut tri, mut lab) = (Vec::new(), Vec::new(), Vec::new());
        grid(&mut p, &mut tri, &mut lab, (40, 20, 0), |u, v| {
            let a = std::f64::consts::PI * u;
            Point3::new(r * a.cos(), r * a.sin(), 4.0 * v)
        });
        let cylinder = p.len();
        grid(&mut p, &mut tri, &mut lab, (20, 20, 1), |u, v| {
            Point3::new(10.0 + 4.0 * u, 0.0, 4.0 * v)
        });
        let mesh = super::super::LabelledMesh {
            positions: p.clone(),
            triangles: tri.clone(),
            labels: lab.clone(),
        };
        let topo = super::super::State::new(&mesh).topo();
        let samples = surface_samples(&p, &tri, &lab, &topo.edges, target, t, 1.0 / 16.0);
        assert!(
            samples.iter().all(|(q, _)| q.x < 5.0),
            "a plane vertex sampled"
        );
        // All but two corners, whose edges are boundary edges or the diagonal of a flat quad
        // (two generators of a cylinder span a plane).
        assert_eq!(samples.len(), cylinder - 2);
        let (lo, hi) = ((8.0 * t * r).sqrt(), (8.0 * t * 3.0 * r).sqrt());
        let mut inner = 0;
        for (q, size) in &samples {
            if q.z > 0.5 && q.z < 3.5 && q.y > 0.5 {
                inner += 1;
                assert!(*size > lo && *size < hi, "{q} {size} {lo} {hi}");
            }
        }
        assert!(inner > 300, "{inner}");
    }
}
