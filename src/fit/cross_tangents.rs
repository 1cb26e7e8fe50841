//! Cross-boundary derivatives along each patch side as one length times a unit direction field
//! both neighbours share (made coplanar with the boundary curve the interpolant really has), so
//! that two patches meeting at an edge have parallel normals along the edge, not only at its
//! samples; and the corner twists they start from.
//!
//! **Why.** Eq. 9-14 interpolate each sample row with a cubic spline clamped only at its ends:
//! along a boundary row v = 0 the patch's iso-curve S(u, 0) is the spline through the edge
//! samples C_k with end derivatives C'(0), C'(1). At an interior sample its derivative
//! S_u(u_k, 0) is the spline's, not the exact edge tangent C'(t_k) (which lies in the
//! implicit's tangent plane): on the bunny at 1,500 patches the spline derivative leaves the
//! tangent plane by 2.6 degrees at the 95th percentile. The cross derivatives D_k = S_v(u_k, 0)
//! of the two neighbours do lie in the tangent plane (eq. 12's end conditions), so the patch
//! normals S_u x D_k of the two sides differ by about that angle: the normal jump is the
//! interpolation error of the along-edge derivative, not of the cross derivative.
//!
//! **What.** Both neighbours know the same boundary spline (it is built from the shared edge
//! samples and the shared corner tangents alone, [`super::edge_curve`]) and the same unit
//! normals N_i of the implicit at the edge samples. With a_i = S_u(u_i, 0) / |S_u(u_i, 0)|
//! the spline's unit derivative at interior sample i, the plane spanned by a_i and the
//! tangent-plane direction orthogonal to it has unit normal
//!
//!   N'_i = (N_i - (N_i . a_i) a_i) / |N_i - (N_i . a_i) a_i|,
//!
//! the unit vector nearest N_i that is orthogonal to a_i, and e_i = N'_i x a_i is the unit
//! cross direction in that plane. Each patch replaces its interior cross derivatives on the
//! side by D_i = m e_i, with m one length per side (the mean of its own derivatives'
//! components along e_i; e_i is the same vector up to sign for both patches, whichever way
//! each walks the edge, and m carries the sign). The cross-derivative spline of the side is linear in its
//! data, so both patches' splines are m_A E(t) and m_B E(t) with the same E(t) between the
//! samples too, except for the corner intervals, where the end data are the adjacent edges'
//! tangents (exact and shared, different for the two patches) and the corner twists: the
//! normals S_u x D of the two patches are then parallel along the whole edge but for the
//! first and last interval. At every sample the normal is +-N', within the spline's tangent
//! error of the implicit normal (positions are unchanged: only first derivatives move).
//!
//! Before, each patch kept its own one-sided-difference derivatives, projected into the
//! plane normal to N'_i: G1 at the samples only, and between them the two splines of
//! independent data (each with its own shear along the side) tilt apart, worst where the
//! normal turns fast along the edge (a crease rounded below the sample spacing, a rim). On
//! the Stanford bunny (`docs/BENCHMARKS.md`, session 6) the common direction took the edge
//! samples jumping more than 5 degrees from 17 to 2 and the p95 from 0.68 to 0.28 degrees,
//! the input points' deviation unchanged; the shear the own derivatives carried is dropped,
//! which the sphere and torus tolerance tests (`fit::samples`) still meet. The previous try
//! of this idea (session 5) was measured before the STEP writer extended small patches'
//! surfaces and was dropped because OpenCASCADE's point projection then missed 1,283 edge
//! points; it now misses none ([`crate::export::apron`]).
//!
//! **Corner twists.** Between the corner and the first interior sample the normal along the
//! edge depends, to first order, on the normal component of the twist S_uv only (tangential
//! components change the length of S_u x S_v, not its direction). Differentiating S_v . N = 0
//! along the edge v = 0 gives N . S_uv = -S_v . D_{S_u} N, and along u = 0 gives
//! N . S_uv = -S_u . D_{S_v} N: both are the implicit's second fundamental form II(S_u, S_v),
//! symmetric because the shape operator is self-adjoint, so one twist satisfies both edges at
//! every corner, whatever the valence. [`corner_twists`] keeps the tangential part of the finite
//! difference estimate ([`crate::nurbs::Twist::Estimate`]) and sets the normal part to
//! -II(S_u, S_v), with D_a N the one-sided differences of the edge samples' unit normals along the two sides
//! (the unit gradient differentiated at a point follows the implicit's wiggles below the sample
//! spacing, which the patch cannot follow; tried first, it made the jumps at irregular vertices
//! worse). Each
//! neighbour then turns its normal along the shared edge at the implicit's rate, so the normal
//! jump near net vertices falls to second order. (This is first-order agreement, not the exact
//! G1 that Peters & Fan show is impossible for one bicubic per quad at valence != 4.) In
//! practice the boundary splines' end curvatures and the sampled normals do not satisfy the
//! identity exactly, so these twists are the starting values of the vertex solve
//! ([`super::vertex_twists`]), which makes their normal components first-order compatible
//! around every net vertex.

