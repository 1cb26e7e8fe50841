//! Recursive-subdivision meshing of a simple planar polygon (seed 000 section 2.2, after
//! Talbert & Parkinson 1990).
//!
//! A loop is split in two by the candidate line minimizing (seed 000 eq. 3-5)
//!
//! ```text
//! f(theta, L_ij) = C1 theta + C2 L_ij,
//! theta = sum_{k=1..4} |theta_k - pi/2| / (2 pi),
//! ```
//!
//! where theta_1..4 are the angles the line makes with the loop's edges at both ends and L_ij is
//! its length (here divided by the longest candidate's length so that both terms lie in [0, 1];
//! the paper uses C1 = C2 = 0.5). Nodes are placed along the line so that its pieces are about
//! `target` long; that is how the interior nodes come about. Splitting recurses until every loop
//! has at most four nodes; triangles are output, quadrilaterals are cut along the diagonal with
//! the larger smallest angle.
//!
//! Candidate lines must lie inside the loop (inside the interior angle at both ends, crossing no
//! edge, passing no node) and must not join two nodes for which `forbidden` holds (in the hole
//! filler: two ring vertices the mesh already joins by an edge). Candidates are sorted by cost
//! and checked for crossings cheapest first, so a split costs O(n^2 log n) for an n-node loop.

use super::plane::{orient, point_segment_distance, segments_meet};
use crate::error::{Error, Result};
use nalgebra::Point2;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Weights of the split cost (seed 000 eq. 3).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SplitWeights {
    /// C1, the weight of the angle term.
    pub c1: f64,
    /// C2, the weight of the (normalized) length term.
    pub c2: f64,
}

impl Default for SplitWeights {
    /// C1 = C2 = 0.5 as in seed 000.
    fn default() -> Self {
        SplitWeights { c1: 0.5, c2: 0.5 }
    }
}

/// A planar triangulation: the input polygon's nodes first, then new interior nodes.
#[derive(Debug, Clone, Default)]
pub struct PlanarMesh {
    pub points: Vec<Point2<f64>>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[usize; 3]>,
}

/// Meshes the simple counter-clockwise `polygon` (see the module doc). `forbidden(i, j)` is
/// asked only for pairs of polygon nodes.
pub fn recursive_mesh(
    polygon: &[Point2<f64>],
    target: f64,
    weights: SplitWeights,
    forbidden: &dyn Fn(usize, usize) -> bool,
) -> Result<PlanarMesh> {
    let n0 = polygon.len();
    if n0 < 3 {
        return Err(Error::Degenerate(format!(
            "a hole ring of {n0} vertices cannot be meshed"
        )));
    }
    if !(target > 0.0 && target.is_finite()) {
        return Err(Error::InvalidOption(format!(
            "target edge length {target} must be positive"
        )));
    }
    let mut out = PlanarMesh {
        points: polygon.to_vec(),
        triangles: Vec::new(),
    };
    let size = bbox_size(polygon);
    let eps = 1e-9 * size.max(target);
    // A generous cap against runaway subdivision: the area over the area of a target triangle.
    let area = 0.5 * super::plane::signed_area2(polygon).abs();
    let max_nodes = n0 + 16 * (area / (0.4 * target * target)) as usize + 64;
    let mut stack: Vec<Vec<usize>> = vec![(0..n0).collect()];
    while let Some(lp) = stack.pop() {
        if out.points.len() > max_nodes {
            return Err(Error::Numerical(
                "recursive meshing did not converge (node count exploded)".into(),
            ));
        }
        match lp.len() {
            0..=2 => {
                return Err(Error::Degenerate(
                    "recursive meshing: loop collapsed".into(),
                ));
            }
            3 => out.triangles.push([lp[0], lp[1], lp[2]]),
            4 => {
                if !split_quad(&out.points, &lp, n0, forbidden, &mut out.triangles) {
                    steiner_fan(&mut out, &lp)?;
                }
            }
            _ => {
                let Some((a, b)) = best_split(&out.points, &lp, n0, weights, forbidden, eps) else {
                    steiner_fan(&mut out, &lp)?;
                    continue;
                };
                let (pa, pb) = (out.points[lp[a]], out.points[lp[b]]);
                let len = (pb - pa).norm();
                // Node spacing: the target, or the input polygon's edges at the ends of the line
                // when they are longer (a coarse border then grades into the fill instead of
                // forcing a fine strip along it). Only input edges count: split-line pieces are
                // up to 1.5 times the spacing, and letting them count would coarsen the fill
                // step by step.
                let m = lp.len();
                let input_edge = |k: usize| {
                    let (u, v) = (lp[k % m], lp[(k + 1) % m]);
                    let adjacent = u < n0 && v < n0 && ((u + 1) % n0 == v || (v + 1) % n0 == u);
                    adjacent.then(|| (out.points[v] - out.points[u]).norm())
                };
                let local = [a, a + m - 1, b, b + m - 1]
                    .iter()
                    .filter_map(|&k| input_edge(k))
                    .fold(0.0, f64::max);
                let spacing = target.max(local);
                let pieces = ((len / spacing).round() as usize).max(1);
                let mut inner: Vec<usize> = Vec::with_capacity(pieces.saturating_sub(1));
                for k in 1..pieces {
                    let t = k as f64 / pieces as f64;
                    out.points.push(pa + (pb - pa) * t);
                    inner.push(out.points.len() - 1);
                }
                // Loop 1: a .. b along the loop, then back to a over the inner nodes reversed.
                let mut l1: Vec<usize> = Vec::new();
                let mut k = a;
                loop {
                    l1.push(lp[k]);
                    if k == b {
                        break;
                    }
                    k = (k + 1) % m;
                }
                l1.extend(inner.iter().rev());
                // Loop 2: b .. a along the loop, then to b over the inner nodes.
                let mut l2: Vec<usize> = Vec::new();
                let mut k = b;
                loop {
                    l2.push(lp[k]);
                    if k == a {
                        break;
                    }
                    k = (k + 1) % m;
                }
                l2.extend(inner.iter());
                stack.push(l2);
                stack.push(l1);
            }
        }
    }
    Ok(out)
}

