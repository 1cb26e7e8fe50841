//! Thin-plate radial basis function interpolation (seed 003 eq. 1-6, seed 004 eq. 3).
//!
//! ```text
//! f(x) = sum_j lambda_j phi(|x - c_j|) + P0 + P1 x + P2 y + P3 z,   phi(r) = r^2 log r   (eq. 1-2)
//! f(c_i) = h_i                                                                           (eq. 3-4)
//! sum_j lambda_j = sum_j lambda_j c_j = 0                                                (eq. 5)
//! ```
//!
//! giving the symmetric saddle-point system of eq. 6, `[A P; P^T 0] [lambda; p] = [h; 0]`. It is
//! solved by faer's LU with partial pivoting (for the 60-130 unknowns of `fit`'s local RBFs
//! about twice as fast as its symmetric-indefinite LBL^T, which pivots in smaller steps: the
//! bunny's implicit 3.7 -> 3.3 s; a Cholesky solve in the null space of P^T, half the flops on
//! paper, was slower still at these sizes); the residual is checked and a singular or
//! inaccurate solve is an `Err`, never a panic.
//!
//! Coordinates are centred and scaled (x -> (x - o) / L) before solving: the interpolant is
//! invariant under this (phi(s r) = s^2 phi(r) + s^2 log(s) r^2 and the r^2 part is cancelled by
//! eq. 5), while the conditioning improves.
//!
//! [`ThinPlateRbf::fit_surface`] builds the constraints of a surface: zeros at the on-surface
//! points (eq. 4a) and +eps / -eps at points offset by eps along / against the normals (eq. 4b),
//! so f is positive outside and approximates the signed distance near the points.

use super::tps_kernel::{phi_column, Centres};
use crate::{Error, Result};
use faer::linalg::solvers::Solve;
use faer::Mat;
use nalgebra::{Point3, Vector3};

/// f and grad f at a point.
pub type ValueAndGradient = (f64, Vector3<f64>);

/// A fitted thin-plate RBF implicit.
#[derive(Debug, Clone, PartialEq)]
pub struct ThinPlateRbf {
    origin: Point3<f64>,
    scale: f64,
    /// Centres in scaled coordinates with their weights lambda_j, summed by the vectorized
    /// kernel of `tps_kernel`.
    kernel: Centres,
    /// P0 + P . X in scaled coordinates X.
    p0: f64,
    p: Vector3<f64>,
}

impl ThinPlateRbf {
    /// Interpolates the values `h` at `centers` (eq. 1-6). Needs at least 4 non-coplanar
    /// centres; duplicate centres make the system singular (an `Err`).
    pub fn fit(centers: &[Point3<f64>], h: &[f64]) -> Result<ThinPlateRbf> {
        Self::solve(centers, h, 0).map(|(f, _)| f)
    }

    /// [`fit`](Self::fit), also returning f and grad f at the first `at` centres, read off the
    /// system instead of evaluated: f(c_i) is row i of eq. 6, (A lambda + P p)_i, and
    /// grad f(c_i) = sum_j lambda_j (c_i - c_j)(ln r_ij^2 + 1) + P with ln r_ij^2 = 2 A_ij / r_ij^2,
    /// so no logarithm is taken again (checking a fit at its own centres otherwise costs as
    /// much as building its matrix).
    pub fn fit_with_centre_values(
        centers: &[Point3<f64>],
        h: &[f64],
        at: usize,
    ) -> Result<(ThinPlateRbf, Vec<ValueAndGradient>)> {
        Self::solve(centers, h, at.min(centers.len()))
    }

