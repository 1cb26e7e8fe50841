//! Sharp local functions: a domain crossed by a crease (or holding a corner) fits one height
//! polynomial per smooth region ([`crate::features`]) and combines them by max and min
//! (Ohtake, Belyaev, Alexa, Turk, Seidel 2003, "Multi-level partition of unity implicits",
//! section 4, "sharp features"), instead of one smooth function that rounds the edge.
//!
//! Each side i has its own height polynomial f_i (seed 004 eq. 1, or a plane on few points),
//! negative inside. The solid near a **convex** edge is the intersection of the two sides'
//! half-spaces, near a **concave** edge their union:
//!
//! ```text
//! convex:   F = max(f_a, f_b)        concave:  F = min(f_a, f_b)
//! corner:   F = max(f_a, f_b, f_c), min(f_a, f_b, f_c), or mixed:
//!           F = max(f_a, min(f_b, f_c))   (a meets b and c convexly, b and c meet concavely)
//!           F = min(f_a, max(f_b, f_c))   (the opposite)
//! ```
//!
//! Which one is decided from the data: two sides meet convexly when each side's points lie
//! inside the other's half-space (median of f_b over a's points plus median of f_a over b's
//! points below zero), concavely otherwise. Of the three relations at a corner either all agree
//! (max or min of all three) or exactly one pair (b, c) differs, and then side a meets both
//! others the same way: F = outer(f_a, inner(f_b, f_c)).
//!
//! grad F is the gradient of the side that gives the max or min (of the first such side on a
//! tie), so F is only C0 on the crease, where the active side changes: the blend of seed 003
//! eq. 8 carries that into the implicit, which is then C0 along the creases and C2 elsewhere.
//! [`SharpFunction::side_value_and_gradient`] evaluates one side alone (the crease's two
//! surfaces for the net and patch stages, Newton on f_a = f_b = 0).

mod relabel;
mod shared;
mod side;

use super::poly::HeightPoly;
use nalgebra::{Point3, Vector3};
use side::{fit_side, median};

/// Fewest points of one region in a domain for a side of its own.
pub const MIN_SIDE: usize = 4;

/// Most sides of one sharp function (an edge: 2, a corner: 3; more are split further).
pub const MAX_SIDES: usize = 3;

/// Label of a point that belongs to no region (it joins no side).
pub const NO_REGION: u32 = u32::MAX;

/// How two values are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Combine {
    /// Intersection of the insides (a convex edge).
    Max,
    /// Union of the insides (a concave edge).
    Min,
}

impl Combine {
    /// The combined value and which of the two (0 or 1) gave it (the first on a tie).
    #[inline]
    fn pick(self, a: f64, b: f64) -> (f64, usize) {
        let first = match self {
            Combine::Max => a >= b,
            Combine::Min => a <= b,
        };
        if first {
            (a, 0)
        } else {
            (b, 1)
        }
    }
}

/// One side of a sharp function: a region and its height polynomial.
#[derive(Debug, Clone, PartialEq)]
pub struct SharpSide {
    pub region: u32,
    pub poly: HeightPoly,
}

/// F = outer(f_0, inner(f_1, f_2)) over two or three sides (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct SharpFunction {
    sides: Vec<SharpSide>,
    outer: Combine,
    /// With three sides: how sides 1 and 2 combine (equal to `outer` when all three meet the
    /// same way). Unused with two.
    inner: Combine,
}

impl SharpFunction {
    /// A sharp function from its sides (two or three) and how they combine; `None` for another
    /// number of sides.
    pub fn new(sides: Vec<SharpSide>, outer: Combine, inner: Combine) -> Option<SharpFunction> {
        (2..=MAX_SIDES)
            .contains(&sides.len())
            .then_some(SharpFunction {
                sides,
                outer,
                inner,
            })
    }

    /// The sides.
    pub fn sides(&self) -> &[SharpSide] {
        &self.sides
    }

    /// How side 0 combines with the rest, and (three sides) sides 1 and 2 with each other.
    pub fn combination(&self) -> (Combine, Combine) {
        (self.outer, self.inner)
    }

