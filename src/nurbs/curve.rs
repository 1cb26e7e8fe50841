//! Non-rational B-spline curves in 3D and cubic interpolation with clamped end tangents
//! (seed 004 eq. 9-11; Piegl & Tiller §9.2.2).
//!
//! Given points Q_0..Q_S, parameters ū_0 = 0 < ... < ū_S = 1 and end derivatives D_0, D_S
//! (with respect to the unit parameter interval), the cubic with knots
//! `U = {0,0,0,0, ū_1, ..., ū_{S-1}, 1,1,1,1}` (S+7 knots) and S+3 control points P_0..P_{S+2}
//! that interpolates them has
//!
//! ```text
//! P_0 = Q_0,                P_1     = P_0 + (u_4 / 3) D_0                 (u_4 = ū_1)
//! P_{S+2} = Q_S,            P_{S+1} = P_{S+2} - ((1 - u_{S+2}) / 3) D_S   (u_{S+2} = ū_{S-1})
//! a_k P_k + b_k P_{k+1} + c_k P_{k+2} = Q_k,   1 <= k <= S-1              (eq. 10)
//! a_k = N_{k,3}(ū_k), b_k = N_{k+1,3}(ū_k), c_k = N_{k+2,3}(ū_k)
//! ```
//!
//! a tridiagonal system for P_2..P_S (eq. 11). It is solved with the Thomas algorithm, written
//! out here because it is O(S) with no allocation of a dense or banded matrix (faer offers no
//! tridiagonal solver), and because the B-spline collocation matrix is totally positive, so
//! elimination without pivoting is stable (de Boor, "A Practical Guide to Splines", ch. XIII).
//!
//! **Reversal symmetry.** The solve runs in a canonical direction chosen from the data (the
//! lexicographically smaller of the data and its reversal), so interpolating a row and the same
//! row reversed (with [`Params::reversed`] parameters and negated, swapped tangents) gives
//! bit-identical control points in opposite order. Neighbouring patches rely on that for
//! watertight shared edges.

use super::basis::{self, MAX_DEGREE};
use super::params::Params;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::cmp::Ordering;

/// A non-rational B-spline curve with a clamped knot vector. Build values with
/// [`new`](Self::new) or [`interpolate_with_end_tangents`](Self::interpolate_with_end_tangents),
/// which check the invariants evaluation relies on (public fields are for writers and tests).
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineCurve {
    /// Polynomial degree p (1..=7).
    pub degree: usize,
    /// Clamped knot vector, `ctrl.len() + degree + 1` values.
    pub knots: Vec<f64>,
    /// Control points.
    pub ctrl: Vec<Point3<f64>>,
}

impl BSplineCurve {
    /// A curve after checking its knots (clamped, non-decreasing, right count) and that every
    /// control point is finite.
    pub fn new(degree: usize, knots: Vec<f64>, ctrl: Vec<Point3<f64>>) -> Result<BSplineCurve> {
        basis::check_clamped_knots(&knots, degree, ctrl.len())
            .map_err(|m| Error::Degenerate(format!("B-spline curve: {m}")))?;
        if ctrl.iter().any(|p| !p.coords.iter().all(|c| c.is_finite())) {
            return Err(Error::Degenerate(
                "B-spline curve: non-finite control point".into(),
            ));
        }
        Ok(BSplineCurve {
            degree,
            knots,
            ctrl,
        })
    }