    fn solve(
        centers: &[Point3<f64>],
        h: &[f64],
        at: usize,
    ) -> Result<(ThinPlateRbf, Vec<ValueAndGradient>)> {
        let n = centers.len();
        if n < 4 || h.len() != n {
            return Err(Error::Degenerate(format!(
                "thin-plate RBF needs at least 4 centres with values, got {n}"
            )));
        }
        if centers
            .iter()
            .any(|c| !c.coords.iter().all(|x| x.is_finite()))
            || h.iter().any(|x| !x.is_finite())
        {
            return Err(Error::Degenerate("non-finite RBF constraint".into()));
        }
        let mut o = Vector3::zeros();
        for c in centers {
            o += c.coords;
        }
        let origin = Point3::from(o / n as f64);
        let scale = centers
            .iter()
            .map(|c| (c - origin).norm())
            .fold(0.0, f64::max);
        if scale.is_nan() || scale <= 0.0 {
            return Err(Error::Degenerate("coincident RBF centres".into()));
        }
        let xs: Vec<Vector3<f64>> = centers.iter().map(|c| (c - origin) / scale).collect();
        // The linear part P(x) is only determined when the centres span 3D (eq. 5-6 singular
        // otherwise): the smallest eigenvalue of their covariance must not vanish.
        let mut cov = nalgebra::Matrix3::zeros();
        for x in &xs {
            cov += x * x.transpose();
        }
        let ev = nalgebra::SymmetricEigen::new(cov / n as f64).eigenvalues;
        if ev.min().is_nan() || ev.min() <= 1e-12 {
            return Err(Error::Degenerate("coplanar RBF centres".into()));
        }
        let m = n + 4;
        let mut a = Mat::<f64>::zeros(m, m);
        let coord = |k: usize| -> Vec<f64> { xs.iter().map(|x| x[k]).collect() };
        let (cx, cy, cz) = (coord(0), coord(1), coord(2));
        // A in the system matrix's own column-major storage: column j from the diagonal down
        // by the vectorized kernel, mirrored into row j ((x_i - x_j)^2 = (x_j - x_i)^2
        // exactly, so this is the whole matrix for half the logarithms).
        for j in 0..n {
            phi_column(
                &cx[j..],
                &cy[j..],
                &cz[j..],
                [xs[j].x, xs[j].y, xs[j].z],
                &mut a.col_as_slice_mut(j)[j..n],
            );
            for i in j + 1..n {
                a[(j, i)] = a[(i, j)];
            }
        }
        for i in 0..n {
            a[(i, n)] = 1.0;
            a[(n, i)] = 1.0;
            for k in 0..3 {
                a[(i, n + 1 + k)] = xs[i][k];
                a[(n + 1 + k, i)] = xs[i][k];
            }
        }
        let mut b = Mat::<f64>::zeros(m, 1);
        for i in 0..n {
            b[(i, 0)] = h[i];
        }
        let x = a.partial_piv_lu().solve(&b);
        // Residual check: the factorization does not report near-singularity itself.
        let r = &a * &x - &b;
        let res = (0..m).map(|i| r[(i, 0)].abs()).fold(0.0f64, f64::max);
        let bnorm = (0..m).map(|i| b[(i, 0)].abs()).fold(0.0f64, f64::max);
        let xmax = (0..m).map(|i| x[(i, 0)].abs()).fold(0.0, f64::max);
        if !res.is_finite() || !xmax.is_finite() || res > 1e-8 * (bnorm + xmax) {
            return Err(Error::Numerical(format!(
                "thin-plate RBF system is singular or ill-conditioned (residual {res:.3e})"
            )));
        }
        let lambda: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
        let p = Vector3::new(x[(n + 1, 0)], x[(n + 2, 0)], x[(n + 3, 0)]);
        let at_centres = (0..at)
            .map(|i| {
                // Row i of A is column i (symmetric), contiguous; the factorization worked on
                // its own copy.
                let row = &a.col_as_slice(i)[..n];
                let (mut gx, mut gy, mut gz) = (0.0, 0.0, 0.0);
                for j in 0..n {
                    let (dx, dy, dz) = (cx[i] - cx[j], cy[i] - cy[j], cz[i] - cz[j]);
                    let r2 = dx * dx + dy * dy + dz * dz;
                    let t = if r2 > 0.0 {
                        lambda[j] * (2.0 * row[j] / r2 + 1.0)
                    } else {
                        0.0
                    };
                    gx += dx * t;
                    gy += dy * t;
                    gz += dz * t;
                }
                (
                    r[(i, 0)] + b[(i, 0)],
                    (p + Vector3::new(gx, gy, gz)) / scale,
                )
            })
            .collect();
        let rbf = ThinPlateRbf {
            origin,
            scale,
            kernel: Centres::new(&xs, &lambda),
            p0: x[(n, 0)],
            p,
        };
        Ok((rbf, at_centres))
    }

    /// Surface implicit through `points` (value 0) with off-surface constraints (seed 003 eq. 4b):
    /// +eps at `p + eps n` for even-numbered points and -eps at `p - eps n` for odd-numbered ones,
    /// so both sides are held with 2n rather than 3n unknowns. An offset is shortened, down to
    /// eps/8, while another point is nearer to the offset point than its own point (Carr et al.
    /// 2001), and dropped when that does not help.
    pub fn fit_surface(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        eps: f64,
    ) -> Result<ThinPlateRbf> {
        Self::fit_surface_with_point_values(points, normals, eps).map(|(f, _)| f)
    }

