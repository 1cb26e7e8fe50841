//! Local height-function polynomials (seed 004 eq. 1-2).
//!
//! In a local frame (origin `o`, orthonormal axes `u, v, w` with `w` along the mean normal of the
//! points, all lengths divided by a scale `L`) the surface is the graph `W = h(U, V)` of a
//! quadratic (eq. 1: `h = a0 + a1 U + a2 V + a3 U^2 + a4 U V + a5 V^2`) or cubic (eq. 2: plus
//! `a6 U^3 + a7 U^2 V + a8 U V^2 + a9 V^3`) polynomial, fitted by least squares. The implicit is
//!
//! ```text
//! f(x) = L (W - h(U, V)) / sqrt(1 + h_U^2 + h_V^2)
//! ```
//!
//! which has the same zero set as seed 004's `w - h(u, v)` and approximates the signed distance
//! near it (the vertical offset divided by the secant of the slope), positive on the side the
//! normals point to. A height function only describes the points when their normals agree with
//! `w` (otherwise the surface folds over the `(u, v)` plane); [`Frame::from_normals`] refuses
//! such point sets and the caller falls back to an RBF (seed 004 eq. 3).

use crate::{Error, Result};
use nalgebra::{Point3, SMatrix, SVector, Vector3};

/// Orthonormal local frame with a length scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub origin: Point3<f64>,
    pub u: Vector3<f64>,
    pub v: Vector3<f64>,
    pub w: Vector3<f64>,
    /// Length scale L: local coordinates are divided by it.
    pub scale: f64,
}

impl Frame {
    /// Frame with `w` along `normal` (need not be unit) at `origin`.
    pub fn new(origin: Point3<f64>, normal: Vector3<f64>, scale: f64) -> Option<Frame> {
        let w = normal.try_normalize(1e-300)?;
        let a = if w.x.abs() < 0.6 {
            Vector3::x()
        } else if w.y.abs() < 0.6 {
            Vector3::y()
        } else {
            Vector3::z()
        };
        let u = a.cross(&w).normalize();
        let v = w.cross(&u);
        (scale > 0.0 && scale.is_finite()).then_some(Frame {
            origin,
            u,
            v,
            w,
            scale,
        })
    }

    /// Frame at the centroid of `points`, `w` along the mean of `normals`; `None` when some
    /// normal makes `n . w < min_cos` (no height field) or the mean normal vanishes.
    pub fn from_normals(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        scale: f64,
        min_cos: f64,
    ) -> Option<Frame> {
        if points.is_empty() || points.len() != normals.len() {
            return None;
        }
        let mut c = Vector3::zeros();
        let mut n = Vector3::zeros();
        for (p, m) in points.iter().zip(normals) {
            c += p.coords;
            n += m;
        }
        c /= points.len() as f64;
        let f = Frame::new(Point3::from(c), n, scale)?;
        normals
            .iter()
            .all(|m| m.dot(&f.w) >= min_cos * m.norm())
            .then_some(f)
    }

    /// Local scaled coordinates (U, V, W) of `x`.
    #[inline]
    pub fn local(&self, x: &Point3<f64>) -> Vector3<f64> {
        let d = (x - self.origin) / self.scale;
        Vector3::new(d.dot(&self.u), d.dot(&self.v), d.dot(&self.w))
    }
}

/// Degree of the height polynomial.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Degree {
    /// A tilted plane `a0 + a1 U + a2 V` (3 coefficients), for supports too small for eq. 1.
    Linear,
    /// Seed 004 eq. 1 (6 coefficients).
    Quadratic,
    /// Seed 004 eq. 2 (10 coefficients).
    Cubic,
}

impl Degree {
    /// Number of coefficients.
    pub fn terms(self) -> usize {
        match self {
            Degree::Linear => 3,
            Degree::Quadratic => 6,
            Degree::Cubic => 10,
        }
    }
}

/// A fitted height polynomial as an implicit function.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightPoly {
    pub frame: Frame,
    pub degree: Degree,
    /// Coefficients a0..a9 in scaled coordinates (unused ones are 0).
    pub coef: [f64; 10],
}