    /// Parameter domain `(knots[p], knots[n+1])`.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.ctrl.len()])
    }

    /// C(t) (t is clamped to the domain).
    pub fn evaluate(&self, t: f64) -> Point3<f64> {
        Point3::from(self.derivatives(t, 0)[0])
    }

    /// d^order C / dt^order at t (order 0 gives the point as a vector).
    pub fn derivative(&self, t: f64, order: usize) -> Vector3<f64> {
        if order > MAX_DEGREE {
            return Vector3::zeros();
        }
        self.derivatives(t, order)[order]
    }

    /// C(t) and its derivatives up to `n` (n <= MAX_DEGREE): `out[k]` = C^(k)(t).
    pub fn derivatives(&self, t: f64, n: usize) -> [Vector3<f64>; MAX_DEGREE + 1] {
        let p = self.degree;
        let (a, b) = self.domain();
        let t = t.clamp(a, b);
        let span = basis::find_span(self.ctrl.len(), p, t, &self.knots);
        let d = basis::ders_basis_funs(span, t, p, n.min(MAX_DEGREE), &self.knots);
        let mut out = [Vector3::zeros(); MAX_DEGREE + 1];
        for (k, o) in out.iter_mut().enumerate().take(n.min(p) + 1) {
            for (c, w) in self.ctrl[span - p..=span].iter().zip(&d[k]) {
                *o += c.coords * *w;
            }
        }
        out
    }

    /// The same point set traversed backwards: control points reversed, knots mirrored
    /// (`a + b - k`). For [0, 1] knots on the 2^-40 grid of [`Params`] this is exact.
    pub fn reversed(&self) -> BSplineCurve {
        let (a, b) = self.domain();
        BSplineCurve {
            degree: self.degree,
            knots: self.knots.iter().rev().map(|k| (a + b) - k).collect(),
            ctrl: self.ctrl.iter().rev().copied().collect(),
        }
    }

    /// Largest distance between corresponding control points, or `None` when degree, knots
    /// (within `tol`) or control point counts differ.
    pub fn max_ctrl_distance(&self, other: &BSplineCurve, knot_tol: f64) -> Option<f64> {
        if self.degree != other.degree
            || self.ctrl.len() != other.ctrl.len()
            || self.knots.len() != other.knots.len()
            || self
                .knots
                .iter()
                .zip(&other.knots)
                .any(|(a, b)| (a - b).abs() > knot_tol)
        {
            return None;
        }
        Some(
            self.ctrl
                .iter()
                .zip(&other.ctrl)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max),
        )
    }

    /// The cubic through `points` at `params` with end derivatives `t0` = C'(0), `t1` = C'(1)
    /// (seed 004 eq. 9-11; see the module documentation). `points.len() == params.len()`,
    /// at least 2 points; S+1 points give S+3 control points and S+7 knots.
    pub fn interpolate_with_end_tangents(
        points: &[Point3<f64>],
        params: &Params,
        t0: Vector3<f64>,
        t1: Vector3<f64>,
    ) -> Result<BSplineCurve> {
        let values: Vec<Vector3<f64>> = points.iter().map(|p| p.coords).collect();
        let ctrl = interpolate_coords(&values, params, t0, t1)?;
        Ok(BSplineCurve {
            degree: 3,
            knots: params.cubic_knots(),
            ctrl: ctrl.into_iter().map(Point3::from).collect(),
        })
    }
}

/// Control coordinates of the clamped cubic interpolant of `values` (points or vectors: the
/// problem is linear) at `params` with end derivatives `d0`, `d1`. Runs in the canonical
/// direction (module documentation) so reversed data gives the exactly reversed answer.
pub(crate) fn interpolate_coords(
    values: &[Vector3<f64>],
    params: &Params,
    d0: Vector3<f64>,
    d1: Vector3<f64>,
) -> Result<Vec<Vector3<f64>>> {
    if values.len() != params.len() {
        return Err(Error::Degenerate(format!(
            "{} values but {} parameters",
            values.len(),
            params.len()
        )));
    }
    let finite = |v: &Vector3<f64>| v.iter().all(|c| c.is_finite());
    if !values.iter().all(finite) || !finite(&d0) || !finite(&d1) {
        return Err(Error::Degenerate(
            "non-finite interpolation data (NaN or infinite point or tangent)".into(),
        ));
    }
    if reversed_is_smaller(values, params.as_slice(), &d0, &d1) {
        let rv: Vec<Vector3<f64>> = values.iter().rev().copied().collect();
        let mut c = solve_forward(&rv, &params.reversed(), -d1, -d0)?;
        c.reverse();
        Ok(c)
    } else {
        solve_forward(values, params, d0, d1)
    }
}

fn cmp_vec(a: &Vector3<f64>, b: &Vector3<f64>) -> Ordering {
    a.x.total_cmp(&b.x)
        .then(a.y.total_cmp(&b.y))
        .then(a.z.total_cmp(&b.z))
}

