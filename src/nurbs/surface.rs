//! Tensor-product B-spline surfaces: evaluation, derivatives, normals, point inversion and
//! bicubic interpolation of a grid with clamped boundary tangents (seed 004 eq. 4 with unit
//! weights, and eq. 9-14).
//!
//! `S(u, v) = Σ_i Σ_j N_{i,p}(u) N_{j,q}(v) P_{i,j}` (eq. 4 with all w_{i,j} = 1: scansurf's
//! patches are polynomial; STEP and IGES receive them as such).

use super::basis::{self, MAX_DEGREE};
use super::curve::{interpolate_coords, BSplineCurve};
use super::params::Params;
use crate::{Error, Result};
use nalgebra::{Matrix2, Point3, Vector2, Vector3};

/// A non-rational B-spline surface with clamped knot vectors. `ctrl[i][j]` is the control point
/// with index i along u and j along v (`ctrl.len()` = n_u, every row n_v long).
///
/// The fields are public for the writers and for tests; build values with [`new`](Self::new)
/// or [`interpolate_grid`](Self::interpolate_grid), which check the invariants that
/// evaluation relies on (a hand-built value with inconsistent knots can panic when evaluated;
/// [`PatchNetwork::validate`](super::PatchNetwork::validate) rejects it before export).
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSurface {
    pub degree_u: usize,
    pub degree_v: usize,
    pub knots_u: Vec<f64>,
    pub knots_v: Vec<f64>,
    pub ctrl: Vec<Vec<Point3<f64>>>,
}

/// One side of a patch's parameter rectangle, listed in boundary-loop order: the loop runs
/// counter-clockwise around the surface normal `S_u × S_v`: V0 with u increasing, U1 with v
/// increasing, V1 with u decreasing, U0 with v decreasing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// v = v_min.
    V0,
    /// u = u_max.
    U1,
    /// v = v_max.
    V1,
    /// u = u_min.
    U0,
}

impl Side {
    /// The four sides in boundary-loop order.
    pub const LOOP: [Side; 4] = [Side::V0, Side::U1, Side::V1, Side::U0];

    /// Whether the boundary loop traverses this side against its parameter direction
    /// (V1 and U0 do).
    pub fn loop_reversed(self) -> bool {
        matches!(self, Side::V1 | Side::U0)
    }
}

/// Mixed second derivative `∂²S/∂u∂v` at the four corners, for the v-direction tangent curves
/// of [`BSplineSurface::interpolate_grid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Twist {
    /// Estimate from the boundary tangents by one-sided finite differences: at a corner, the
    /// average of d/du of the given ∂Q/∂v along the v-side and d/dv of the given ∂Q/∂u along
    /// the u-side (three-point differences when three samples exist, else two-point). This is
    /// the default: it reproduces a bilinear twist exactly and avoids the flat spots of
    /// Ferguson's zero twist.
    Estimate,
    /// Ferguson's zero twist (flat spots near the corners; for comparison).
    Zero,
    /// Exact twists at the corners (u, v) = (0,0), (1,0), (0,1), (1,1).
    Given([Vector3<f64>; 4]),
}

/// The data of one patch for [`BSplineSurface::interpolate_grid`]: an (S+1) x (T+1) grid of
/// points and the boundary tangents. Tangents are derivatives with respect to the unit
/// parameter interval of the patch ([0, 1] in u and in v).
#[derive(Debug, Clone, PartialEq)]
pub struct PatchGrid {
    /// `points[k][j]` = Q_{k,j}: k = 0..=S along u, j = 0..=T along v.
    pub points: Vec<Vec<Point3<f64>>>,
    /// ∂Q/∂u at u = 0 for j = 0..=T (the u = 0 column).
    pub du_u0: Vec<Vector3<f64>>,
    /// ∂Q/∂u at u = 1 for j = 0..=T.
    pub du_u1: Vec<Vector3<f64>>,
    /// ∂Q/∂v at v = 0 for k = 0..=S (the v = 0 row).
    pub dv_v0: Vec<Vector3<f64>>,
    /// ∂Q/∂v at v = 1 for k = 0..=S.
    pub dv_v1: Vec<Vector3<f64>>,
    /// Corner twists.
    pub twist: Twist,
}

/// A point, its first and second partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceDerivatives {
    pub point: Point3<f64>,
    pub du: Vector3<f64>,
    pub dv: Vector3<f64>,
    pub duu: Vector3<f64>,
    pub duv: Vector3<f64>,
    pub dvv: Vector3<f64>,
}

/// Result of a point inversion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    pub u: f64,
    pub v: f64,
    pub point: Point3<f64>,
    pub distance: f64,
}