#[inline]
fn monomials(u: f64, v: f64) -> [f64; 10] {
    [
        1.0,
        u,
        v,
        u * u,
        u * v,
        v * v,
        u * u * u,
        u * u * v,
        u * v * v,
        v * v * v,
    ]
}

impl HeightPoly {
    /// Least-squares fit of `W = h(U, V)` to `points` in `frame`. A tiny ridge on the non-linear
    /// coefficients keeps the fit bounded where the points do not span the cell (a strip). Errors
    /// when there are too few points (3 for a plane, 9 for a quadratic, 30 for a cubic) or the
    /// normal equations are singular.
    pub fn fit(points: &[Point3<f64>], frame: Frame, degree: Degree) -> Result<HeightPoly> {
        let m = degree.terms();
        let needed = match degree {
            Degree::Linear => 3,
            Degree::Quadratic => 9,
            Degree::Cubic => 30,
        };
        if points.len() < needed {
            return Err(Error::Degenerate(format!(
                "height polynomial with {m} terms from {} points",
                points.len()
            )));
        }
        let mut ata = SMatrix::<f64, 10, 10>::zeros();
        let mut atb = SVector::<f64, 10>::zeros();
        for p in points {
            let l = frame.local(p);
            let b = monomials(l.x, l.y);
            for i in 0..m {
                atb[i] += b[i] * l.z;
                for j in i..m {
                    ata[(i, j)] += b[i] * b[j];
                }
            }
        }
        let ridge = 1e-7 * points.len() as f64;
        for i in 0..m {
            for j in 0..i {
                ata[(i, j)] = ata[(j, i)];
            }
            if i >= 3 {
                ata[(i, i)] += ridge;
            }
        }
        for i in m..10 {
            ata[(i, i)] = 1.0;
        }
        let chol = ata
            .cholesky()
            .ok_or_else(|| Error::Numerical("singular height-polynomial fit".into()))?;
        let c = chol.solve(&atb);
        if !c.iter().all(|x| x.is_finite()) {
            return Err(Error::Numerical("non-finite height-polynomial fit".into()));
        }
        let mut coef = [0.0; 10];
        coef.iter_mut().zip(c.iter()).for_each(|(a, b)| *a = *b);
        Ok(HeightPoly {
            frame,
            degree,
            coef,
        })
    }

    /// h, h_U, h_V, h_UU, h_UV, h_VV at (U, V).
    #[inline]
    fn height(&self, u: f64, v: f64) -> [f64; 6] {
        let a = &self.coef;
        let h = a[0]
            + u * (a[1] + u * (a[3] + u * a[6]) + v * (a[4] + u * a[7]))
            + v * (a[2] + v * (a[5] + v * a[9] + u * a[8]));
        let hu = a[1]
            + 2.0 * a[3] * u
            + a[4] * v
            + 3.0 * a[6] * u * u
            + 2.0 * a[7] * u * v
            + a[8] * v * v;
        let hv = a[2]
            + a[4] * u
            + 2.0 * a[5] * v
            + a[7] * u * u
            + 2.0 * a[8] * u * v
            + 3.0 * a[9] * v * v;
        let huu = 2.0 * a[3] + 6.0 * a[6] * u + 2.0 * a[7] * v;
        let huv = a[4] + 2.0 * a[7] * u + 2.0 * a[8] * v;
        let hvv = 2.0 * a[5] + 2.0 * a[8] * u + 6.0 * a[9] * v;
        [h, hu, hv, huu, huv, hvv]
    }

