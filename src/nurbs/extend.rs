//! Extension of a clamped B-spline surface beyond its domain by a linear apron, leaving the
//! surface over the original domain unchanged.
//!
//! **Why.** A STEP face may be the trimmed region of a larger surface. OpenCASCADE's default
//! point projection (`GeomAPI_ProjectPointOnSurf`, `Extrema_ExtAlgo_Grad`) starts its Newton
//! iterations from a 44 x 44 grid over the whole surface domain and treats two neighbouring
//! grid points as one when their squared distance is below 2e-7 (twice `Precision::Confusion`,
//! an absolute length in millimetres). On a patch smaller than about 0.02 mm (a model a
//! quarter of a unit across, read as millimetres, at 1,500 patches) every grid cell is
//! "confused" and only starts on the u = min and v = min sides survive: points on the other
//! two sides are found only when Newton crosses the whole patch, and 1 % of them are not (the
//! Stanford bunny: 265 of 28,200 edge-point projections). Stretching the domain by the apron
//! spreads the same 44 grid lines over a larger parameter range, so the patch itself gets
//! fewer, longer grid cells and the search works as designed.
//!
//! **How.** For degree p, knots t_0 .. t_{n+p} clamped on [a, b] and control points
//! P_0 .. P_{n-1}, the extended curve has knots
//!
//!   (a - e_a)^(p+1), a^p, t_{p+1} .. t_{n-1}, b^p, (b + e_b)^(p+1)
//!
//! and control points Q_k = P_0 + (p - k) (e_a / d_a) (P_0 - P_1) for k < p, then P_0 ..
//! P_{n-1}, then P_{n-1} + k (e_b / d_b) (P_{n-1} - P_{n-2}) for k = 1 .. p, where
//! d_a = t_{p+1} - a and d_b = b - t_{n-1}. A knot of multiplicity p at a leaves the basis
//! functions over [a, b] those of the clamped vector, so the curve there is unchanged; each
//! apron span is the straight segment along the end tangent C'(a) = p (P_1 - P_0) / d_a,
//! traversed at the same speed, so the extended curve is C1. Surfaces are extended row by row
//! along v, then column by column along u (the corner regions are the tensor product of both
//! linear extensions).

use super::surface::BSplineSurface;
use nalgebra::Point3;

/// Extension of one control polygon; `e0`, `e1` in parameter units at the start and end.
fn extend_polygon(
    ctrl: &[Point3<f64>],
    knots: &[f64],
    p: usize,
    e0: f64,
    e1: f64,
) -> Vec<Point3<f64>> {
    let n = ctrl.len();
    let (a, b) = (knots[p], knots[n]);
    let d0 = knots[p + 1] - a;
    let d1 = b - knots[n - 1];
    let step0 = (ctrl[0] - ctrl[1]) * (e0 / d0);
    let step1 = (ctrl[n - 1] - ctrl[n - 2]) * (e1 / d1);
    let mut out = Vec::with_capacity(n + 2 * p);
    for k in 0..p {
        out.push(ctrl[0] + step0 * (p - k) as f64);
    }
    out.extend_from_slice(ctrl);
    for k in 1..=p {
        out.push(ctrl[n - 1] + step1 * k as f64);
    }
    out
}

/// The knot vector of [`extend_polygon`].
fn extend_knots(knots: &[f64], p: usize, n: usize, e0: f64, e1: f64) -> Vec<f64> {
    let (a, b) = (knots[p], knots[n]);
    let mut out = Vec::with_capacity(knots.len() + 2 * p);
    out.extend(std::iter::repeat_n(a - e0, p + 1));
    out.extend(std::iter::repeat_n(a, p));
    out.extend_from_slice(&knots[p + 1..n]);
    out.extend(std::iter::repeat_n(b, p));
    out.extend(std::iter::repeat_n(b + e1, p + 1));
    out
}