impl BSplineSurface {
    /// A surface after checking both knot vectors, the control grid's shape and finiteness.
    pub fn new(
        degree_u: usize,
        degree_v: usize,
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        ctrl: Vec<Vec<Point3<f64>>>,
    ) -> Result<BSplineSurface> {
        let nv = ctrl.first().map_or(0, Vec::len);
        if ctrl.iter().any(|r| r.len() != nv) {
            return Err(Error::Degenerate(
                "B-spline surface: ragged control grid".into(),
            ));
        }
        basis::check_clamped_knots(&knots_u, degree_u, ctrl.len())
            .map_err(|m| Error::Degenerate(format!("B-spline surface, u: {m}")))?;
        basis::check_clamped_knots(&knots_v, degree_v, nv)
            .map_err(|m| Error::Degenerate(format!("B-spline surface, v: {m}")))?;
        if ctrl
            .iter()
            .flatten()
            .any(|p| !p.coords.iter().all(|c| c.is_finite()))
        {
            return Err(Error::Degenerate(
                "B-spline surface: non-finite control point".into(),
            ));
        }
        Ok(BSplineSurface {
            degree_u,
            degree_v,
            knots_u,
            knots_v,
            ctrl,
        })
    }

    /// Number of control points along u and along v.
    pub fn ctrl_dims(&self) -> (usize, usize) {
        (self.ctrl.len(), self.ctrl.first().map_or(0, Vec::len))
    }

    /// Parameter domain along u.
    pub fn domain_u(&self) -> (f64, f64) {
        (self.knots_u[self.degree_u], self.knots_u[self.ctrl.len()])
    }

    /// Parameter domain along v.
    pub fn domain_v(&self) -> (f64, f64) {
        let nv = self.ctrl_dims().1;
        (self.knots_v[self.degree_v], self.knots_v[nv])
    }

    fn clamp_uv(&self, u: f64, v: f64) -> (f64, f64) {
        let (u0, u1) = self.domain_u();
        let (v0, v1) = self.domain_v();
        (u.clamp(u0, u1), v.clamp(v0, v1))
    }

    /// S(u, v) (parameters clamped to the domain).
    pub fn evaluate(&self, u: f64, v: f64) -> Point3<f64> {
        let (u, v) = self.clamp_uv(u, v);
        let (p, q) = (self.degree_u, self.degree_v);
        let (nu, nv) = self.ctrl_dims();
        let su = basis::find_span(nu, p, u, &self.knots_u);
        let sv = basis::find_span(nv, q, v, &self.knots_v);
        let bu = basis::basis_funs(su, u, p, &self.knots_u);
        let bv = basis::basis_funs(sv, v, q, &self.knots_v);
        let mut acc = Vector3::zeros();
        for (r, wu) in bu.iter().enumerate().take(p + 1) {
            let row = &self.ctrl[su - p + r];
            let mut t = Vector3::zeros();
            for (s, wv) in bv.iter().enumerate().take(q + 1) {
                t += row[sv - q + s].coords * *wv;
            }
            acc += t * *wu;
        }
        Point3::from(acc)
    }

    /// S and its partial derivatives up to second order at (u, v) (clamped to the domain).
    pub fn derivatives(&self, u: f64, v: f64) -> SurfaceDerivatives {
        let (u, v) = self.clamp_uv(u, v);
        let (p, q) = (self.degree_u, self.degree_v);
        let (nu, nv) = self.ctrl_dims();
        let su = basis::find_span(nu, p, u, &self.knots_u);
        let sv = basis::find_span(nv, q, v, &self.knots_v);
        let du = basis::ders_basis_funs(su, u, p, 2, &self.knots_u);
        let dv = basis::ders_basis_funs(sv, v, q, 2, &self.knots_v);
        // temp[l][r] = Σ_s N_s^(l)(v) P[su-p+r][sv-q+s]
        let mut temp = [[Vector3::zeros(); MAX_DEGREE + 1]; 3];
        for r in 0..=p {
            let row = &self.ctrl[su - p + r];
            for s in 0..=q {
                let c = row[sv - q + s].coords;
                for (l, t) in temp.iter_mut().enumerate() {
                    t[r] += c * dv[l][s];
                }
            }
        }
        let comb = |k: usize, l: usize| -> Vector3<f64> {
            (0..=p).fold(Vector3::zeros(), |a, r| a + temp[l][r] * du[k][r])
        };
        SurfaceDerivatives {
            point: Point3::from(comb(0, 0)),
            du: comb(1, 0),
            dv: comb(0, 1),
            duu: comb(2, 0),
            duv: comb(1, 1),
            dvv: comb(0, 2),
        }
    }