    /// F and which side gives it, from the sides' values.
    #[inline]
    fn pick(&self, v: &[f64]) -> (f64, usize) {
        if v.len() == 2 {
            return self.outer.pick(v[0], v[1]);
        }
        let (r, k) = self.inner.pick(v[1], v[2]);
        let (f, j) = self.outer.pick(v[0], r);
        (f, if j == 0 { 0 } else { 1 + k })
    }

    /// Each side's f_i(x), in the sides' order (the entries past the last side are 0).
    #[inline]
    fn side_values(&self, x: &Point3<f64>) -> [f64; MAX_SIDES] {
        let mut v = [0.0; MAX_SIDES];
        for (vi, s) in v.iter_mut().zip(&self.sides) {
            *vi = s.poly.value(x);
        }
        v
    }

    /// F(x).
    #[inline]
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        self.pick(&self.side_values(x)[..self.sides.len()]).0
    }

    /// F(x) and the gradient of the active side.
    #[inline]
    pub fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let (_, k) = self.pick(&self.side_values(x)[..self.sides.len()]);
        self.sides[k].poly.value_and_gradient(x)
    }

    /// f and grad f of the side of `region` alone, `None` when it is not a side here.
    pub fn side_value_and_gradient(
        &self,
        region: u32,
        x: &Point3<f64>,
    ) -> Option<(f64, Vector3<f64>)> {
        self.sides
            .iter()
            .find(|s| s.region == region)
            .map(|s| s.poly.value_and_gradient(x))
    }

    /// Share of the points whose normal agrees with the function
    /// ([`crate::implicit::local::agrees`], as [`crate::implicit::local::assess`] counts it), where a point
    /// agrees with F when it agrees with the gradient of some side whose value there is within
    /// `tie` of F: on the crease both sides are F, and a point sampled on the crease with the
    /// normal of either face is on the surface as its normal says (its face's side may lose the
    /// max or min to the other by a rounding error, whose gradient is 90 degrees off).
    pub fn normal_agreement(
        &self,
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        tie: f64,
    ) -> f64 {
        self.evaluate(points, normals, normals, tie).1
    }

    /// F and grad F at every point (as [`Self::value_and_gradient`] gives them) and the share
    /// of the points whose normal agrees ([`Self::normal_agreement`]), each side evaluated once
    /// per point: what a crease cell of the octree is assessed by. Each point has two normals,
    /// its own (`normals`) and its region's alone (`side_normals`,
    /// [`crate::features::Segmentation::labels_normals_and_sides`]), and counts as agreeing
    /// when either does. Beside a crease a cloud's estimated normal can be the other face's, or lie along
    /// the crease (the PCA of an L of neighbours whose two least spreads are about equal:
    /// make_parts' wedge.xyz and cornerblock.xyz, four such points in cells of twenty failed
    /// every cell along a stretch of edge, whose smooth fits then cut it, 1.2e-3 and 9.1e-4 of
    /// the diagonal); the one-sided normal is its face's. It in turn is its label's, and a
    /// point relabelled to the other side (module `relabel`) or labelled across the crease
    /// has the wrong one, where its own normal agrees (seed-11 flange.xyz, judged by the
    /// one-sided normals alone: 3.7e-4 -> 9.7e-4).
    pub fn evaluate(
        &self,
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        side_normals: &[Vector3<f64>],
        tie: f64,
    ) -> (Vec<(f64, Vector3<f64>)>, f64) {
        let k = self.sides.len();
        let mut agree = 0usize;
        let values = points
            .iter()
            .zip(normals.iter().zip(side_normals))
            .map(|(x, (n, ns))| {
                let mut v = [0.0; MAX_SIDES];
                let mut vg = [(0.0, Vector3::zeros()); MAX_SIDES];
                for ((vi, gi), s) in v.iter_mut().zip(vg.iter_mut()).zip(&self.sides) {
                    *vi = s.poly.value(x);
                    *gi = s.poly.value_and_gradient(x);
                }
                let (f, active) = self.pick(&v[..k]);
                if vg[..k].iter().any(|(vs, g)| {
                    (vs - f).abs() <= tie
                        && (super::local::agrees(g, n) || super::local::agrees(g, ns))
                }) {
                    agree += 1;
                }
                vg[active]
            })
            .collect();
        let share = if points.is_empty() {
            1.0
        } else {
            agree as f64 / points.len() as f64
        };
        (values, share)
    }

    /// Fits a sharp function to a domain's points: `labels[i]` is the region of `points[i]`
    /// ([`NO_REGION`] for none), `normals` their one-sided unit normals, `scale` the domain's
    /// length scale, `min_normal_cos` the height-function test of [`crate::implicit::poly::Frame::from_normals`]. A
    /// side stays a plane when that leaves none of its points farther than `flat` (a plane
    /// extended past the crease stays where the face is; a quadratic bends away from it).
    /// `None` unless two or three regions hold at least [`MIN_SIDE`] points each and every side
    /// can be fitted (not yet assessed against the tolerance: the caller does that, over all
    /// the points). Points that another side fits and their own does not are given that side's
    /// region and the sides fitted again (module `relabel`); then, at an edge, points on the
    /// crease that the other side cuts into are given to that side too (module `shared`).
    pub fn fit(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        labels: &[u32],
        scale: f64,
        min_normal_cos: f64,
        flat: f64,
    ) -> Option<SharpFunction> {
        let fit = |l: &[u32], extra: &[(u32, usize)]| {
            Self::fit_labelled(points, normals, l, scale, min_normal_cos, flat, extra)
        };
        let first = fit(labels, &[])?;
        let (best, labels) = relabel::refit(first, points, labels, flat, |l| fit(l, &[]));
        Some(
            shared::refit(best, points, normals, &labels, flat, |extra| {
                fit(&labels, extra)
            })
            .1,
        )
    }

    /// [`Self::fit`] from the labels as they are, each side also fitted to the points `extra`
    /// gives it (region, index into `points`: crease points shared, module `shared`).
    fn fit_labelled(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        labels: &[u32],
        scale: f64,
        min_normal_cos: f64,
        flat: f64,
        extra: &[(u32, usize)],
    ) -> Option<SharpFunction> {
        let groups = region_groups(labels, MIN_SIDE);
        if !(2..=MAX_SIDES).contains(&groups.len()) {
            return None;
        }
        let mut sides = Vec::with_capacity(groups.len());
        let mut members = Vec::with_capacity(groups.len());
        for (region, mut idx) in groups {
            idx.extend(extra.iter().filter(|e| e.0 == region).map(|e| e.1));
            let p: Vec<Point3<f64>> = idx.iter().map(|&i| points[i]).collect();
            let n: Vec<Vector3<f64>> = idx.iter().map(|&i| normals[i]).collect();
            let poly = fit_side(&p, &n, scale, min_normal_cos, flat)?;
            sides.push(SharpSide { region, poly });
            members.push(p);
        }
        // Relation of each pair: convex when each side's points lie inside the other.
        let convex = |i: usize, j: usize| -> bool {
            let inside =
                |a: usize, b: usize| median(members[a].iter().map(|p| sides[b].poly.value(p)));
            inside(i, j) + inside(j, i) < 0.0
        };
        let kind = |c: bool| if c { Combine::Max } else { Combine::Min };
        if sides.len() == 2 {
            let c = kind(convex(0, 1));
            return SharpFunction::new(sides, c, c);
        }
        let (r01, r02, r12) = (convex(0, 1), convex(0, 2), convex(1, 2));
        // The side whose two relations agree goes first (module doc).
        let first = if r01 == r02 {
            0
        } else if r01 == r12 {
            1
        } else {
            2
        };
        let (outer, inner) = match first {
            0 => (kind(r01), kind(r12)),
            1 => (kind(r01), kind(r02)),
            _ => (kind(r02), kind(r01)),
        };
        let by_medians = (first, outer, inner);
        let (first, outer, inner) = corner_structure(&sides, points, flat, by_medians);
        sides.swap(0, first);
        SharpFunction::new(sides, outer, inner)
    }
}

