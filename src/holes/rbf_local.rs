//! A thin-plate RBF interpolant for hole-sized point sets (up to a few thousand points), solved
//! densely.
//!
//! Seed 003 eq. 1-6 (used by seed 000 section 2.1):
//!
//! ```text
//! f(x) = sum_j lambda_j phi(|x - c_j|) + P0 + P1 x + P2 y + P3 z,    phi(r) = r^2 log r
//! f(c_i) = h_i                          (eq. 3-4: 0 on the surface, > 0 off it)
//! sum_j lambda_j = sum_j lambda_j c_j = 0                             (eq. 5)
//! ```
//!
//! giving the symmetric (N+4) x (N+4) system of eq. 6, `[A P; P^T 0] [lambda; p] = [h; 0]`.
//! It is solved by LU with partial pivoting (faer), sequentially so that the result does not
//! depend on the thread count.
//!
//! **Temporary**: the shared `implicit::rbf` module (another branch) will provide the same
//! interpolant with domain decomposition. Everything in `holes` works on a `&dyn Implicit`, and
//! the fitter is a parameter: to switch, pass the shared fitter to
//! [`super::fill_holes_with`] or make [`super::default_fitter`] call it (same inputs: centres
//! and values), then delete this file.
//!
//! Conditioning: the points are centred and scaled into the unit ball before the solve. The
//! thin-plate kernel changes under scaling only by a multiple of `r^2`, which the side conditions
//! of eq. 5 reduce to a constant, so the interpolant is the same up to round-off.

use crate::error::{Error, Result};
use crate::implicit::Implicit;
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{dyn_stack::MemBuffer, dyn_stack::MemStack, Conj, Mat, Par};
use nalgebra::{Point3, Vector3};

/// Largest point set accepted (the dense solve is O(N^3)).
pub const MAX_POINTS: usize = 6000;

/// A fitted thin-plate interpolant (see the module doc).
#[derive(Debug, Clone)]
pub struct ThinPlateRbf {
    /// Centres in normalized coordinates `(x - origin) / scale`.
    centers: Vec<Vector3<f64>>,
    /// lambda_j.
    weights: Vec<f64>,
    /// P0..P3 in normalized coordinates.
    poly: [f64; 4],
    origin: Point3<f64>,
    scale: f64,
}

/// Fits the thin-plate interpolant through `points` with the given `values` (seed 003 eq. 1-6).
///
/// Points closer than 1e-9 of the set's size to an earlier point are dropped (a duplicate makes
/// the system singular). Errors: mismatched lengths, fewer than 4 distinct points, non-finite
/// input, more than [`MAX_POINTS`] points, or a singular system (all points coplanar with no
/// off-surface point, for instance).
pub fn fit_hole_rbf(points: &[Point3<f64>], values: &[f64]) -> Result<impl Implicit> {
    ThinPlateRbf::fit(points, values)
}