    /// Unit normal `S_u × S_v / |S_u × S_v|`, or `None` where the surface is degenerate.
    pub fn normal(&self, u: f64, v: f64) -> Option<Vector3<f64>> {
        let d = self.derivatives(u, v);
        let n = d.du.cross(&d.dv);
        let len = n.norm();
        let scale = d.du.norm() * d.dv.norm();
        (len > 1e-12 * scale && len.is_finite()).then(|| n / len)
    }

    /// The boundary curve on `side`, in its parameter direction (increasing u or v): the
    /// boundary row or column of control points with that direction's knots. Reverse it for the
    /// loop when [`Side::loop_reversed`].
    pub fn boundary_curve(&self, side: Side) -> BSplineCurve {
        let (nu, nv) = self.ctrl_dims();
        match side {
            Side::V0 | Side::V1 => {
                let j = if side == Side::V0 { 0 } else { nv - 1 };
                BSplineCurve {
                    degree: self.degree_u,
                    knots: self.knots_u.clone(),
                    ctrl: self.ctrl.iter().map(|row| row[j]).collect(),
                }
            }
            Side::U0 | Side::U1 => {
                let i = if side == Side::U0 { 0 } else { nu - 1 };
                BSplineCurve {
                    degree: self.degree_v,
                    knots: self.knots_v.clone(),
                    ctrl: self.ctrl[i].clone(),
                }
            }
        }
    }