/// How three sides combine at a corner: `(first, outer, inner)` for
/// F = outer(f_first, inner(f_b, f_c)), the other two sides in their order. The structure the
/// pairwise median tests give (`by_medians`) is kept when it leaves no point farther than
/// `flat`; otherwise the one of the eight (max or min of all three, or one side combined
/// one way with the other two combined the other way) with the smallest largest residual
/// over all the domain's `points`. The medians fail at a mixed corner whose domain lies
/// mostly on one side of the concave edge: a V groove's root meeting an end face, the
/// domain over one flank; there the end face's points lie outside the other flank's plane as
/// often as inside it, and the pair was taken for concave (make_parts-style V block from its
/// mesh: 0.35 mm off where the groove meets the end face).
fn corner_structure(
    sides: &[SharpSide],
    points: &[Point3<f64>],
    flat: f64,
    by_medians: (usize, Combine, Combine),
) -> (usize, Combine, Combine) {
    let values: Vec<[f64; 3]> = points
        .iter()
        .map(|x| [0, 1, 2].map(|k| sides[k].poly.value(x)))
        .collect();
    let worst = |(first, outer, inner): (usize, Combine, Combine)| -> f64 {
        let (b, c) = match first {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        values
            .iter()
            .map(|v| outer.pick(v[first], inner.pick(v[b], v[c]).0).0.abs())
            .fold(0.0, f64::max)
    };
    let mut best = (by_medians, worst(by_medians));
    if best.1 <= flat {
        return by_medians;
    }
    for first in 0..3 {
        for (outer, inner) in [
            (Combine::Max, Combine::Max),
            (Combine::Min, Combine::Min),
            (Combine::Max, Combine::Min),
            (Combine::Min, Combine::Max),
        ] {
            if outer == inner && first > 0 {
                continue;
            }
            let w = worst((first, outer, inner));
            if w < best.1 {
                best = ((first, outer, inner), w);
            }
        }
    }
    best.0
}

/// A fit and its sum of F(x)^2 over `points`, the measure by which the refits of modules
/// `relabel` and `shared` are kept.
type Scored = (f64, SharpFunction);

/// `f` with its sum of F(x)^2 over `points`.
fn scored(f: SharpFunction, points: &[Point3<f64>]) -> Scored {
    (points.iter().map(|x| f.value(x).powi(2)).sum(), f)
}

/// Up to `rounds` refits of `best`: `step` gives the next state (labels, shared points) and the
/// function fitted from it, or `None` to stop; a refit is kept, with its state, while its sum
/// of F(x)^2 over `points` drops, and the first that does not ends the rounds.
fn improve<S>(
    mut best: Scored,
    mut state: S,
    points: &[Point3<f64>],
    rounds: usize,
    mut step: impl FnMut(&SharpFunction, &S) -> Option<(S, SharpFunction)>,
) -> (Scored, S) {
    for _ in 0..rounds {
        let Some((next_state, next)) = step(&best.1, &state) else {
            break;
        };
        let next = scored(next, points);
        if next.0 >= best.0 {
            break;
        }
        best = next;
        state = next_state;
    }
    (best, state)
}

/// Regions with at least `min` of `labels`, with the indices of their points, largest first
/// (ties by region id).
pub fn region_groups(labels: &[u32], min: usize) -> Vec<(u32, Vec<usize>)> {
    let mut by: std::collections::BTreeMap<u32, Vec<usize>> = std::collections::BTreeMap::new();
    for (i, &l) in labels.iter().enumerate() {
        if l != NO_REGION {
            by.entry(l).or_default().push(i);
        }
    }
    let mut out: Vec<(u32, Vec<usize>)> = by.into_iter().filter(|(_, v)| v.len() >= min).collect();
    out.sort_by(|a, b| b.1.len().cmp(&a.1.len()).then(a.0.cmp(&b.0)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the faces of the solid { x <= 0 } ∩ { y <= 0 } (convex edge along z) or its
    /// complement's boundary (concave), within `r` of the edge, with normals and labels.
    fn edge(convex: bool, r: f64, k: usize) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>, Vec<u32>) {
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        let s = if convex { 1.0 } else { -1.0 };
        for i in 1..=k {
            for j in 0..k {
                let a = r * i as f64 / k as f64;
                let z = r * (2.0 * j as f64 / k as f64 - 1.0);
                // Face x = 0 (region 0) over y < 0, face y = 0 (region 1) over x < 0.
                p.push(Point3::new(0.0, -a, z));
                n.push(Vector3::x() * s);
                l.push(0);
                p.push(Point3::new(-a, 0.0, z));
                n.push(Vector3::y() * s);
                l.push(1);
            }
        }
        (p, n, l)
    }

    #[test]
    fn convex_edge_is_the_max_of_its_faces() {
        let (p, n, l) = edge(true, 1.0, 8);
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        assert_eq!(f.combination().0, Combine::Max);
        // Zero on both faces, up to the edge.
        for q in &p {
            assert!(f.value(q).abs() < 1e-9, "{q}: {}", f.value(q));
        }
        // Inside (x, y < 0) negative, outside positive, the distance to the solid beyond the
        // edge's corner region.
        assert!((f.value(&Point3::new(-0.2, -0.3, 0.1)) + 0.2).abs() < 1e-9);
        assert!((f.value(&Point3::new(0.3, 0.1, 0.0)) - 0.3).abs() < 1e-9);
        // The gradient is one face's normal, whichever is nearer.
        let (_, g) = f.value_and_gradient(&Point3::new(0.1, -0.5, 0.0));
        assert!((g - Vector3::x()).norm() < 1e-9, "{g}");
        let (_, g) = f.value_and_gradient(&Point3::new(-0.5, 0.1, 0.0));
        assert!((g - Vector3::y()).norm() < 1e-9, "{g}");
        // Each side alone.
        let (v, g) = f
            .side_value_and_gradient(1, &Point3::new(0.3, 0.2, 0.0))
            .unwrap();
        assert!((v - 0.2).abs() < 1e-9 && (g - Vector3::y()).norm() < 1e-9);
        assert!(f.side_value_and_gradient(7, &Point3::origin()).is_none());
    }

    #[test]
    fn a_side_keeps_its_frame_when_a_few_normals_cross_the_edge() {
        // Two of face x = 0's 64 points carry face y = 0's normal (estimated across the edge):
        // the side is fitted from the others, and F is still the max of the two faces.
        let (p, mut n, l) = edge(true, 1.0, 8);
        for k in [0, 2] {
            assert_eq!(l[k], 0);
            n[k] = Vector3::y();
        }
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.5, 1e-9).expect("a sharp function");
        assert_eq!(f.combination().0, Combine::Max);
        for q in &p {
            assert!(f.value(q).abs() < 1e-9, "{q}: {}", f.value(q));
        }
        // A quarter of the side's normals across the edge is no side (no frame).
        let (p, mut n, l) = edge(true, 1.0, 8);
        for k in (0..p.len()).filter(|&k| l[k] == 0).step_by(4) {
            n[k] = Vector3::y();
        }
        assert!(SharpFunction::fit(&p, &n, &l, 1.0, 0.5, 1e-9).is_none());
    }

    #[test]
    fn points_on_the_edge_agree_with_the_side_of_their_own_face() {
        // Samples on the edge itself (x = y = 0), half of them with the normal of face y = 0:
        // at the tie F takes face x = 0's gradient, 90 degrees off those normals.
        let (mut p, mut n, mut l) = edge(true, 1.0, 8);
        for j in 0..8 {
            let z = j as f64 / 8.0 - 0.5;
            p.extend([Point3::new(0.0, 0.0, z), Point3::new(0.0, 0.0, z)]);
            n.extend([Vector3::x(), Vector3::y()]);
            l.extend([0, 1]);
        }
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        let plain = crate::implicit::local::assess(
            crate::implicit::local::LocalFunction::Sharp(f.clone()),
            &p,
            &n,
        );
        assert!(plain.normal_agreement < 1.0, "{}", plain.normal_agreement);
        assert_eq!(f.normal_agreement(&p, &n, 1e-6), 1.0);
        // A normal that agrees with no side near the point still disagrees.
        let odd = [Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, -0.5, 0.0)];
        let m = [-Vector3::y(), Vector3::y()];
        assert_eq!(f.normal_agreement(&odd, &m, 1e-6), 0.0);
    }

    #[test]
    fn a_point_agrees_when_its_own_or_its_one_sided_normal_does() {
        let (p, n, l) = edge(true, 1.0, 8);
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        // On face x = 0 beside the edge: an estimate along the edge (z) or toward the other
        // face (y), with the face's own normal (x) as the one-sided one, and the other way.
        let q = [Point3::new(0.0, -0.05, 0.0); 4];
        let own = [Vector3::z(), Vector3::y(), Vector3::x(), Vector3::x()];
        let one_sided = [Vector3::x(), Vector3::x(), Vector3::z(), Vector3::y()];
        assert_eq!(f.evaluate(&q, &own, &one_sided, 1e-6).1, 1.0);
        // Neither agreeing: against the fit.
        assert_eq!(f.evaluate(&q, &own[..2], &own[..2], 1e-6).1, 0.0);
        assert_eq!(f.normal_agreement(&q[..2], &own[..2], 1e-6), 0.0);
    }

    #[test]
    fn concave_edge_is_the_min_of_its_faces() {
        // The solid is the complement: x >= 0 or y >= 0, normals pointing into x, y < 0.
        let (p, n, l) = edge(false, 1.0, 8);
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        assert_eq!(f.combination().0, Combine::Min);
        for q in &p {
            assert!(f.value(q).abs() < 1e-9);
        }
        // Outside is the quadrant x, y < 0: positive there, by the distance to the nearer face.
        assert!((f.value(&Point3::new(-0.2, -0.5, 0.0)) - 0.2).abs() < 1e-9);
        // Inside (x > 0 or y > 0): negative.
        assert!(f.value(&Point3::new(0.3, -0.5, 0.0)) < 0.0);
        assert!(f.value(&Point3::new(-0.5, 0.3, 0.0)) < 0.0);
        let (_, g) = f.value_and_gradient(&Point3::new(-0.1, -0.5, 0.0));
        assert!((g + Vector3::x()).norm() < 1e-9, "{g}");
    }

    /// Points of the faces x = 0 (region 0), y = 0 (1), z = 0 (2) around the corner at the
    /// origin of the cube [-1, 0]^3 (all convex), with outward normals.
    fn corner(k: usize) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>, Vec<u32>) {
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        for i in 1..=k {
            for j in 1..=k {
                let (a, b) = (-(i as f64) / k as f64, -(j as f64) / k as f64);
                for (r, q) in [
                    Point3::new(0.0, a, b),
                    Point3::new(a, 0.0, b),
                    Point3::new(a, b, 0.0),
                ]
                .into_iter()
                .enumerate()
                {
                    p.push(q);
                    n.push(Vector3::ith(r, 1.0));
                    l.push(r as u32);
                }
            }
        }
        (p, n, l)
    }

    #[test]
    fn convex_corner_is_the_max_of_three_faces() {
        let (p, n, l) = corner(6);
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        assert_eq!(f.combination(), (Combine::Max, Combine::Max));
        assert!(f.value(&Point3::origin()).abs() < 1e-9);
        assert!((f.value(&Point3::new(-0.1, -0.2, -0.3)) + 0.1).abs() < 1e-9);
        assert!((f.value(&Point3::new(0.2, 0.1, -0.5)) - 0.2).abs() < 1e-9);
        let (_, g) = f.value_and_gradient(&Point3::new(-0.5, -0.5, 0.1));
        assert!((g - Vector3::z()).norm() < 1e-9);
    }

    #[test]
    fn mixed_corner_nests_the_odd_pair() {
        // An L-shaped step: the solid { z <= 0 } ∩ ({ x <= 0 } ∪ { y <= 0 }) near the origin:
        // the top z = 0 (region 2) meets both walls convexly, the walls x = 0 (0) and y = 0
        // (1) meet each other concavely (the inner corner of the L).
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        let k = 8;
        for i in 0..k {
            for j in 1..=k {
                let (a, b) = (i as f64 / k as f64, -(j as f64) / k as f64);
                // Wall x = 0 over y > 0 (outside: +x), wall y = 0 over x > 0 (outside: +y).
                p.push(Point3::new(0.0, a + 0.05, b));
                n.push(Vector3::x());
                l.push(0);
                p.push(Point3::new(a + 0.05, 0.0, b));
                n.push(Vector3::y());
                l.push(1);
            }
        }
        for i in 1..=k {
            for j in 1..=k {
                // The top over the L: x < 0 or y < 0.
                let (a, b) = (-(i as f64) / k as f64, j as f64 / k as f64);
                for q in [Point3::new(a, b - 0.5, 0.0), Point3::new(b - 0.5, a, 0.0)] {
                    p.push(q);
                    n.push(Vector3::z());
                    l.push(2);
                }
            }
        }
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        assert_eq!(f.sides()[0].region, 2, "the top goes first");
        assert_eq!(f.combination(), (Combine::Max, Combine::Min));
        // Inside the L below the top, outside in the notch and above.
        assert!(f.value(&Point3::new(-0.3, 0.4, -0.2)) < 0.0);
        assert!(f.value(&Point3::new(0.4, -0.3, -0.2)) < 0.0);
        assert!(f.value(&Point3::new(0.3, 0.3, -0.2)) > 0.0);
        assert!(f.value(&Point3::new(-0.3, -0.3, 0.2)) > 0.0);
        for q in &p {
            assert!(f.value(q).abs() < 1e-9, "{q}: {}", f.value(q));
        }
    }

    #[test]
    fn a_groove_meeting_an_end_face_is_nested_right_off_its_root() {
        // The solid { x >= 0 } ∩ { z <= |y| }: a V groove along x, its root on the x axis,
        // meeting the end face x = 0 (region 0, convex with both flanks); the flanks z = y
        // (1) and z = -y (2) meet concavely. The domain lies mostly over flank 1, so most of
        // the end face's points are outside flank 2's plane: the medians call that pair
        // concave, and F = min(...) misses the end face.
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        let k = 10;
        let s2 = std::f64::consts::FRAC_1_SQRT_2;
        for i in 0..=2 * k {
            for j in 0..=2 * k {
                let (a, b) = (i as f64 / k as f64, j as f64 / k as f64);
                // End face over y in [-0.2, 1.8], z in [-0.7, 1.3], inside the solid.
                let (y, z) = (a - 0.2, b - 0.7);
                if z < y.abs() - 1e-9 {
                    p.push(Point3::new(0.0, y, z));
                    n.push(-Vector3::x());
                    l.push(0);
                }
                // Flanks over x in (0, 0.6], y in [-0.2, 1.8].
                let (x, y) = (0.05 + 0.55 * b / 2.0, a - 0.2);
                if y.abs() > 1e-9 {
                    p.push(Point3::new(x, y, y.abs()));
                    n.push(Vector3::new(0.0, -y.signum() * s2, s2));
                    l.push(if y > 0.0 { 1 } else { 2 });
                }
            }
        }
        let f = SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).unwrap();
        assert_eq!(f.sides()[0].region, 0, "the end face goes first");
        assert_eq!(f.combination(), (Combine::Max, Combine::Min));
        for q in &p {
            assert!(f.value(q).abs() < 1e-9, "{q}: {}", f.value(q));
        }
        assert!(f.value(&Point3::new(0.5, 0.0, -0.3)) < 0.0);
        assert!(f.value(&Point3::new(0.5, 0.3, 0.6)) > 0.0);
        assert!(f.value(&Point3::new(-0.2, 0.3, 0.0)) > 0.0);
    }

    #[test]
    fn one_region_or_too_few_points_is_no_sharp_function() {
        let (p, n, mut l) = edge(true, 1.0, 8);
        let one = vec![0; l.len()];
        assert!(SharpFunction::fit(&p, &n, &one, 1.0, 0.3, 1e-9).is_none());
        // Region 1 reduced to fewer than MIN_SIDE points.
        let mut ones = 0;
        for x in l.iter_mut() {
            if *x == 1 {
                ones += 1;
                if ones >= MIN_SIDE {
                    *x = NO_REGION;
                }
            }
        }
        assert!(SharpFunction::fit(&p, &n, &l, 1.0, 0.3, 1e-9).is_none());
    }
}