fn bbox_size(p: &[Point2<f64>]) -> f64 {
    let (mut lo, mut hi) = (p[0], p[0]);
    for q in p {
        lo = Point2::new(lo.x.min(q.x), lo.y.min(q.y));
        hi = Point2::new(hi.x.max(q.x), hi.y.max(q.y));
    }
    (hi - lo).norm()
}

/// Counter-clockwise angle from direction `u` to direction `v`, in [0, 2 pi).
fn ccw_angle(u: &nalgebra::Vector2<f64>, v: &nalgebra::Vector2<f64>) -> f64 {
    let a = (u.x * v.y - u.y * v.x).atan2(u.dot(v));
    if a < 0.0 {
        a + TAU
    } else {
        a
    }
}

/// The split line (as positions in `lp`) of least cost (seed 000 eq. 3-5); `None` when every
/// line crosses the loop or is forbidden. L_ij is divided by the loop's largest node distance.
/// (A candidate skipped by the length bound could beat the chosen one when every cheaper
/// candidate crosses the loop; the split is then near-optimal rather than optimal.)
///
/// Which lines lie inside the interior angle at both ends is decided exactly (cross products);
/// the angles in the cost use a polynomial arctangent (error below 1e-5 rad), since the cost is
/// evaluated for every pair of nodes at every split and `atan2` dominated the meshing time.
fn best_split(
    pts: &[Point2<f64>],
    lp: &[usize],
    n0: usize,
    w: SplitWeights,
    forbidden: &dyn Fn(usize, usize) -> bool,
    eps: f64,
) -> Option<(usize, usize)> {
    let m = lp.len();
    let p = |k: usize| pts[lp[k % m]];
    // Interior angle at each node: from the outgoing edge counter-clockwise to the incoming one.
    let out_dir: Vec<_> = (0..m).map(|k| p(k + 1) - p(k)).collect();
    let in_dir: Vec<_> = (0..m).map(|k| p(k + m - 1) - p(k)).collect();
    let interior: Vec<f64> = (0..m).map(|k| ccw_angle(&out_dir[k], &in_dir[k])).collect();
    let cross = |u: &nalgebra::Vector2<f64>, v: &nalgebra::Vector2<f64>| u.x * v.y - u.y * v.x;
    // Strictly inside the interior angle at node k.
    let inside = |k: usize, d: &nalgebra::Vector2<f64>| {
        let (a, b) = (cross(&out_dir[k], d), cross(d, &in_dir[k]));
        if interior[k] < PI {
            a > 0.0 && b > 0.0
        } else {
            a > 0.0 || b > 0.0
        }
    };
    // All node pairs with their lengths (cheap); the angles are computed only for pairs short
    // enough to beat the best cost found so far, starting with the 4m shortest. The length
    // term alone, C2 L / L_max, bounds a pair's cost from below.
    let mut pairs: Vec<(f64, u32, u32)> = Vec::with_capacity(m * m / 2);
    for a in 0..m {
        for b in a + 2..m {
            if a == 0 && b == m - 1 {
                continue; // adjacent
            }
            pairs.push(((p(b) - p(a)).norm(), a as u32, b as u32));
        }
    }
    let lmax = pairs.iter().map(|x| x.0).fold(0.0, f64::max);
    if !(lmax > eps) || pairs.is_empty() {
        return None;
    }
    let cost = |a: usize, b: usize, len: f64| -> Option<f64> {
        let d = p(b) - p(a);
        if len <= eps || !inside(a, &d) || !inside(b, &(-d)) {
            return None;
        }
        let t1 = fast_ccw_angle(&out_dir[a], &d).min(interior[a]);
        let t3 = fast_ccw_angle(&out_dir[b], &(-d)).min(interior[b]);
        let (t2, t4) = (interior[a] - t1, interior[b] - t3);
        let theta = ((t1 - FRAC_PI_2).abs()
            + (t2 - FRAC_PI_2).abs()
            + (t3 - FRAC_PI_2).abs()
            + (t4 - FRAC_PI_2).abs())
            / (2.0 * PI);
        Some(w.c1 * theta + w.c2 * len / lmax)
    };
    let short = (4 * m).min(pairs.len() - 1);
    pairs.select_nth_unstable_by(short, |x, y| x.0.total_cmp(&y.0));
    let mut scored: Vec<(f64, usize, usize)> = Vec::new();
    let mut best = f64::INFINITY;
    for &(len, a, b) in &pairs[..=short] {
        if let Some(c) = cost(a as usize, b as usize, len) {
            best = best.min(c);
            scored.push((c, a as usize, b as usize));
        }
    }
    for &(len, a, b) in &pairs[short + 1..] {
        if w.c2 * len / lmax >= best {
            continue;
        }
        if let Some(c) = cost(a as usize, b as usize, len) {
            best = best.min(c);
            scored.push((c, a as usize, b as usize));
        }
    }
    let order = |x: &(f64, usize, usize), y: &(f64, usize, usize)| {
        x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2))
    };
    let usable = |a: usize, b: usize| {
        let (ga, gb) = (lp[a], lp[b]);
        !(ga < n0 && gb < n0 && forbidden(ga, gb)) && line_is_clear(pts, lp, a, b, eps)
    };
    // The cheapest candidates are usually usable: pick minima one at a time, and sort the rest
    // only if many in a row are not.
    for _ in 0..16 {
        let Some((k, &(_, a, b))) = scored.iter().enumerate().min_by(|x, y| order(x.1, y.1)) else {
            break;
        };
        if usable(a, b) {
            return Some((a, b));
        }
        scored.swap_remove(k);
    }
    scored.sort_by(order);
    if let Some(&(_, a, b)) = scored.iter().find(|&&(_, a, b)| usable(a, b)) {
        return Some((a, b));
    }
    // Every candidate cheap enough was blocked: look at all the others too.
    let mut rest: Vec<(f64, usize, usize)> = pairs
        .iter()
        .filter_map(|&(len, a, b)| {
            cost(a as usize, b as usize, len).map(|c| (c, a as usize, b as usize))
        })
        .collect();
    rest.sort_by(order);
    rest.iter()
        .find(|&&(_, a, b)| usable(a, b))
        .map(|&(_, a, b)| (a, b))
}