use super::edge_curve::EdgeSamples;
use super::samples::PatchSamples;
use crate::implicit::Implicit;
use crate::nurbs::{estimate_twists, BSplineCurve, Params, PatchGrid};
use crate::Result;
use nalgebra::{Point3, Vector3};

/// Sides with fewer sample intervals keep their own cross derivatives (projected, with their
/// shear) instead of the shared direction field: with two intervals both touch a corner, where
/// the end data differ between the neighbours anyway, and dropping the shear only distorts the
/// patch (a smooth blob at 2 intervals: deviation mean 1.8e-7 -> 3.1e-6, normal jump p95
/// 0.013 -> 0.40 degrees). From three intervals on the shared field wins where the normals
/// are rough (the bunny at 12 intervals: 16 edge samples over 5 degrees with the own derivatives,
/// 16 with the shared direction plus each side's own shear, 0 with the shared direction alone)
/// and costs a little on an exact sphere (4 intervals: normal jump p95 0.31 degrees, against
/// under 0.1 with the own derivatives).
pub const MIN_SHARED_INTERVALS: usize = 3;

/// The interpolating cubic splines of a patch's four boundary rows (eq. 9-14 along one
/// direction, with the corner tangents as end conditions), in the side order of
/// `PatchSamples::sides`: v = 0, u = 1, v = 1, u = 0. They are exactly the patch's boundary
/// curves, and both [`align_cross_derivatives`] and [`corner_twists`] need them; the first
/// changes only interior cross derivatives, never the corner tangents these splines end on,
/// so one set serves both.
pub struct BoundarySplines {
    pub sides: [BSplineCurve; 4],
}

impl BoundarySplines {
    /// Interpolates the four boundary rows of `patch` on its parameters `u`, `v`.
    pub fn of(patch: &PatchSamples, u: &Params, v: &Params) -> Result<Self> {
        let s = patch.params_u.len() - 1;
        let t = patch.params_v.len() - 1;
        let row = |j: usize| -> Vec<Point3<f64>> { (0..=s).map(|i| patch.points[i][j]).collect() };
        let col = |i: usize| -> Vec<Point3<f64>> { patch.points[i].clone() };
        let interp = BSplineCurve::interpolate_with_end_tangents;
        Ok(BoundarySplines {
            sides: [
                interp(&row(0), u, patch.tan_u0[0], patch.tan_u1[0])?,
                interp(&col(s), v, patch.tan_v0[s], patch.tan_v1[s])?,
                interp(&row(t), u, patch.tan_u0[t], patch.tan_u1[t])?,
                interp(&col(0), v, patch.tan_v0[0], patch.tan_v1[0])?,
            ],
        })
    }
}

/// Replaces the interior cross derivatives of every side of `patch` by one length times the
/// shared unit cross direction (module documentation). `edges` are the sampling's per-edge
/// data (for the normals), `splines` the patch's [`BoundarySplines`].
pub fn align_cross_derivatives(
    patch: &mut PatchSamples,
    edges: &[EdgeSamples],
    splines: &BoundarySplines,
) -> Result<()> {
    let s = patch.params_u.len() - 1;
    let t = patch.params_v.len() - 1;
    // Side order of `PatchSamples::sides`: v = 0, u = 1, v = 1, u = 0.
    for (k, curve) in splines.sides.iter().enumerate() {
        let side = patch.sides[k];
        let Some(edge) = edges.get(side.edge as usize) else {
            continue;
        };
        let (n, params) = if k % 2 == 0 {
            (s + 1, &patch.params_u)
        } else {
            (t + 1, &patch.params_v)
        };
        if edge.normals.len() != n || n < 3 {
            continue;
        }
        let cross = match k {
            0 => &mut patch.tan_v0,
            2 => &mut patch.tan_v1,
            1 => &mut patch.tan_u1,
            _ => &mut patch.tan_u0,
        };
        // (N'_i, e_i = N'_i x a_i) at every interior sample, from shared data only.
        let frames: Option<Vec<(Vector3<f64>, Vector3<f64>)>> = (1..n - 1)
            .map(|i| {
                let normal = if side.reversed {
                    edge.normals[n - 1 - i]
                } else {
                    edge.normals[i]
                };
                let a = curve.derivative(params[i], 1).try_normalize(0.0)?;
                let np = (normal - a * normal.dot(&a)).try_normalize(1e-12)?;
                Some((np, np.cross(&a)))
            })
            .collect();
        let Some(frames) = frames else { continue };
        if n - 1 < MIN_SHARED_INTERVALS {
            // Every interval touches a corner: keep the own derivatives (with their shear),
            // projected into the plane of a_i and e_i (the normal is still N' at the sample).
            for (d, (np, _)) in cross[1..n - 1].iter_mut().zip(&frames) {
                *d -= np * d.dot(np);
            }
            continue;
        }
        // One length per side: the mean of the own derivatives' components along e.
        let m = (1..n - 1)
            .map(|i| cross[i].dot(&frames[i - 1].1))
            .sum::<f64>()
            / (n - 2) as f64;
        if !m.is_finite() {
            continue;
        }
        for (d, (_, e)) in cross[1..n - 1].iter_mut().zip(&frames) {
            *d = e * m;
        }
    }
    Ok(())
}