    /// f(x) (world units, approximately the signed distance).
    #[inline]
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        let l = self.frame.local(x);
        let [h, hu, hv, ..] = self.height(l.x, l.y);
        self.frame.scale * (l.z - h) / (1.0 + hu * hu + hv * hv).sqrt()
    }

    /// f(x) and its analytic gradient.
    #[inline]
    pub fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let l = self.frame.local(x);
        let [h, hu, hv, huu, huv, hvv] = self.height(l.x, l.y);
        let g = l.z - h;
        let s2 = 1.0 + hu * hu + hv * hv;
        let s = s2.sqrt();
        let inv_s = 1.0 / s;
        let inv_s3 = inv_s / s2;
        // d(g/s)/dU = -h_U / s - g (h_U h_UU + h_V h_UV) / s^3, same for V; d(g/s)/dW = 1/s.
        let du = -hu * inv_s - g * (hu * huu + hv * huv) * inv_s3;
        let dv = -hv * inv_s - g * (hu * huv + hv * hvv) * inv_s3;
        let dw = inv_s;
        let f = &self.frame;
        (f.scale * g * inv_s, f.u * du + f.v * dv + f.w * dw)
    }

    /// The surface point above local coordinates (U, V).
    pub fn surface_point(&self, u: f64, v: f64) -> Point3<f64> {
        let h = self.height(u, v)[0];
        let f = &self.frame;
        f.origin + (f.u * u + f.v * v + f.w * h) * f.scale
    }

    /// Largest slope |grad h| over `points` (a fold indicator).
    pub fn max_slope(&self, points: &[Point3<f64>]) -> f64 {
        points
            .iter()
            .map(|p| {
                let l = self.frame.local(p);
                let [_, hu, hv, ..] = self.height(l.x, l.y);
                (hu * hu + hv * hv).sqrt()
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere_cap(n: usize, r: f64) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let mut p = Vec::new();
        let mut nn = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let a = (i as f64 / (n - 1) as f64 - 0.5) * 0.4;
                let b = (j as f64 / (n - 1) as f64 - 0.5) * 0.4;
                let d = Vector3::new(a, b, 1.0).normalize();
                p.push(Point3::from(d * r));
                nn.push(d);
            }
        }
        (p, nn)
    }

    #[test]
    fn quadratic_is_exact_on_a_paraboloid_and_gradient_matches() {
        let mut pts = Vec::new();
        for i in 0..8 {
            for j in 0..8 {
                let (x, y) = (i as f64 * 0.1 - 0.35, j as f64 * 0.1 - 0.35);
                pts.push(Point3::new(x, y, 0.3 + 0.5 * x * x - 0.2 * x * y + 0.1 * y));
            }
        }
        let nrm = vec![Vector3::z(); pts.len()];
        let fr = Frame::from_normals(&pts, &nrm, 0.5, 0.3).unwrap();
        let q = HeightPoly::fit(&pts, fr, Degree::Quadratic).unwrap();
        for p in &pts {
            assert!(q.value(p).abs() < 1e-6, "{}", q.value(p));
        }
        let x = Point3::new(0.1, -0.2, 0.5);
        let (f, g) = q.value_and_gradient(&x);
        assert!((f - q.value(&x)).abs() < 1e-14);
        let h = 1e-6;
        for k in 0..3 {
            let mut a = x;
            let mut b = x;
            a[k] += h;
            b[k] -= h;
            let fd = (q.value(&a) - q.value(&b)) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-6, "{k}: {fd} vs {}", g[k]);
        }
        // Above the surface (normals +z) is positive.
        assert!(q.value(&Point3::new(0.0, 0.0, 1.0)) > 0.0);
    }

    #[test]
    fn cubic_approximates_sphere_distance() {
        let (p, n) = sphere_cap(10, 2.0);
        let fr = Frame::from_normals(&p, &n, 0.4, 0.3).unwrap();
        let quad = HeightPoly::fit(&p, fr, Degree::Quadratic).unwrap();
        let cub = HeightPoly::fit(&p, fr, Degree::Cubic).unwrap();
        let err = |h: &HeightPoly| p.iter().map(|x| h.value(x).abs()).fold(0.0, f64::max);
        assert!(err(&cub) <= err(&quad) + 1e-12);
        assert!(err(&quad) < 1e-3);
        // Normalized value: about the signed distance at 0.01 off the sphere.
        let x = Point3::new(0.0, 0.0, 2.01);
        assert!((cub.value(&x) - 0.01).abs() < 5e-4, "{}", cub.value(&x));
    }

    #[test]
    fn folded_normals_are_refused() {
        let p = vec![Point3::origin(), Point3::new(1.0, 0.0, 0.0)];
        let n = vec![Vector3::z(), -Vector3::z() + Vector3::x() * 0.1];
        assert!(Frame::from_normals(&p, &n, 1.0, 0.3).is_none());
        assert!(HeightPoly::fit(
            &p,
            Frame::new(Point3::origin(), Vector3::z(), 1.0).unwrap(),
            Degree::Quadratic
        )
        .is_err());
    }
}