/// Counter-clockwise angle from `u` to `v` in [0, 2 pi), with [`fast_atan2`].
fn fast_ccw_angle(u: &nalgebra::Vector2<f64>, v: &nalgebra::Vector2<f64>) -> f64 {
    let a = fast_atan2(u.x * v.y - u.y * v.x, u.dot(v));
    if a < 0.0 {
        a + TAU
    } else {
        a
    }
}

/// atan2 by a degree-11 odd minimax polynomial on [0, 1] and octant reduction; absolute error
/// below 1e-5 rad.
fn fast_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (num, den) = if ax >= ay { (ay, ax) } else { (ax, ay) };
    if den == 0.0 {
        return 0.0;
    }
    let z = num / den;
    let z2 = z * z;
    let mut r = z
        * (0.999_977_26
            + z2 * (-0.332_623_47
                + z2 * (0.193_543_46
                    + z2 * (-0.116_432_87 + z2 * (0.052_653_32 + z2 * -0.011_721_20)))));
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// When no line can split a loop (every diagonal is forbidden), a new node that sees every
/// edge of the loop: the loop's centroid or the midpoint of one of its diagonals. The loop
/// becomes a fan around it.
fn steiner_fan(out: &mut PlanarMesh, lp: &[usize]) -> Result<()> {
    let m = lp.len();
    let p = |k: usize| out.points[lp[k % m]];
    let mut cands = vec![Point2::from(
        lp.iter()
            .map(|&i| out.points[i].coords)
            .sum::<nalgebra::Vector2<f64>>()
            / m as f64,
    )];
    for a in 0..m {
        for b in a + 2..m {
            cands.push(nalgebra::center(&p(a), &p(b)));
        }
    }
    for c in cands {
        if (0..m).all(|k| orient(&p(k), &p(k + 1), &c) > 0.0) {
            out.points.push(c);
            let s = out.points.len() - 1;
            for k in 0..m {
                out.triangles.push([lp[k], lp[(k + 1) % m], s]);
            }
            return Ok(());
        }
    }
    Err(Error::Degenerate(
        "recursive meshing: a loop has no usable split line (all cross it or existing edges)"
            .into(),
    ))
}