impl BSplineSurface {
    /// The surface extended by `e_u` (before u_min and after u_max) and `e_v` (v), in parameter
    /// units, as described in the module documentation; a zero or negative width leaves that
    /// direction as it is. Over the original domain the result evaluates to the same points
    /// (up to rounding in the basis functions), so a face bounded by the original boundary
    /// curves is the same face.
    pub fn extended(&self, e_u: f64, e_v: f64) -> BSplineSurface {
        let (p, q) = (self.degree_u, self.degree_v);
        let (nu, nv) = self.ctrl_dims();
        let (mut ctrl, knots_v) = if e_v > 0.0 {
            let rows = self
                .ctrl
                .iter()
                .map(|row| extend_polygon(row, &self.knots_v, q, e_v, e_v))
                .collect();
            (rows, extend_knots(&self.knots_v, q, nv, e_v, e_v))
        } else {
            (self.ctrl.clone(), self.knots_v.clone())
        };
        let knots_u = if e_u > 0.0 {
            let nv2 = ctrl.first().map_or(0, Vec::len);
            let cols: Vec<Vec<Point3<f64>>> = (0..nv2)
                .map(|j| {
                    let col: Vec<Point3<f64>> = ctrl.iter().map(|r| r[j]).collect();
                    extend_polygon(&col, &self.knots_u, p, e_u, e_u)
                })
                .collect();
            ctrl = (0..nu + 2 * p)
                .map(|i| cols.iter().map(|c| c[i]).collect())
                .collect();
            extend_knots(&self.knots_u, p, nu, e_u, e_u)
        } else {
            self.knots_u.clone()
        };
        BSplineSurface {
            degree_u: p,
            degree_v: q,
            knots_u,
            knots_v,
            ctrl,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::nurbs::Side;

    /// A non-planar bicubic with interior knots, domain [0, 1] x [2, 3].
    pub(crate) fn wavy() -> BSplineSurface {
        let ku = vec![0.0, 0.0, 0.0, 0.0, 0.3, 0.6, 1.0, 1.0, 1.0, 1.0];
        let kv = vec![2.0, 2.0, 2.0, 2.0, 2.5, 3.0, 3.0, 3.0, 3.0];
        let ctrl = (0..6)
            .map(|i| {
                (0..5)
                    .map(|j| {
                        let (x, y) = (i as f64, j as f64);
                        Point3::new(x + 0.1 * y * y, y, (0.7 * x).sin() * (0.9 * y).cos())
                    })
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, ku, kv, ctrl).unwrap()
    }

    #[test]
    fn original_domain_is_unchanged_and_the_apron_is_c1() {
        let s = wavy();
        let x = s.extended(0.4, 0.25);
        // A valid clamped surface whose domain grew by the widths.
        let x = BSplineSurface::new(
            x.degree_u,
            x.degree_v,
            x.knots_u.clone(),
            x.knots_v.clone(),
            x.ctrl.clone(),
        )
        .unwrap();
        assert_eq!(x.domain_u(), (-0.4, 1.4));
        assert_eq!(x.domain_v(), (1.75, 3.25));
        for i in 0..=10 {
            for j in 0..=10 {
                let (u, v) = (i as f64 / 10.0, 2.0 + j as f64 / 10.0);
                assert!((s.evaluate(u, v) - x.evaluate(u, v)).norm() < 1e-13);
            }
        }
        // The original boundary curves lie on the extended surface.
        for side in Side::LOOP {
            let c = s.boundary_curve(side);
            for k in 0..=8 {
                let t = k as f64 / 8.0;
                let (t0, t1) = c.domain();
                let p = c.evaluate(t0 + t * (t1 - t0));
                let (u, v) = match side {
                    Side::V0 => (t, 2.0),
                    Side::V1 => (t, 3.0),
                    Side::U0 => (0.0, 2.0 + t),
                    Side::U1 => (1.0, 2.0 + t),
                };
                assert!((x.evaluate(u, v) - p).norm() < 1e-13, "{side:?} {t}");
            }
        }
        // C1 across the old boundary u = 0, and straight along the end tangent beyond it.
        let h = 1e-7;
        for v in [2.0, 2.3, 2.9] {
            let d_in = s.derivatives(0.0, v).du;
            let d_out = (x.evaluate(0.0, v) - x.evaluate(-h, v)) / h;
            assert!((d_in - d_out).norm() < 1e-5 * d_in.norm(), "{d_in} {d_out}");
            let far = x.evaluate(-0.4, v);
            let lin = s.evaluate(0.0, v) - d_in * 0.4;
            assert!((far - lin).norm() < 1e-12);
        }
    }

    #[test]
    fn zero_widths_leave_the_surface_alone() {
        let s = wavy();
        assert_eq!(s.extended(0.0, 0.0), s);
        let x = s.extended(0.0, 0.5);
        assert_eq!(x.knots_u, s.knots_u);
        assert_eq!(x.ctrl_dims(), (6, 11));
    }
}
