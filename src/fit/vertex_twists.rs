//! Corner twists made first-order compatible around every net vertex ("vertex enclosure").
//!
//! **The condition.** Let two patches A and B share the edge C(t), t measured from the vertex V
//! (t = 0), with cross-boundary derivatives D_A(t), D_B(t). They are G1 along the edge iff
//! det(C', D_A, D_B) = 0. At V all three lie in the tangent plane (normal N): the corner data
//! are the edge tangents. The first derivative along the edge is
//!
//!   d/dt det = det(C'', a, b) + det(c, D_A', b) + det(c, a, D_B')
//!            = (N . C'') [a, b] + tau_A [b, c] + tau_B [c, a],              (1)
//!
//! with c = C'(0), a = D_A(0), b = D_B(0), [x, y] = N . (x x y), and tau = N . D'(0): only the
//! normal components of the derivatives of the cross derivatives count, and D' at a corner is
//! the patch's twist S_uv up to the signs of the parameter directions. With tau from the
//! implicit's second fundamental form and N . C'' = II(c, c), (1) vanishes identically (the 2D
//! identity c [a, b] + a [b, c] + b [c, a] = 0 under II(c, .)); but C'' is the boundary
//! spline's second derivative at its end, not the surface's, and II is estimated from sampled
//! normals, so (1) is not zero: the normal jump then grows linearly from the vertex (measured
//! on the bunny: 1.4 degrees at 0.1 % of the edge, 11 at 1 %) until the first boundary sample,
//! where the cross derivatives agree again.
//!
//! **The solve.** Around a vertex of valence n there are n edges, each with one condition (1),
//! and n corners, each with one unknown W = N . S_uv (a corner's twist enters the conditions of
//! both its edges). For odd n the system is regular and (1) can be met on every edge; for even
//! n it is singular (Peters' vertex enclosure constraint), and G1 needs a compatibility that
//! generic data do not have. So the normal components solve
//!
//!   min sum_edges (d/dt det / (|a| |b| |c|))^2 + mu sum_corners ((W - W_0) / (|S_u| |S_v|)^(1/2))^2,
//!
//! W_0 the implicit-based value of [`super::cross_tangents::corner_twists`], mu =
//! [`REGULARIZATION`]: the conditions where they can be met, the implicit's curvature where
//! they cannot. Tangential components stay as estimated (they do not enter (1)). This is
//! first-order agreement at the vertex, not exact G1 along the edge (Peters & Fan: one bicubic
//! per quad cannot be exactly G1 at valence != 4 in general).

use super::samples::PatchSamples;
use crate::nurbs::PatchGrid;
use nalgebra::{DMatrix, DVector, Vector3};
use std::collections::HashMap;

/// Weight of the pull toward the implicit-based twists (the `mu` of the module doc).
pub const REGULARIZATION: f64 = 1e-2;

/// One patch corner's data at its vertex. Corners are numbered as
/// [`PatchGrid`]'s twists: 0 = (0, 0), 1 = (1, 0), 2 = (0, 1), 3 = (1, 1).
#[derive(Debug, Clone, Copy)]
pub struct Corner {
    /// S_u, S_v and the boundary splines' second derivatives S_uu (along the corner's u-side)
    /// and S_vv (along its v-side) at the corner.
    pub su: Vector3<f64>,
    pub sv: Vector3<f64>,
    pub suu: Vector3<f64>,
    pub svv: Vector3<f64>,
}

/// The net node at twist corner `k` of a patch, its u-side and v-side net edges, and the signs
/// of d/du and d/dv walking away from the corner.
fn corner_topology(p: &PatchSamples, k: usize) -> (u32, u32, u32, f64, f64) {
    let (i, j) = (k & 1, k >> 1);
    // PatchSamples::corners are at (0,0), (1,0), (1,1), (0,1); sides v = 0, u = 1, v = 1, u = 0.
    let node = p.corners[[0, 1, 3, 2][k]];
    let u_edge = p.sides[if j == 0 { 0 } else { 2 }].edge;
    let v_edge = p.sides[if i == 0 { 3 } else { 1 }].edge;
    let su = if i == 0 { 1.0 } else { -1.0 };
    let sv = if j == 0 { 1.0 } else { -1.0 };
    (node, u_edge, v_edge, su, sv)
}

/// Replaces the normal components of the corner twists of `patches` (in place, `twists[p][k]`)
/// by the vertex solve of the module documentation. `corners[p][k]` holds each corner's data,
/// `normal(node)` the unit surface normal at a net node.
pub fn solve_vertex_twists(
    patches: &[PatchSamples],
    corners: &[[Corner; 4]],
    normal: &dyn Fn(u32) -> Option<Vector3<f64>>,
    twists: &mut [[Vector3<f64>; 4]],
) {
    // Corners by node, in a deterministic order.
    let mut by_node: HashMap<u32, Vec<(usize, usize)>> = HashMap::new();
    for (pi, p) in patches.iter().enumerate() {
        for k in 0..4 {
            by_node
                .entry(corner_topology(p, k).0)
                .or_default()
                .push((pi, k));
        }
    }
    let mut nodes: Vec<u32> = by_node.keys().copied().collect();
    nodes.sort_unstable();
    for node in nodes {
        let list = &by_node[&node];
        let Some(n) = normal(node) else { continue };
        if let Some(w) = solve_one(patches, corners, twists, list, n) {
            for (&(pi, k), wk) in list.iter().zip(w) {
                let t = twists[pi][k];
                twists[pi][k] = t - n * n.dot(&t) + n * wk;
            }
        }
    }
}