impl ThinPlateRbf {
    /// See [`fit_hole_rbf`].
    pub fn fit(points: &[Point3<f64>], values: &[f64]) -> Result<ThinPlateRbf> {
        if points.len() != values.len() {
            return Err(Error::InvalidOption(format!(
                "{} points but {} values",
                points.len(),
                values.len()
            )));
        }
        if points.len() > MAX_POINTS {
            return Err(Error::InvalidOption(format!(
                "{} points is too many for a dense RBF fit (at most {MAX_POINTS})",
                points.len()
            )));
        }
        if points.iter().any(|p| !p.iter().all(|c| c.is_finite()))
            || values.iter().any(|v| !v.is_finite())
        {
            return Err(Error::Degenerate(
                "RBF fit: non-finite point or value".into(),
            ));
        }
        let bbox = crate::mesh::Aabb::of(points)
            .ok_or_else(|| Error::Degenerate("RBF fit: no points".into()))?;
        let origin = bbox.center();
        let scale = 0.5 * bbox.diagonal();
        if scale <= 0.0 || !scale.is_finite() {
            return Err(Error::Degenerate("RBF fit: all points coincide".into()));
        }
        // Normalize and drop near-duplicates (O(N^2), fine at the sizes this is for).
        let eps2 = 1e-18;
        let mut centers: Vec<Vector3<f64>> = Vec::with_capacity(points.len());
        let mut h: Vec<f64> = Vec::with_capacity(points.len());
        for (p, &v) in points.iter().zip(values) {
            let c = (p - origin) / scale;
            if centers.iter().all(|q| (q - c).norm_squared() > eps2) {
                centers.push(c);
                h.push(v / scale);
            }
        }
        let n = centers.len();
        if n < 4 {
            return Err(Error::Degenerate(format!(
                "RBF fit: {n} distinct points, need at least 4"
            )));
        }
        let m = n + 4;
        let a = Mat::<f64>::from_fn(m, m, |i, j| {
            if i < n && j < n {
                phi((centers[i] - centers[j]).norm_squared())
            } else if i < n {
                poly_term(&centers[i], j - n)
            } else if j < n {
                poly_term(&centers[j], i - n)
            } else {
                0.0
            }
        });
        let rhs = Mat::<f64>::from_fn(m, 1, |i, _| if i < n { h[i] } else { 0.0 });
        let x = lu_solve(a, rhs.clone())?;
        let weights: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
        let poly = [x[(n, 0)], x[(n + 1, 0)], x[(n + 2, 0)], x[(n + 3, 0)]];
        if weights.iter().chain(poly.iter()).any(|w| !w.is_finite()) {
            return Err(Error::Numerical("RBF fit: singular system".into()));
        }
        let rbf = ThinPlateRbf {
            centers,
            weights,
            poly,
            origin,
            scale,
        };
        // The interpolation conditions must hold; a near-singular system shows here.
        let worst = rbf
            .centers
            .iter()
            .zip(&h)
            .map(|(c, &hv)| (rbf.eval_normalized(c).0 - hv).abs())
            .fold(0.0, f64::max);
        if !(worst < 1e-6) {
            return Err(Error::Numerical(format!(
                "RBF fit: interpolation residual {worst:.1e} (ill-conditioned point set)"
            )));
        }
        Ok(rbf)
    }

    /// Number of centres after deduplication.
    pub fn len(&self) -> usize {
        self.centers.len()
    }

    /// True when there are no centres (never, for a fitted interpolant).
    pub fn is_empty(&self) -> bool {
        self.centers.is_empty()
    }

    /// Value and gradient in normalized coordinates.
    fn eval_normalized(&self, y: &Vector3<f64>) -> (f64, Vector3<f64>) {
        let mut v = self.poly[0] + self.poly[1] * y.x + self.poly[2] * y.y + self.poly[3] * y.z;
        let mut g = Vector3::new(self.poly[1], self.poly[2], self.poly[3]);
        for (c, &w) in self.centers.iter().zip(&self.weights) {
            let d = y - c;
            let q = d.norm_squared();
            if q > 0.0 {
                let l = q.ln();
                // phi = r^2 ln r = q ln q / 2; grad phi = (2 ln r + 1) d = (ln q + 1) d.
                v += w * 0.5 * q * l;
                g += d * (w * (l + 1.0));
            }
        }
        (v, g)
    }
}

/// phi(r) = r^2 log r as a function of q = r^2 (seed 003 eq. 2).
fn phi(q: f64) -> f64 {
    if q > 0.0 {
        0.5 * q * q.ln()
    } else {
        0.0
    }
}

/// The linear polynomial's basis: 1, x, y, z.
fn poly_term(c: &Vector3<f64>, k: usize) -> f64 {
    match k {
        0 => 1.0,
        1 => c.x,
        2 => c.y,
        _ => c.z,
    }
}