/// Directional derivative of the unit normal of f at `p` along `a` (central differences).
fn normal_derivative<I: Implicit + ?Sized>(
    f: &I,
    p: Point3<f64>,
    a: Vector3<f64>,
) -> Option<Vector3<f64>> {
    let e = 1e-3;
    let np = f.gradient(&(p + a * e)).try_normalize(0.0)?;
    let nm = f.gradient(&(p - a * e)).try_normalize(0.0)?;
    let d = (np - nm) / (2.0 * e);
    d.iter().all(|x| x.is_finite()).then_some(d)
}

/// The normal component of the twist that makes the patch's normal turn along one side at the
/// implicit's rate across that side: with e1 = S_a / |S_a| (S_a the derivative along the side),
/// e2 = N x e1 and the other derivative S_b = alpha e1 + beta e2,
///
///   N . S_ab = alpha N . S_aa / |S_a| - beta (D_{S_a} N) . e2,
///
/// S_aa the second derivative of the patch's own boundary spline (shared with the neighbour).
fn side_condition(
    n: Vector3<f64>,
    sa: Vector3<f64>,
    saa: Vector3<f64>,
    sb: Vector3<f64>,
    dn: Vector3<f64>,
) -> Option<f64> {
    let len = sa.norm();
    let e1 = sa.try_normalize(0.0)?;
    let e2 = n.cross(&e1);
    let (alpha, beta) = (sb.dot(&e1), sb.dot(&e2));
    let c = alpha * n.dot(&saa) / len - beta * dn.dot(&e2);
    c.is_finite().then_some(c)
}

/// Corner twists for `grid` (cross derivatives already aligned): the finite-difference estimate
/// with its normal component replaced by the mean of the two sides' conditions
/// ([`side_condition`]; equal to -II(S_u, S_v) when the boundary splines are exact).
/// Corners (u, v) = (0,0), (1,0), (0,1), (1,1).
pub fn corner_twists<I: Implicit + ?Sized>(
    f: &I,
    grid: &PatchGrid,
    u: &Params,
    v: &Params,
    splines: &BoundarySplines,
) -> Result<[Vector3<f64>; 4]> {
    let mut twist = estimate_twists(grid, u, v);
    let s = grid.points.len() - 1;
    let t = grid.points[0].len() - 1;
    let [v0, u1, v1, u0] = &splines.sides;
    let (ua, ub) = u
        .as_slice()
        .first()
        .zip(u.as_slice().last())
        .map(|(a, b)| (*a, *b))
        .unwrap_or((0.0, 1.0));
    let (va, vb) = v
        .as_slice()
        .first()
        .zip(v.as_slice().last())
        .map(|(a, b)| (*a, *b))
        .unwrap_or((0.0, 1.0));
    // (point, S_u, S_v, S_uu, S_vv)
    let corners = [
        (
            grid.points[0][0],
            grid.du_u0[0],
            grid.dv_v0[0],
            v0.derivative(ua, 2),
            u0.derivative(va, 2),
        ),
        (
            grid.points[s][0],
            grid.du_u1[0],
            grid.dv_v0[s],
            v0.derivative(ub, 2),
            u1.derivative(va, 2),
        ),
        (
            grid.points[0][t],
            grid.du_u0[t],
            grid.dv_v1[0],
            v1.derivative(ua, 2),
            u0.derivative(vb, 2),
        ),
        (
            grid.points[s][t],
            grid.du_u1[t],
            grid.dv_v1[s],
            v1.derivative(ub, 2),
            u1.derivative(vb, 2),
        ),
    ];
    for (k, &(p, su, sv, suu, svv)) in corners.iter().enumerate() {
        let Some(n) = f.gradient(&p).try_normalize(0.0) else {
            continue;
        };
        let (Some(nu), Some(nv)) = (normal_derivative(f, p, su), normal_derivative(f, p, sv))
        else {
            continue;
        };
        let (Some(cu), Some(cv)) = (
            side_condition(n, su, suu, sv, nu),
            side_condition(n, sv, svv, su, nv),
        ) else {
            continue;
        };
        let tw = twist[k];
        twist[k] = tw - n * n.dot(&tw) + n * (0.5 * (cu + cv));
    }
    Ok(twist)
}
