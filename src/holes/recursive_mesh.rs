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
/// line crosses the loop or is forbidden.
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
    let mut cands: Vec<(f64, f64, usize, usize)> = Vec::new(); // (angle cost, length, a, b)
    for a in 0..m {
        for b in a + 2..m {
            if a == 0 && b == m - 1 {
                continue; // adjacent
            }
            let d = p(b) - p(a);
            let len = d.norm();
            if len <= eps {
                continue;
            }
            let t1 = ccw_angle(&out_dir[a], &d);
            if !(t1 > 1e-9 && t1 < interior[a] - 1e-9) {
                continue;
            }
            let t3 = ccw_angle(&out_dir[b], &(-d));
            if !(t3 > 1e-9 && t3 < interior[b] - 1e-9) {
                continue;
            }
            let (t2, t4) = (interior[a] - t1, interior[b] - t3);
            let theta = ((t1 - FRAC_PI_2).abs()
                + (t2 - FRAC_PI_2).abs()
                + (t3 - FRAC_PI_2).abs()
                + (t4 - FRAC_PI_2).abs())
                / (2.0 * PI);
            cands.push((theta, len, a, b));
        }
    }
    let lmax = cands.iter().map(|c| c.1).fold(0.0, f64::max);
    if cands.is_empty() || lmax <= 0.0 {
        return None;
    }
    let mut scored: Vec<(f64, usize, usize)> = cands
        .iter()
        .map(|&(th, len, a, b)| (w.c1 * th + w.c2 * len / lmax, a, b))
        .collect();
    scored.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    for &(_, a, b) in &scored {
        let (ga, gb) = (lp[a], lp[b]);
        if ga < n0 && gb < n0 && forbidden(ga, gb) {
            continue;
        }
        if line_is_clear(pts, lp, a, b, eps) {
            return Some((a, b));
        }
    }
    None
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