/// Solves `a x = rhs` by LU with partial pivoting, sequentially.
fn lu_solve(mut a: Mat<f64>, mut rhs: Mat<f64>) -> Result<Mat<f64>> {
    let m = a.nrows();
    let par = Par::Seq;
    let mut fwd = vec![0usize; m];
    let mut bwd = vec![0usize; m];
    let mut buf = MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
        m,
        m,
        par,
        Default::default(),
    ));
    let (_, perm) = factor::lu_in_place(
        a.as_mut(),
        &mut fwd,
        &mut bwd,
        par,
        MemStack::new(&mut buf),
        Default::default(),
    );
    // A zero (or NaN) pivot means a singular system.
    let tiny = (0..m)
        .map(|i| a[(i, i)].abs())
        .fold(f64::INFINITY, f64::min);
    if !(tiny > 1e-14) {
        return Err(Error::Numerical("RBF fit: singular system".into()));
    }
    let mut sbuf = MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(m, 1, par));
    solve::solve_in_place_with_conj(
        a.as_ref(),
        a.as_ref(),
        perm,
        Conj::No,
        rhs.as_mut(),
        par,
        MemStack::new(&mut sbuf),
    );
    Ok(rhs)
}

impl Implicit for ThinPlateRbf {
    fn value(&self, x: &Point3<f64>) -> f64 {
        let y = (x - self.origin) / self.scale;
        self.eval_normalized(&y).0 * self.scale
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        let y = (x - self.origin) / self.scale;
        self.eval_normalized(&y).1
    }
    fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let y = (x - self.origin) / self.scale;
        let (v, g) = self.eval_normalized(&y);
        (v * self.scale, g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a sphere of radius 2 with offsets along the normal: the zero set must follow
    /// the sphere between the samples, and f must grow outward.
    #[test]
    fn sphere_patch_is_reproduced() {
        let mut pts = Vec::new();
        let mut vals = Vec::new();
        let r = 2.0;
        for i in 0..12 {
            for j in 0..12 {
                let th = 0.2 + 0.05 * i as f64;
                let ph = 0.05 * j as f64;
                let n = Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                pts.push(Point3::from(n * r));
                vals.push(0.0);
                pts.push(Point3::from(n * (r + 0.05)));
                vals.push(0.05);
            }
        }
        let f = fit_hole_rbf(&pts, &vals).unwrap();
        // Between samples.
        let th: f64 = 0.2 + 0.05 * 5.5;
        let ph: f64 = 0.05 * 5.5;
        let n = Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
        let p = Point3::from(n * r);
        let (v, g) = f.value_and_gradient(&p);
        assert!(v.abs() < 1e-4, "value {v}");
        assert!(g.normalize().dot(&n) > 0.99, "gradient {g:?}");
        // Analytic gradient agrees with central differences.
        let q = Point3::from(n * (r + 0.01));
        let ga = f.gradient(&q);
        let hstep = 1e-6;
        for k in 0..3 {
            let mut a = q;
            let mut b = q;
            a[k] += hstep;
            b[k] -= hstep;
            let gd = (f.value(&a) - f.value(&b)) / (2.0 * hstep);
            assert!((gd - ga[k]).abs() < 1e-5, "{gd} vs {}", ga[k]);
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let p = vec![Point3::origin(); 3];
        assert!(ThinPlateRbf::fit(&p, &[0.0; 2]).is_err());
        assert!(ThinPlateRbf::fit(&p, &[0.0; 3]).is_err());
        let q = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(f64::NAN, 0.0, 1.0),
        ];
        assert!(ThinPlateRbf::fit(&q, &[0.0; 4]).is_err());
        // Coplanar points with all-zero values: the plane is an exact solution (not singular).
        let flat: Vec<Point3<f64>> = (0..25)
            .map(|i| Point3::new((i % 5) as f64, (i / 5) as f64, 0.0))
            .collect();
        // ... but the polynomial part is undetermined in z: singular.
        assert!(ThinPlateRbf::fit(&flat, &[0.0; 25]).is_err());
    }
}