/// Whether the reversed data (values reversed, params mirrored, tangents negated and swapped)
/// is lexicographically smaller than the data as given.
fn reversed_is_smaller(
    v: &[Vector3<f64>],
    t: &[f64],
    d0: &Vector3<f64>,
    d1: &Vector3<f64>,
) -> bool {
    let n = v.len();
    let by_values = (0..n)
        .map(|k| cmp_vec(&v[n - 1 - k], &v[k]))
        .find(|o| o.is_ne());
    let by_params = || {
        (0..n)
            .map(|k| (1.0 - t[n - 1 - k]).total_cmp(&t[k]))
            .find(|o| o.is_ne())
    };
    let by_tangents = || {
        let o = cmp_vec(&-d1, d0).then(cmp_vec(&-d0, d1));
        o.is_ne().then_some(o)
    };
    by_values
        .or_else(by_params)
        .or_else(by_tangents)
        .is_some_and(|o| o == Ordering::Less)
}

/// The eq. 10-11 solve in the given direction.
fn solve_forward(
    q: &[Vector3<f64>],
    params: &Params,
    d0: Vector3<f64>,
    d1: Vector3<f64>,
) -> Result<Vec<Vector3<f64>>> {
    let s = q.len() - 1;
    let knots = params.cubic_knots();
    let n_ctrl = s + 3;
    let mut p = vec![Vector3::zeros(); n_ctrl];
    p[0] = q[0];
    p[1] = q[0] + d0 * (knots[4] / 3.0);
    p[s + 2] = q[s];
    p[s + 1] = q[s] - d1 * ((1.0 - knots[s + 2]) / 3.0);
    if s < 2 {
        return Ok(p);
    }
    // Rows k = 1..=S-1 (index k-1), unknowns P_{k+1}.
    let t = params.as_slice();
    let m = s - 1;
    let mut a = vec![0.0; m];
    let mut b = vec![0.0; m];
    let mut c = vec![0.0; m];
    let mut r = vec![Vector3::zeros(); m];
    for k in 1..=m {
        let span = basis::find_span(n_ctrl, 3, t[k], &knots);
        if span != k + 3 {
            return Err(Error::Numerical(format!(
                "knot span {span} for parameter {k} (expected {})",
                k + 3
            )));
        }
        let n = basis::basis_funs(span, t[k], 3, &knots);
        a[k - 1] = n[0];
        b[k - 1] = n[1];
        c[k - 1] = n[2];
        r[k - 1] = q[k];
    }
    r[0] -= p[1] * a[0];
    r[m - 1] -= p[s + 1] * c[m - 1];
    // Thomas algorithm: forward elimination, then back substitution.
    let mut cp = vec![0.0; m];
    let mut beta = b[0];
    if beta.abs() < 1e-300 {
        return Err(Error::Numerical("singular interpolation system".into()));
    }
    r[0] /= beta;
    for i in 1..m {
        cp[i - 1] = c[i - 1] / beta;
        beta = b[i] - a[i] * cp[i - 1];
        if beta.abs() < 1e-300 || !beta.is_finite() {
            return Err(Error::Numerical("singular interpolation system".into()));
        }
        let prev = r[i - 1];
        r[i] = (r[i] - prev * a[i]) / beta;
    }
    for i in (0..m - 1).rev() {
        let next = r[i + 1];
        r[i] -= next * cp[i];
    }
    p[2..(m + 2)].copy_from_slice(&r[..m]);
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
    }

    fn random_point(seed: &mut u64) -> Point3<f64> {
        Point3::new(
            lcg(seed) * 4.0 - 2.0,
            lcg(seed) * 4.0 - 2.0,
            lcg(seed) * 4.0 - 2.0,
        )
    }

    #[test]
    fn reproduces_a_known_cubic_exactly() {
        let mut seed = 7;
        for s in 1..9 {
            let params = Params::new(
                &(0..=s)
                    .map(|k| k as f64 + 0.6 * lcg(&mut seed))
                    .collect::<Vec<_>>(),
            )
            .unwrap();
            let truth = BSplineCurve::new(
                3,
                params.cubic_knots(),
                (0..s + 3).map(|_| random_point(&mut seed)).collect(),
            )
            .unwrap();
            let pts: Vec<Point3<f64>> = params
                .as_slice()
                .iter()
                .map(|&t| truth.evaluate(t))
                .collect();
            let c = BSplineCurve::interpolate_with_end_tangents(
                &pts,
                &params,
                truth.derivative(0.0, 1),
                truth.derivative(1.0, 1),
            )
            .unwrap();
            assert_eq!(c.knots.len(), s + 7);
            for (a, b) in c.ctrl.iter().zip(&truth.ctrl) {
                assert!((a - b).norm() < 1e-10, "S={s}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn interpolates_points_and_tangents() {
        let pts: Vec<Point3<f64>> = (0..7)
            .map(|k| {
                let a = k as f64 * 0.5;
                Point3::new(a.cos(), a.sin(), 0.2 * a)
            })
            .collect();
        let params = Params::sqrt_chord(&pts).unwrap();
        let t0 = Vector3::new(0.0, 2.0, 0.5);
        let t1 = Vector3::new(-1.0, -0.3, 0.5);
        let c = BSplineCurve::interpolate_with_end_tangents(&pts, &params, t0, t1).unwrap();
        for (p, &t) in pts.iter().zip(params.as_slice()) {
            assert!((c.evaluate(t) - p).norm() < 1e-13);
        }
        assert!((c.derivative(0.0, 1) - t0).norm() < 1e-12);
        assert!((c.derivative(1.0, 1) - t1).norm() < 1e-12);
    }

    #[test]
    fn reversed_data_gives_bit_identical_reversed_curve() {
        let pts: Vec<Point3<f64>> = (0..6)
            .map(|k| {
                let a = k as f64 * 0.41 + 0.1;
                Point3::new(a.sin() * 3.3, a * a, (2.0 * a).cos())
            })
            .collect();
        let params = Params::sqrt_chord(&pts).unwrap();
        let (t0, t1) = (Vector3::new(0.3, 1.1, -0.7), Vector3::new(1.9, -0.2, 0.4));
        let fwd = BSplineCurve::interpolate_with_end_tangents(&pts, &params, t0, t1).unwrap();
        let rev_pts: Vec<Point3<f64>> = pts.iter().rev().copied().collect();
        let bwd =
            BSplineCurve::interpolate_with_end_tangents(&rev_pts, &params.reversed(), -t1, -t0)
                .unwrap();
        assert_eq!(fwd.reversed(), bwd);
        assert_eq!(bwd.reversed(), fwd);
    }

    #[test]
    fn evaluation_matches_truck_geometry() {
        use truck_geometry::prelude as tg;
        use truck_geometry::prelude::ParametricCurve;
        let mut seed = 3;
        let params = Params::new(&[0.0, 0.3, 0.45, 0.8, 1.0]).unwrap();
        let c = BSplineCurve::new(
            3,
            params.cubic_knots(),
            (0..7).map(|_| random_point(&mut seed)).collect(),
        )
        .unwrap();
        let tc = tg::BSplineCurve::new(
            tg::KnotVec::from(c.knots.clone()),
            c.ctrl
                .iter()
                .map(|p| tg::Point3::new(p.x, p.y, p.z))
                .collect(),
        );
        for k in 0..=20 {
            let t = k as f64 / 20.0;
            let (a, b) = (c.evaluate(t), tc.subs(t));
            assert!((a.x - b.x).abs() + (a.y - b.y).abs() + (a.z - b.z).abs() < 1e-12);
            let (da, db) = (c.derivative(t, 1), tc.der(t));
            assert!((da.x - db.x).abs() + (da.y - db.y).abs() + (da.z - db.z).abs() < 1e-10);
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let params = Params::uniform(2).unwrap();
        let p = Point3::origin();
        let z = Vector3::zeros();
        assert!(BSplineCurve::interpolate_with_end_tangents(&[p, p], &params, z, z).is_err());
        let nan = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(BSplineCurve::interpolate_with_end_tangents(&[p, nan, p], &params, z, z).is_err());
        assert!(BSplineCurve::new(3, vec![0.0, 1.0], vec![p]).is_err());
    }
}
