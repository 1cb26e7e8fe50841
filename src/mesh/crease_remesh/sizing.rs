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

use crate::spatial::KdTree;
use nalgebra::Point3;
use std::collections::HashMap;

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

    /// Crease samples finer than L.
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
}