/// The normal twist components at one vertex (in the order of `list`), `None` when the data
/// are degenerate.
fn solve_one(
    patches: &[PatchSamples],
    corners: &[[Corner; 4]],
    twists: &[[Vector3<f64>; 4]],
    list: &[(usize, usize)],
    n: Vector3<f64>,
) -> Option<Vec<f64>> {
    let m = list.len();
    // Per edge at this vertex: the corners using it, with (tangent c, cross derivative D,
    // second derivative along the edge, sign of the twist in D').
    type Use = (usize, Vector3<f64>, Vector3<f64>, Vector3<f64>, f64);
    let mut edges: HashMap<u32, Vec<Use>> = HashMap::new();
    for (slot, &(pi, k)) in list.iter().enumerate() {
        let (_, ue, ve, su, sv) = corner_topology(&patches[pi], k);
        let c = &corners[pi][k];
        edges
            .entry(ue)
            .or_default()
            .push((slot, c.su * su, c.sv, c.suu, su));
        edges
            .entry(ve)
            .or_default()
            .push((slot, c.sv * sv, c.su, c.svv, sv));
    }
    let mut keys: Vec<u32> = edges.keys().copied().collect();
    keys.sort_unstable();
    let bracket = |x: &Vector3<f64>, y: &Vector3<f64>| n.dot(&x.cross(y));
    let mut rows: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
    for e in keys {
        let uses = &edges[&e];
        let [(ia, ca, a, acc_a, sa), (ib, _, b, acc_b, sb)] = uses.as_slice() else {
            continue;
        };
        let c = *ca;
        let scale = a.norm() * b.norm() * c.norm();
        if !(scale > 0.0 && scale.is_finite()) {
            continue;
        }
        let kappa = 0.5 * n.dot(&(acc_a + acc_b));
        // (1) = kappa [a, b] + sa W_a [b, c] + sb W_b [c, a], divided by |a| |b| |c|.
        let r0 = kappa * bracket(a, b) / scale;
        let ga = sa * bracket(b, &c) / scale;
        let gb = sb * bracket(&c, a) / scale;
        rows.push((vec![(*ia, ga), (*ib, gb)], r0));
    }
    if rows.is_empty() {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(rows.len() + m, m);
    let mut rhs = DVector::<f64>::zeros(rows.len() + m);
    for (r, (coefs, r0)) in rows.iter().enumerate() {
        for &(slot, g) in coefs {
            a[(r, slot)] += g;
        }
        rhs[r] = -r0;
    }
    for (slot, &(pi, k)) in list.iter().enumerate() {
        let c = &corners[pi][k];
        let w = (REGULARIZATION / (c.su.norm() * c.sv.norm()).max(f64::MIN_POSITIVE)).sqrt();
        let w0 = n.dot(&twists[pi][k]);
        a[(rows.len() + slot, slot)] = w;
        rhs[rows.len() + slot] = w * w0;
    }
    let sol = a.svd(true, true).solve(&rhs, 1e-14).ok()?;
    sol.iter()
        .all(|x| x.is_finite())
        .then(|| sol.iter().copied().collect())
}

/// The data of the four corners of a patch built from `grid` and its boundary splines'
/// second derivatives `[v = 0 at u0, v = 0 at u1, v = 1 at u0, v = 1 at u1]` along u and
/// `[u = 0 at v0, u = 1 at v0, u = 0 at v1, u = 1 at v1]` along v.
pub fn corners_of(grid: &PatchGrid, suu: [Vector3<f64>; 4], svv: [Vector3<f64>; 4]) -> [Corner; 4] {
    let s = grid.points.len() - 1;
    let t = grid.points[0].len() - 1;
    let su = [grid.du_u0[0], grid.du_u1[0], grid.du_u0[t], grid.du_u1[t]];
    let sv = [grid.dv_v0[0], grid.dv_v0[s], grid.dv_v1[0], grid.dv_v1[s]];
    std::array::from_fn(|k| Corner {
        su: su[k],
        sv: sv[k],
        suu: suu[k],
        svv: svv[k],
    })
}

#[cfg(test)]
mod tests {
    use super::super::samples::PatchSide;
    use super::*;

    /// `n` patches around node 0, all with their corner (0, 0) there: patch p has its u-side
    /// on edge p and its v-side on edge p + 1 (mod n), tangent directions at angles
    /// 2 pi k / n in the plane z = 0 (normal +z), on the quadric z = x^T B x.
    fn fan(n: usize, b: [[f64; 2]; 2], len: f64) -> (Vec<PatchSamples>, Vec<[Corner; 4]>) {
        let dir = |k: usize| {
            let a = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            Vector3::new(a.cos(), a.sin(), 0.0)
        };
        let q = |x: &Vector3<f64>, y: &Vector3<f64>| {
            2.0 * (x.x * (b[0][0] * y.x + b[0][1] * y.y) + x.y * (b[1][0] * y.x + b[1][1] * y.y))
        };
        let side = |edge: usize| PatchSide {
            edge: edge as u32,
            reversed: false,
        };
        let mut patches = Vec::new();
        let mut corners = Vec::new();
        for p in 0..n {
            patches.push(PatchSamples {
                quad: p,
                corners: [0, 1 + p as u32, 100, 1 + ((p + 1) % n) as u32],
                sides: [side(p), side(1000 + p), side(2000 + p), side((p + 1) % n)],
                points: Vec::new(),
                normals: Vec::new(),
                params_u: Vec::new(),
                params_v: Vec::new(),
                tan_u0: Vec::new(),
                tan_u1: Vec::new(),
                tan_v0: Vec::new(),
                tan_v1: Vec::new(),
                deviation_u: 0.0,
                deviation_v: 0.0,
                deviation_cell: 0.0,
                unprojected: 0,
                max_residual: 0.0,
                coons_rows: false,
                measured: true,
            });
            let (cu, cv) = (dir(p) * len, dir(p + 1) * len);
            let z = Vector3::z();
            let c = Corner {
                su: cu,
                sv: cv,
                suu: z * q(&cu, &cu),
                svv: z * q(&cv, &cv),
            };
            corners.push([c; 4]);
        }
        (patches, corners)
    }

    /// The exact twist normals of the quadric, W = 2 B(S_u, S_v), at corner 0 of each patch.
    fn quadric_twists(corners: &[[Corner; 4]], b: [[f64; 2]; 2]) -> Vec<[Vector3<f64>; 4]> {
        corners
            .iter()
            .map(|c| {
                let (x, y) = (c[0].su, c[0].sv);
                let w = 2.0
                    * (x.x * (b[0][0] * y.x + b[0][1] * y.y)
                        + x.y * (b[1][0] * y.x + b[1][1] * y.y));
                [
                    Vector3::new(0.1 * x.x, 0.0, w),
                    Vector3::zeros(),
                    Vector3::zeros(),
                    Vector3::zeros(),
                ]
            })
            .collect()
    }

    /// Condition (1) of the module doc on edge p (u-side of patch p, v-side of patch p - 1),
    /// relative to |a| |b| |c|.
    fn residuals(corners: &[[Corner; 4]], twists: &[[Vector3<f64>; 4]]) -> Vec<f64> {
        let n = corners.len();
        let z = Vector3::z();
        let br = |x: &Vector3<f64>, y: &Vector3<f64>| z.dot(&x.cross(y));
        (0..n)
            .map(|p| {
                let (ca, cb) = (&corners[p][0], &corners[(p + n - 1) % n][0]);
                let (c, a, b) = (ca.su, ca.sv, cb.su);
                let kappa = 0.5 * z.dot(&(ca.suu + cb.svv));
                let (wa, wb) = (twists[p][0].z, twists[(p + n - 1) % n][0].z);
                (kappa * br(&a, &b) + wa * br(&b, &c) + wb * br(&c, &a))
                    / (a.norm() * b.norm() * c.norm())
            })
            .collect()
    }

    #[test]
    fn consistent_quadric_data_are_kept() {
        let b = [[1.5, 0.4], [0.4, -0.7]];
        for n in [3, 4, 5, 6] {
            let (patches, corners) = fan(n, b, 0.01);
            let mut twists = quadric_twists(&corners, b);
            let before = twists.clone();
            assert!(residuals(&corners, &twists).iter().all(|r| r.abs() < 1e-12));
            solve_vertex_twists(&patches, &corners, &|_| Some(Vector3::z()), &mut twists);
            for (t, t0) in twists.iter().zip(&before) {
                assert!(
                    (t[0] - t0[0]).norm() < 1e-12 * t0[0].norm().max(1e-6),
                    "n {n}"
                );
            }
        }
    }

    #[test]
    fn odd_valence_meets_the_condition_and_tangential_parts_stay() {
        let b = [[1.5, 0.4], [0.4, -0.7]];
        for n in [3, 5] {
            let (patches, mut corners) = fan(n, b, 0.01);
            // Boundary second derivatives that are not the surface's: (1) fails.
            for (p, c) in corners.iter_mut().enumerate() {
                c[0].suu.z *= 1.0 + 0.3 * p as f64;
            }
            let mut twists = quadric_twists(&corners, b);
            let before = twists.clone();
            let r0: f64 = residuals(&corners, &twists).iter().map(|r| r.abs()).sum();
            assert!(r0 > 1e-3, "the test lost its case: {r0}");
            solve_vertex_twists(&patches, &corners, &|_| Some(Vector3::z()), &mut twists);
            let r1: f64 = residuals(&corners, &twists).iter().map(|r| r.abs()).sum();
            assert!(r1 < 0.05 * r0, "n {n}: {r0} -> {r1}");
            for (t, t0) in twists.iter().zip(&before) {
                assert_eq!(t[0].xy(), t0[0].xy());
            }
        }
    }
}