    /// Lower and upper corners of the control points' bounding box, which holds the surface
    /// (convex hull property).
    pub fn ctrl_bounds(&self) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for p in self.ctrl.iter().flatten() {
            lo = lo.inf(&p.coords);
            hi = hi.sup(&p.coords);
        }
        (lo, hi)
    }

    /// Diagonal of the control points' bounding box (a size scale for tolerances).
    pub fn ctrl_extent(&self) -> f64 {
        let (lo, hi) = self.ctrl_bounds();
        (hi - lo).norm()
    }

    /// Bicubic interpolation of a point grid with clamped boundary tangents (seed 004
    /// eq. 9-14): (S+1) x (T+1) points give (S+3) x (T+3) control points with knot vectors
    /// `u.cubic_knots()` (S+7 knots) and `v.cubic_knots()` (T+7).
    ///
    /// 1. u-pass (eq. 9-11): every row j = 0..=T is interpolated along u through
    ///    Q_{0..=S, j} with end tangents `du_u0[j]`, `du_u1[j]`, giving rows of S+3 control
    ///    points R_{i,j}.
    /// 2. The v-tangents along v = 0 and v = 1 are interpolated along u the same way (they are
    ///    vectors; the problem is linear), with the corner twists as end derivatives, giving
    ///    S+3 control vectors V0_i and V1_i: the end conditions of eq. 12-14 for every control
    ///    column, not only at the data columns.
    /// 3. v-pass (eq. 12-14): every column i = 0..=S+2 is interpolated along v through
    ///    R_{i, 0..=T} with end tangents V0_i, V1_i.
    ///
    /// The parameters are the caller's ([`Params`]), one vector per direction for the whole
    /// patch: seed 004 uses per-row square-root chord parameters, which a tensor-product
    /// surface cannot represent; pass [`Params::average_sqrt_chord`] of the rows for the
    /// paper's behaviour, or parameters chosen per edge for a watertight network.
    ///
    /// **Watertightness.** Each boundary curve depends only on that edge's data: the V0 side is
    /// the u-interpolation of `points[..][0]` with end tangents `du_u0[0]`, `du_u1[0]` and knots
    /// from `u` (the v-pass keeps the first and last control rows: clamped interpolation puts
    /// P_0 = Q_0 and P_{T+2} = Q_T); the U0 side is the v-interpolation of `points[0][..]` with
    /// end tangents `dv_v0[0]`, `dv_v1[0]` and knots from `v`; likewise V1 and U1. Since the
    /// curve interpolation is reversal-symmetric, two patches given the same edge data (in
    /// either direction) get bit-identical boundary control points. The twist and the cross
    /// tangents only move the control rows next to the boundary.
    pub fn interpolate_grid(grid: &PatchGrid, u: &Params, v: &Params) -> Result<BSplineSurface> {
        let s1 = grid.points.len();
        let t1 = grid.points.first().map_or(0, Vec::len);
        if s1 != u.len() || t1 != v.len() {
            return Err(Error::Degenerate(format!(
                "grid of {s1} x {t1} points but {} x {} parameters",
                u.len(),
                v.len()
            )));
        }
        if grid.points.iter().any(|r| r.len() != t1) {
            return Err(Error::Degenerate("ragged interpolation grid".into()));
        }
        if grid.du_u0.len() != t1
            || grid.du_u1.len() != t1
            || grid.dv_v0.len() != s1
            || grid.dv_v1.len() != s1
        {
            return Err(Error::Degenerate(
                "boundary tangent counts do not match the grid".into(),
            ));
        }
        let twist = match grid.twist {
            Twist::Given(t) => t,
            Twist::Zero => [Vector3::zeros(); 4],
            Twist::Estimate => estimate_twists(grid, u, v),
        };
        // 1. u-pass: rows[j][i].
        let rows: Vec<Vec<Vector3<f64>>> = (0..t1)
            .map(|j| {
                let q: Vec<Vector3<f64>> = grid.points.iter().map(|r| r[j].coords).collect();
                interpolate_coords(&q, u, grid.du_u0[j], grid.du_u1[j])
            })
            .collect::<Result<_>>()?;
        // 2. v-tangent curves along the v = 0 and v = 1 sides.
        let tv0 = interpolate_coords(&grid.dv_v0, u, twist[0], twist[1])?;
        let tv1 = interpolate_coords(&grid.dv_v1, u, twist[2], twist[3])?;
        // 3. v-pass: columns.
        let n_u = s1 + 2;
        let ctrl: Vec<Vec<Point3<f64>>> = (0..n_u)
            .map(|i| {
                let q: Vec<Vector3<f64>> = rows.iter().map(|r| r[i]).collect();
                interpolate_coords(&q, v, tv0[i], tv1[i])
                    .map(|c| c.into_iter().map(Point3::from).collect())
            })
            .collect::<Result<_>>()?;
        BSplineSurface::new(3, 3, u.cubic_knots(), v.cubic_knots(), ctrl)
    }

    /// Point inversion: the surface point closest to `p`, by Newton's method on
    /// `f = (S - p)·S_u = 0`, `g = (S - p)·S_v = 0` (Piegl & Tiller §6.1) from `initial_uv`,
    /// with parameters clamped to the domain and step halving whenever a step does not reduce
    /// the distance. Stops when the distance, the cosines between `S - p` and the tangents, or
    /// the step fall below 1e-12 (relative to the patch size), or after 50 iterations; returns
    /// the best point found.
    pub fn closest_point(&self, p: &Point3<f64>, initial_uv: (f64, f64)) -> ClosestPoint {
        let size = self.ctrl_extent().max(f64::MIN_POSITIVE);
        let eps = 1e-12 * size;
        let (mut u, mut v) = self.clamp_uv(initial_uv.0, initial_uv.1);
        let mut d = self.derivatives(u, v);
        let mut best = ClosestPoint {
            u,
            v,
            point: d.point,
            distance: (d.point - p).norm(),
        };
        for _ in 0..50 {
            let r = d.point - p;
            let dist = r.norm();
            if dist <= eps {
                break;
            }
            let (fu, fv) = (r.dot(&d.du), r.dot(&d.dv));
            let cu = fu.abs() / (d.du.norm() * dist).max(f64::MIN_POSITIVE);
            let cv = fv.abs() / (d.dv.norm() * dist).max(f64::MIN_POSITIVE);
            if cu <= 1e-12 && cv <= 1e-12 {
                break;
            }
            let j = Matrix2::new(
                d.du.norm_squared() + r.dot(&d.duu),
                d.du.dot(&d.dv) + r.dot(&d.duv),
                d.du.dot(&d.dv) + r.dot(&d.duv),
                d.dv.norm_squared() + r.dot(&d.dvv),
            );
            let g = Vector2::new(fu, fv);
            // Newton step; a gradient step where the Hessian is not positive definite.
            let step = match j.try_inverse() {
                Some(inv) if j.determinant() > 0.0 && j[(0, 0)] > 0.0 => -(inv * g),
                _ => {
                    let h = Matrix2::new(
                        d.du.norm_squared(),
                        d.du.dot(&d.dv),
                        d.du.dot(&d.dv),
                        d.dv.norm_squared(),
                    );
                    match h.try_inverse() {
                        Some(inv) => -(inv * g),
                        None => break,
                    }
                }
            };
            let mut accepted = false;
            let mut scale = 1.0;
            for _ in 0..30 {
                let (nu, nv) = self.clamp_uv(u + scale * step.x, v + scale * step.y);
                let nd = self.derivatives(nu, nv);
                let ndist = (nd.point - p).norm();
                if ndist <= dist {
                    let moved = (nd.point - d.point).norm();
                    u = nu;
                    v = nv;
                    d = nd;
                    accepted = moved > eps;
                    break;
                }
                scale *= 0.5;
            }
            let dist_now = (d.point - p).norm();
            if dist_now < best.distance {
                best = ClosestPoint {
                    u,
                    v,
                    point: d.point,
                    distance: dist_now,
                };
            }
            if !accepted {
                break;
            }
        }
        best
    }

    /// [`closest_point`](Self::closest_point) started from the nearest of a grid of samples
    /// (`samples_per_span` per knot span and direction, at least 1): a global search for when
    /// no good initial guess is known.
    pub fn closest_point_global(&self, p: &Point3<f64>, samples_per_span: usize) -> ClosestPoint {
        let grid = |knots: &[f64], deg: usize, n: usize| -> Vec<f64> {
            let spans = &knots[deg..=n];
            let mut out = Vec::new();
            let m = samples_per_span.max(1);
            for w in spans.windows(2) {
                if w[1] > w[0] {
                    for k in 0..m {
                        out.push(w[0] + (w[1] - w[0]) * (k as f64 + 0.5) / m as f64);
                    }
                }
            }
            out.push(knots[deg]);
            out.push(knots[n]);
            out
        };
        let (nu, nv) = self.ctrl_dims();
        let us = grid(&self.knots_u, self.degree_u, nu);
        let vs = grid(&self.knots_v, self.degree_v, nv);
        let mut start = (us[0], vs[0]);
        let mut best = f64::INFINITY;
        for &u in &us {
            for &v in &vs {
                let d = (self.evaluate(u, v) - p).norm_squared();
                if d < best {
                    best = d;
                    start = (u, v);
                }
            }
        }
        self.closest_point(p, start)
    }
}