/// True when the segment between loop nodes `a` and `b` crosses no loop edge and passes no
/// other node.
fn line_is_clear(pts: &[Point2<f64>], lp: &[usize], a: usize, b: usize, eps: f64) -> bool {
    let m = lp.len();
    let (pa, pb) = (pts[lp[a]], pts[lp[b]]);
    for k in 0..m {
        let k1 = (k + 1) % m;
        if k != a && k != b && point_segment_distance(&pts[lp[k]], &pa, &pb) <= eps {
            return false;
        }
        if k == a || k == b || k1 == a || k1 == b {
            continue;
        }
        if segments_meet(&pa, &pb, &pts[lp[k]], &pts[lp[k1]], eps) {
            return false;
        }
    }
    true
}

/// Smallest angle of triangle a, b, c.
fn min_angle(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>) -> f64 {
    let ang = |p: &Point2<f64>, q: &Point2<f64>, r: &Point2<f64>| {
        let (u, v) = (q - p, r - p);
        (u.x * v.y - u.y * v.x).abs().atan2(u.dot(&v))
    };
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

/// Cuts a 4-node loop along the valid diagonal with the larger smallest angle; false when
/// neither diagonal can be used.
fn split_quad(
    pts: &[Point2<f64>],
    q: &[usize],
    n0: usize,
    forbidden: &dyn Fn(usize, usize) -> bool,
    tris: &mut Vec<[usize; 3]>,
) -> bool {
    let mut best: Option<(f64, [[usize; 3]; 2])> = None;
    for s in 0..2 {
        let (a, b, c, d) = (q[s], q[s + 1], q[(s + 2) % 4], q[(s + 3) % 4]);
        if a < n0 && c < n0 && forbidden(a, c) {
            continue;
        }
        let (pa, pb, pc, pd) = (pts[a], pts[b], pts[c], pts[d]);
        if !(orient(&pa, &pb, &pc) > 0.0 && orient(&pa, &pc, &pd) > 0.0) {
            continue;
        }
        let quality = min_angle(&pa, &pb, &pc).min(min_angle(&pa, &pc, &pd));
        if best.as_ref().is_none_or(|(bq, _)| quality > *bq) {
            best = Some((quality, [[a, b, c], [a, c, d]]));
        }
    }
    match best {
        Some((_, t)) => {
            tris.extend_from_slice(&t);
            true
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(mesh: &PlanarMesh, poly: &[Point2<f64>]) {
        let area: f64 = mesh
            .triangles
            .iter()
            .map(|t| {
                let a = orient(&mesh.points[t[0]], &mesh.points[t[1]], &mesh.points[t[2]]);
                assert!(a > 0.0, "triangle {t:?} not counter-clockwise");
                0.5 * a
            })
            .sum();
        let want = 0.5 * super::super::plane::signed_area2(poly);
        assert!((area - want).abs() < 1e-9 * want, "area {area} vs {want}");
        // Every polygon edge is used by exactly one triangle in the polygon's direction.
        let n = poly.len();
        for i in 0..n {
            let j = (i + 1) % n;
            let c = mesh
                .triangles
                .iter()
                .filter(|t| (0..3).any(|k| t[k] == i && t[(k + 1) % 3] == j))
                .count();
            assert_eq!(c, 1, "edge {i}->{j}");
        }
    }

    fn circle(n: usize, r: f64) -> Vec<Point2<f64>> {
        (0..n)
            .map(|k| {
                let t = TAU * k as f64 / n as f64;
                Point2::new(r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn disc_gets_interior_nodes_of_the_target_size() {
        let poly = circle(40, 1.0);
        let h = TAU / 40.0;
        let m = recursive_mesh(&poly, h, SplitWeights::default(), &|_, _| false).unwrap();
        check(&m, &poly);
        assert!(m.points.len() > 60, "{} nodes", m.points.len());
        // Mean edge length near the target.
        let mut sum = 0.0;
        let mut cnt = 0;
        for t in &m.triangles {
            for k in 0..3 {
                sum += (m.points[t[k]] - m.points[t[(k + 1) % 3]]).norm();
                cnt += 1;
            }
        }
        let mean = sum / cnt as f64;
        assert!(mean > 0.7 * h && mean < 1.6 * h, "mean edge {mean} vs {h}");
    }

    #[test]
    fn non_convex_and_forbidden() {
        // An L shape.
        let poly = vec![
            Point2::new(0.0, 0.0),
            Point2::new(3.0, 0.0),
            Point2::new(3.0, 1.0),
            Point2::new(1.0, 1.0),
            Point2::new(1.0, 3.0),
            Point2::new(0.0, 3.0),
        ];
        let m = recursive_mesh(&poly, 0.5, SplitWeights::default(), &|_, _| false).unwrap();
        check(&m, &poly);
        // With a coarse target and the diagonal 0-3 forbidden, it must still succeed.
        let m = recursive_mesh(&poly, 10.0, SplitWeights::default(), &|a, b| {
            (a.min(b), a.max(b)) == (0, 3)
        })
        .unwrap();
        check(&m, &poly);
        assert!(!m.triangles.iter().any(|t| (0..3)
            .any(|k| (t[k] == 0 && t[(k + 1) % 3] == 3) || (t[k] == 3 && t[(k + 1) % 3] == 0))));
    }

    #[test]
    fn fast_atan2_is_accurate() {
        for k in 0..3600 {
            let t = -PI + TAU * (k as f64 + 0.37) / 3600.0;
            let (y, x) = (2.5 * t.sin(), 2.5 * t.cos());
            assert!((fast_atan2(y, x) - y.atan2(x)).abs() < 1e-5, "{t}");
        }
        assert_eq!(fast_atan2(0.0, 0.0), 0.0);
    }

    #[test]
    fn collinear_boundary_nodes() {
        // A square with extra nodes on its sides (straight boundary, 180 degree angles).
        let mut poly = Vec::new();
        for k in 0..4 {
            poly.push(Point2::new(k as f64, 0.0));
        }
        for k in 0..4 {
            poly.push(Point2::new(4.0, k as f64));
        }
        for k in 0..4 {
            poly.push(Point2::new(4.0 - k as f64, 4.0));
        }
        for k in 0..4 {
            poly.push(Point2::new(0.0, 4.0 - k as f64));
        }
        let m = recursive_mesh(&poly, 1.0, SplitWeights::default(), &|_, _| false).unwrap();
        check(&m, &poly);
        assert!(m.triangles.iter().all(|t| min_angle(
            &m.points[t[0]],
            &m.points[t[1]],
            &m.points[t[2]]
        ) > 0.3));
        assert!(recursive_mesh(&poly[..2], 1.0, SplitWeights::default(), &|_, _| false).is_err());
    }
}