    /// [`fit_surface`](Self::fit_surface), also returning f and grad f at `points` (see
    /// [`fit_with_centre_values`](Self::fit_with_centre_values)).
    pub fn fit_surface_with_point_values(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        eps: f64,
    ) -> Result<(ThinPlateRbf, Vec<ValueAndGradient>)> {
        if points.len() != normals.len() {
            return Err(Error::Degenerate(
                "points and normals differ in count".into(),
            ));
        }
        let mut c = Vec::with_capacity(3 * points.len());
        let mut h = Vec::with_capacity(3 * points.len());
        c.extend_from_slice(points);
        h.extend(std::iter::repeat_n(0.0, points.len()));
        for (i, (p, n)) in points.iter().zip(normals).enumerate() {
            let Some(n) = n.try_normalize(1e-300) else {
                continue;
            };
            // One offset per point, alternately outside and inside: both sides are constrained
            // with a system of 2n rather than 3n unknowns.
            {
                let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
                let mut e = eps;
                for _ in 0..4 {
                    let q = p + n * (sign * e);
                    let own = (q - p).norm_squared();
                    let clash = points
                        .iter()
                        .enumerate()
                        .any(|(j, r)| j != i && (q - r).norm_squared() < own * 0.999);
                    if !clash {
                        c.push(q);
                        h.push(sign * e);
                        break;
                    }
                    e *= 0.5;
                }
            }
        }
        ThinPlateRbf::fit_with_centre_values(&c, &h, points.len())
    }

    /// Number of centres.
    pub fn len(&self) -> usize {
        self.kernel.len()
    }
    /// True when there are no centres (never for a fitted RBF).
    pub fn is_empty(&self) -> bool {
        self.kernel.is_empty()
    }

    /// f(x).
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        let y = (x - self.origin) / self.scale;
        self.p0 + self.p.dot(&y) + self.kernel.value([y.x, y.y, y.z])
    }

    /// f(x) and its analytic gradient: grad phi(|y - c|) = (y - c)(2 log r + 1).
    pub fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let y = (x - self.origin) / self.scale;
        let (s, g) = self.kernel.value_and_gradient([y.x, y.y, y.z]);
        (
            self.p0 + self.p.dot(&y) + s,
            (self.p + Vector3::from(g)) / self.scale,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere_points(n: usize) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        // Fibonacci sphere of radius 1.
        let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let mut p = Vec::new();
        let mut nn = Vec::new();
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let t = ga * i as f64;
            let d = Vector3::new(r * t.cos(), r * t.sin(), z);
            p.push(Point3::from(d));
            nn.push(d);
        }
        (p, nn)
    }

    #[test]
    fn values_read_off_the_system_match_evaluation() {
        let (p, n) = sphere_points(40);
        let (f, at) = ThinPlateRbf::fit_surface_with_point_values(&p, &n, 0.1).unwrap();
        assert_eq!(at.len(), p.len());
        assert_eq!(f, ThinPlateRbf::fit_surface(&p, &n, 0.1).unwrap());
        for (q, (v, g)) in p.iter().zip(&at) {
            let (ve, ge) = f.value_and_gradient(q);
            assert!((v - ve).abs() < 1e-10, "{v} {ve}");
            assert!((g - ge).norm() < 1e-9 * ge.norm(), "{g} {ge}");
        }
    }

    #[test]
    fn interpolates_and_gradient_is_exact() {
        let (p, n) = sphere_points(60);
        let f = ThinPlateRbf::fit_surface(&p, &n, 0.1).unwrap();
        for q in &p {
            assert!(f.value(q).abs() < 1e-9);
        }
        assert!(f.value(&Point3::origin()) < 0.0);
        assert!(f.value(&Point3::new(0.0, 0.0, 1.3)) > 0.0);
        // Zero set near the unit sphere between the samples.
        let x = Point3::from(Vector3::new(0.3, -0.5, 0.7).normalize());
        assert!(f.value(&x).abs() < 0.02, "{}", f.value(&x));
        let y = Point3::new(0.2, 0.4, -0.5);
        let (v, g) = f.value_and_gradient(&y);
        assert!((v - f.value(&y)).abs() < 1e-12);
        let h = 1e-6;
        for k in 0..3 {
            let mut a = y;
            let mut b = y;
            a[k] += h;
            b[k] -= h;
            let fd = (f.value(&a) - f.value(&b)) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-5, "{fd} {}", g[k]);
        }
    }

    #[test]
    fn singular_systems_are_errors() {
        // Duplicate centres with different values.
        let c = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(0.0, 0.0, 1.0),
        ];
        assert!(ThinPlateRbf::fit(&c, &[0.0, 0.0, 0.0, 1.0, 2.0]).is_err());
        // Coplanar centres: the linear part is undetermined.
        let c: Vec<_> = (0..6)
            .map(|i| Point3::new(i as f64, (i * i) as f64, 0.0))
            .collect();
        assert!(ThinPlateRbf::fit(&c, &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]).is_err());
        assert!(ThinPlateRbf::fit(&c[..2], &[0.0; 2]).is_err());
    }
}