/// d/dt at t_0 = 0 (or at t_n = 1 when `at_end`) of samples f_k at parameters t_k: the
/// derivative of the parabola through the three end samples, or the chord slope with two.
pub fn end_slope(f: &[Vector3<f64>], t: &[f64], at_end: bool) -> Vector3<f64> {
    let n = f.len();
    // Work from the chosen end inward, with signed steps.
    let (i0, i1, i2) = if at_end {
        (n - 1, n - 2, n.wrapping_sub(3))
    } else {
        (0, 1, 2)
    };
    let h1 = t[i1] - t[i0];
    if n < 3 {
        return (f[i1] - f[i0]) / h1;
    }
    let h2 = t[i2] - t[i0];
    // Lagrange derivative at t[i0] of the parabola through (0, f0), (h1, f1), (h2, f2).
    f[i0] * (-(h1 + h2) / (h1 * h2)) + f[i1] * (h2 / (h1 * (h2 - h1)))
        - f[i2] * (h1 / (h2 * (h2 - h1)))
}

/// Corner twists estimated from the boundary tangents ([`Twist::Estimate`]), in the corner
/// order of [`Twist::Given`].
pub fn estimate_twists(grid: &PatchGrid, u: &Params, v: &Params) -> [Vector3<f64>; 4] {
    let (us, vs) = (u.as_slice(), v.as_slice());
    let c = |along_u: &[Vector3<f64>], u_end: bool, along_v: &[Vector3<f64>], v_end: bool| {
        (end_slope(along_u, us, u_end) + end_slope(along_v, vs, v_end)) * 0.5
    };
    [
        c(&grid.dv_v0, false, &grid.du_u0, false),
        c(&grid.dv_v0, true, &grid.du_u1, false),
        c(&grid.dv_v1, false, &grid.du_u0, true),
        c(&grid.dv_v1, true, &grid.du_u1, true),
    ]
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

    fn random_params(n: usize, seed: &mut u64) -> Params {
        Params::new(
            &(0..=n)
                .map(|k| k as f64 + 0.7 * lcg(seed))
                .collect::<Vec<_>>(),
        )
        .unwrap()
    }

    fn random_surface(u: &Params, v: &Params, seed: &mut u64) -> BSplineSurface {
        let ctrl = (0..u.len() + 2)
            .map(|i| {
                (0..v.len() + 2)
                    .map(|j| {
                        Point3::new(
                            i as f64 + 0.4 * lcg(seed),
                            j as f64 + 0.4 * lcg(seed),
                            2.0 * lcg(seed) - 1.0,
                        )
                    })
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, u.cubic_knots(), v.cubic_knots(), ctrl).unwrap()
    }

    /// The grid data of a known surface sampled at the parameters, with true tangents.
    fn sample(s: &BSplineSurface, u: &Params, v: &Params, twist: Twist) -> PatchGrid {
        let (us, vs) = (u.as_slice(), v.as_slice());
        PatchGrid {
            points: us
                .iter()
                .map(|&a| vs.iter().map(|&b| s.evaluate(a, b)).collect())
                .collect(),
            du_u0: vs.iter().map(|&b| s.derivatives(0.0, b).du).collect(),
            du_u1: vs.iter().map(|&b| s.derivatives(1.0, b).du).collect(),
            dv_v0: us.iter().map(|&a| s.derivatives(a, 0.0).dv).collect(),
            dv_v1: us.iter().map(|&a| s.derivatives(a, 1.0).dv).collect(),
            twist,
        }
    }

    fn exact_twist(s: &BSplineSurface) -> Twist {
        Twist::Given([
            s.derivatives(0.0, 0.0).duv,
            s.derivatives(1.0, 0.0).duv,
            s.derivatives(0.0, 1.0).duv,
            s.derivatives(1.0, 1.0).duv,
        ])
    }

    #[test]
    fn reproduces_a_known_bicubic_exactly() {
        let mut seed = 11;
        for (sn, tn) in [(1, 1), (2, 3), (4, 4), (6, 3)] {
            let u = random_params(sn, &mut seed);
            let v = random_params(tn, &mut seed);
            let truth = random_surface(&u, &v, &mut seed);
            let grid = sample(&truth, &u, &v, exact_twist(&truth));
            let s = BSplineSurface::interpolate_grid(&grid, &u, &v).unwrap();
            assert_eq!(s.ctrl_dims(), (sn + 3, tn + 3));
            assert_eq!(s.knots_u.len(), sn + 7);
            let mut worst: f64 = 0.0;
            for (ra, rb) in s.ctrl.iter().zip(&truth.ctrl) {
                for (a, b) in ra.iter().zip(rb) {
                    worst = worst.max((a - b).norm());
                }
            }
            assert!(worst < 1e-10, "{sn}x{tn}: control points off by {worst}");
        }
    }

    #[test]
    fn passes_through_points_and_matches_tangents_with_estimated_twist() {
        let mut seed = 5;
        let u = random_params(5, &mut seed);
        let v = random_params(4, &mut seed);
        let truth = random_surface(&u, &v, &mut seed);
        let grid = sample(&truth, &u, &v, Twist::Estimate);
        let s = BSplineSurface::interpolate_grid(&grid, &u, &v).unwrap();
        for (k, &a) in u.as_slice().iter().enumerate() {
            for (j, &b) in v.as_slice().iter().enumerate() {
                let e = (s.evaluate(a, b) - grid.points[k][j]).norm();
                assert!(e < 1e-12, "point ({k},{j}) off by {e}");
            }
            let e0 = (s.derivatives(a, 0.0).dv - grid.dv_v0[k]).norm();
            let e1 = (s.derivatives(a, 1.0).dv - grid.dv_v1[k]).norm();
            assert!(e0 < 1e-10 && e1 < 1e-10, "dv at u={a}: {e0} {e1}");
        }
        for (j, &b) in v.as_slice().iter().enumerate() {
            let e0 = (s.derivatives(0.0, b).du - grid.du_u0[j]).norm();
            let e1 = (s.derivatives(1.0, b).du - grid.du_u1[j]).norm();
            assert!(e0 < 1e-10 && e1 < 1e-10, "du at v={b}: {e0} {e1}");
        }
    }

    #[test]
    fn estimated_twist_is_exact_for_a_bilinear_twist() {
        // Q(u, v) = (u, v, u v): the twist is constant (0, 0, 1).
        let u = Params::uniform(3).unwrap();
        let v = Params::new(&[0.0, 0.3, 0.7, 1.0]).unwrap();
        let f = |a: f64, b: f64| Point3::new(a, b, a * b);
        let grid = PatchGrid {
            points: u
                .as_slice()
                .iter()
                .map(|&a| v.as_slice().iter().map(|&b| f(a, b)).collect())
                .collect(),
            du_u0: v
                .as_slice()
                .iter()
                .map(|&b| Vector3::new(1.0, 0.0, b))
                .collect(),
            du_u1: v
                .as_slice()
                .iter()
                .map(|&b| Vector3::new(1.0, 0.0, b))
                .collect(),
            dv_v0: u
                .as_slice()
                .iter()
                .map(|&a| Vector3::new(0.0, 1.0, a))
                .collect(),
            dv_v1: u
                .as_slice()
                .iter()
                .map(|&a| Vector3::new(0.0, 1.0, a))
                .collect(),
            twist: Twist::Estimate,
        };
        let tw = estimate_twists(&grid, &u, &v);
        for t in tw {
            assert!((t - Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-12, "{t}");
        }
        let s = BSplineSurface::interpolate_grid(&grid, &u, &v).unwrap();
        for k in 0..=10 {
            for l in 0..=10 {
                let (a, b) = (k as f64 / 10.0, l as f64 / 10.0);
                assert!((s.evaluate(a, b) - f(a, b)).norm() < 1e-13);
            }
        }
    }

    #[test]
    fn evaluation_matches_truck_geometry() {
        use truck_geometry::prelude as tg;
        use truck_geometry::prelude::ParametricSurface;
        let mut seed = 21;
        let u = random_params(3, &mut seed);
        let v = random_params(2, &mut seed);
        let s = random_surface(&u, &v, &mut seed);
        let ts = tg::BSplineSurface::new(
            (
                tg::KnotVec::from(s.knots_u.clone()),
                tg::KnotVec::from(s.knots_v.clone()),
            ),
            s.ctrl
                .iter()
                .map(|r| r.iter().map(|p| tg::Point3::new(p.x, p.y, p.z)).collect())
                .collect(),
        );
        for k in 0..=8 {
            for l in 0..=8 {
                let (a, b) = (k as f64 / 8.0, l as f64 / 8.0);
                let p = s.evaluate(a, b);
                let q = ts.subs(a, b);
                assert!((p.x - q.x).abs() + (p.y - q.y).abs() + (p.z - q.z).abs() < 1e-12);
                let d = s.derivatives(a, b);
                let (qu, qv) = (ts.uder(a, b), ts.vder(a, b));
                assert!(
                    (d.du.x - qu.x).abs() + (d.du.y - qu.y).abs() + (d.du.z - qu.z).abs() < 1e-10
                );
                assert!(
                    (d.dv.x - qv.x).abs() + (d.dv.y - qv.y).abs() + (d.dv.z - qv.z).abs() < 1e-10
                );
            }
        }
    }

    #[test]
    fn second_derivatives_match_finite_differences() {
        let mut seed = 8;
        let u = random_params(3, &mut seed);
        let v = random_params(3, &mut seed);
        let s = random_surface(&u, &v, &mut seed);
        let h = 1e-5;
        for &(a, b) in &[(0.31, 0.62), (0.77, 0.13)] {
            let d = s.derivatives(a, b);
            let duv = (s.derivatives(a, b + h).du - s.derivatives(a, b - h).du) / (2.0 * h);
            let duu = (s.derivatives(a + h, b).du - s.derivatives(a - h, b).du) / (2.0 * h);
            let dvv = (s.derivatives(a, b + h).dv - s.derivatives(a, b - h).dv) / (2.0 * h);
            assert!((d.duv - duv).norm() < 1e-5, "{} vs {}", d.duv, duv);
            assert!((d.duu - duu).norm() < 1e-5);
            assert!((d.dvv - dvv).norm() < 1e-5);
        }
    }

    #[test]
    fn shared_edge_gives_identical_boundary_curves() {
        // Two patches of one smooth surface meet along the curve v = 0 of patch A; patch B runs
        // along the same edge backwards as its U0 side (v decreasing along A's u). Both are
        // given the edge's data computed once; the interiors differ.
        let f = |a: f64, b: f64| {
            Point3::new(
                a * 2.0,
                b * 1.5 + 0.3 * (3.0 * a).sin(),
                (a + b).cos() * 0.7,
            )
        };
        let fu = |a: f64, b: f64| Vector3::new(2.0, 0.9 * (3.0 * a).cos(), -(a + b).sin() * 0.7);
        let fv = |a: f64, b: f64| Vector3::new(0.0, 1.5, -(a + b).sin() * 0.7);
        let edge_u = Params::sqrt_chord(
            &(0..=4)
                .map(|k| f(k as f64 / 4.0 + 0.01 * (k * k) as f64, 0.0))
                .collect::<Vec<_>>(),
        )
        .unwrap();
        let other = Params::new(&[0.0, 0.4, 0.75, 1.0]).unwrap();
        // Patch A: u = edge parameter, v in [0, 1] upwards.
        let ga = PatchGrid {
            points: edge_u
                .as_slice()
                .iter()
                .map(|&a| other.as_slice().iter().map(|&b| f(a, b)).collect())
                .collect(),
            du_u0: other.as_slice().iter().map(|&b| fu(0.0, b)).collect(),
            du_u1: other.as_slice().iter().map(|&b| fu(1.0, b)).collect(),
            dv_v0: edge_u.as_slice().iter().map(|&a| fv(a, 0.0)).collect(),
            dv_v1: edge_u.as_slice().iter().map(|&a| fv(a, 1.0)).collect(),
            twist: Twist::Estimate,
        };
        // Patch B below the edge: B(u', v') = f(1 - v', -u'), so B's U0 side (u' = 0) is the
        // edge run backwards; its v' parameters are the edge's reversed.
        let bv = edge_u.reversed();
        let bu = Params::new(&[0.0, 0.5, 1.0]).unwrap();
        let mut pts_b = vec![vec![Point3::origin(); bv.len()]; bu.len()];
        for (k, &a) in bu.as_slice().iter().enumerate() {
            for (j, &b) in bv.as_slice().iter().enumerate() {
                pts_b[k][j] = if k == 0 {
                    ga.points[bv.len() - 1 - j][0] // the shared edge's samples, reversed
                } else {
                    f(1.0 - b, -a)
                };
            }
        }
        let gb = PatchGrid {
            points: pts_b,
            // dB/du' = -f_v; on the shared edge these are the cross tangents.
            du_u0: bv.as_slice().iter().map(|&b| -fv(1.0 - b, 0.0)).collect(),
            du_u1: bv.as_slice().iter().map(|&b| -fv(1.0 - b, -1.0)).collect(),
            // dB/dv' = -f_u; at the shared edge's ends these are the edge's end tangents,
            // taken from patch A's data (the same numbers, negated).
            dv_v0: bu
                .as_slice()
                .iter()
                .enumerate()
                .map(|(k, &a)| if k == 0 { -ga.du_u1[0] } else { -fu(1.0, -a) })
                .collect(),
            dv_v1: bu
                .as_slice()
                .iter()
                .enumerate()
                .map(|(k, &a)| if k == 0 { -ga.du_u0[0] } else { -fu(0.0, -a) })
                .collect(),
            twist: Twist::Estimate,
        };
        let sa = BSplineSurface::interpolate_grid(&ga, &edge_u, &other).unwrap();
        let sb = BSplineSurface::interpolate_grid(&gb, &bu, &bv).unwrap();
        let ea = sa.boundary_curve(Side::V0);
        let eb = sb.boundary_curve(Side::U0);
        assert_eq!(
            ea.ctrl,
            eb.reversed().ctrl,
            "control points must be bit-identical"
        );
        assert_eq!(ea, eb.reversed());
        // And the interiors really differ (the test is not trivially satisfied).
        assert!((sa.ctrl[1][1] - sb.ctrl[1][1]).norm() > 0.1);
    }

    #[test]
    fn closest_point_inverts_evaluation() {
        let mut seed = 99;
        let u = random_params(3, &mut seed);
        let v = random_params(3, &mut seed);
        let s = random_surface(&u, &v, &mut seed);
        for k in 0..20 {
            let (a, b) = (lcg(&mut seed), lcg(&mut seed));
            let d = s.derivatives(a, b);
            let n = d.du.cross(&d.dv).normalize();
            let off = 0.01 * (k as f64 - 10.0) / 10.0;
            let p = d.point + n * off;
            let c = s.closest_point(&p, (a + 0.05, b - 0.05));
            assert!(
                (c.distance - off.abs()).abs() < 1e-9,
                "{} vs {off}",
                c.distance
            );
            assert!((c.u - a).abs() < 1e-6 && (c.v - b).abs() < 1e-6);
            let g = s.closest_point_global(&p, 3);
            assert!((g.distance - off.abs()).abs() < 1e-9);
        }
        // Outside the domain: clamps to the boundary.
        let corner = s.evaluate(0.0, 0.0);
        let d = s.derivatives(0.0, 0.0);
        let p = corner - d.du.normalize() * 0.5 - d.dv.normalize() * 0.5;
        let c = s.closest_point(&p, (0.5, 0.5));
        assert!(c.u < 1e-9 || c.v < 1e-9);
        assert!(c.distance <= (p - corner).norm() + 1e-12);
    }

    #[test]
    fn malformed_grids_are_errors() {
        let u = Params::uniform(2).unwrap();
        let v = Params::uniform(2).unwrap();
        let z = Vector3::zeros();
        let mut g = PatchGrid {
            points: vec![vec![Point3::origin(); 3]; 2],
            du_u0: vec![z; 3],
            du_u1: vec![z; 3],
            dv_v0: vec![z; 3],
            dv_v1: vec![z; 3],
            twist: Twist::Zero,
        };
        assert!(BSplineSurface::interpolate_grid(&g, &u, &v).is_err());
        g.points = vec![vec![Point3::new(f64::NAN, 0.0, 0.0); 3]; 3];
        assert!(BSplineSurface::interpolate_grid(&g, &u, &v).is_err());
    }
}
