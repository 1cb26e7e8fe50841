//! The local functions of the partition of unity and the choice between them (seed 004
//! section 2.1: "quadratic, cubic and radial basis functions chosen per domain").
//!
//! A domain's points are fitted with the lowest-order function that meets the tolerance:
//! a quadratic height polynomial (seed 004 eq. 1), then a cubic one (eq. 2), then, where the
//! normals fold over any height plane or the polynomials miss the tolerance in a domain too small
//! to split, a thin-plate RBF (seed 003 eq. 1-6, seed 004 eq. 3). Every candidate is checked at
//! all its support points: the largest |f| (the fit residual, about a distance) and the agreement
//! of grad f with the points' normals (the first-order form of seed 003's off-surface check).

use super::poly::{Degree, Frame, HeightPoly};
use super::rbf::ThinPlateRbf;
use super::sharp::SharpFunction;
use nalgebra::{Point3, Vector3};

/// Which kind of function a domain uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum LocalKind {
    /// Plane-like height function for supports with very few points.
    Linear,
    /// Seed 004 eq. 1.
    Quadratic,
    /// Seed 004 eq. 2.
    Cubic,
    /// Seed 003 eq. 1-6 / seed 004 eq. 3.
    Rbf,
    /// One height polynomial per smooth region, combined by max / min ([`super::sharp`]).
    Sharp,
    /// An empty domain far from all points: a constant signed distance estimate.
    Constant,
}

/// A domain's function.
#[derive(Debug, Clone, PartialEq)]
pub enum LocalFunction {
    Poly(HeightPoly),
    Rbf(ThinPlateRbf),
    Sharp(SharpFunction),
    Constant(f64),
}

impl LocalFunction {
    /// The kind, for statistics.
    pub fn kind(&self) -> LocalKind {
        match self {
            LocalFunction::Poly(p) => match p.degree {
                Degree::Linear => LocalKind::Linear,
                Degree::Quadratic => LocalKind::Quadratic,
                Degree::Cubic => LocalKind::Cubic,
            },
            LocalFunction::Rbf(_) => LocalKind::Rbf,
            LocalFunction::Sharp(_) => LocalKind::Sharp,
            LocalFunction::Constant(_) => LocalKind::Constant,
        }
    }
    /// f(x).
    #[inline]
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        match self {
            LocalFunction::Poly(p) => p.value(x),
            LocalFunction::Rbf(r) => r.value(x),
            LocalFunction::Sharp(s) => s.value(x),
            LocalFunction::Constant(c) => *c,
        }
    }
    /// f(x) and grad f(x).
    #[inline]
    pub fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        match self {
            LocalFunction::Poly(p) => p.value_and_gradient(x),
            LocalFunction::Rbf(r) => r.value_and_gradient(x),
            LocalFunction::Sharp(s) => s.value_and_gradient(x),
            LocalFunction::Constant(c) => (*c, Vector3::zeros()),
        }
    }
}

/// Parameters of one domain's fit.
#[derive(Debug, Clone, Copy)]
pub struct LocalParams {
    /// Accepted largest |f| at the support points (world units).
    pub tolerance: f64,
    /// Smallest n . w for a height function (seed 004 eq. 1-2 need a graph).
    pub min_normal_cos: f64,
    /// Length scale of the domain (half the support box edge).
    pub scale: f64,
    /// Off-surface distance for RBF constraints (seed 003 eq. 4b).
    pub rbf_eps: f64,
}

/// A candidate function with its measured quality.
#[derive(Debug, Clone)]
pub struct LocalFit {
    pub function: LocalFunction,
    /// Largest |f| at the support points.
    pub max_residual: f64,
    /// Root mean square of f at the support points.
    pub rms_residual: f64,
    /// Fraction of support points whose normal agrees with grad f (dot > 0.3 |grad f|).
    pub normal_agreement: f64,
}

impl LocalFit {
    /// Residual within tolerance and all normals agreeing.
    pub fn meets(&self, tol: f64) -> bool {
        self.max_residual <= tol && self.normal_agreement >= 1.0
    }
}

/// Measures a candidate at the support points.
pub fn assess(f: LocalFunction, points: &[Point3<f64>], normals: &[Vector3<f64>]) -> LocalFit {
    let values: Vec<(f64, Vector3<f64>)> = points.iter().map(|p| f.value_and_gradient(p)).collect();
    assess_values(f, &values, normals)
}

/// Whether a point's normal `n` agrees with the gradient `g` of a function there (their angle
/// under about 73 degrees: the dot product above 0.3 of their lengths' product).
#[inline]
pub fn agrees(g: &Vector3<f64>, n: &Vector3<f64>) -> bool {
    g.dot(n) > 0.3 * g.norm() * n.norm()
}

/// [`assess`] from f and grad f at the points, already known.
pub fn assess_values(
    f: LocalFunction,
    values: &[(f64, Vector3<f64>)],
    normals: &[Vector3<f64>],
) -> LocalFit {
    let mut max_residual = 0.0f64;
    let mut sq = 0.0f64;
    let mut agree = 0usize;
    for (&(v, g), n) in values.iter().zip(normals) {
        max_residual = max_residual.max(v.abs());
        sq += v * v;
        if agrees(&g, n) {
            agree += 1;
        }
        if !v.is_finite() {
            max_residual = f64::INFINITY;
        }
    }
    LocalFit {
        function: f,
        max_residual,
        rms_residual: (sq / values.len().max(1) as f64).sqrt(),
        normal_agreement: if values.is_empty() {
            1.0
        } else {
            agree as f64 / values.len() as f64
        },
    }
}

/// The frame of a height function for these points, if their normals allow one.
pub fn height_frame(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    p: &LocalParams,
) -> Option<Frame> {
    Frame::from_normals(points, normals, p.scale, p.min_normal_cos)
}

/// Fits a height polynomial of `degree` in `frame` and assesses it.
pub fn fit_poly(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    frame: Frame,
    degree: Degree,
) -> Option<LocalFit> {
    HeightPoly::fit(points, frame, degree)
        .ok()
        .map(|h| assess(LocalFunction::Poly(h), points, normals))
}

/// Fits a thin-plate RBF through the points (with off-surface constraints), not yet assessed.
pub fn fit_rbf(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    p: &LocalParams,
) -> Option<LocalFunction> {
    ThinPlateRbf::fit_surface(points, normals, p.rbf_eps)
        .ok()
        .map(LocalFunction::Rbf)
}

/// Fits a thin-plate RBF through the points (as [`fit_rbf`]) and assesses it there, with f and
/// grad f at the points read off its system (they are its centres) rather than evaluated.
pub fn fit_rbf_assessed(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    p: &LocalParams,
) -> Option<LocalFit> {
    let (f, values) =
        ThinPlateRbf::fit_surface_with_point_values(points, normals, p.rbf_eps).ok()?;
    Some(assess_values(LocalFunction::Rbf(f), &values, normals))
}

/// The better of two fits: meeting the tolerance first, then agreement, then residual.
pub fn better(a: Option<LocalFit>, b: Option<LocalFit>, tol: f64) -> Option<LocalFit> {
    match (a, b) {
        (None, x) | (x, None) => x,
        (Some(a), Some(b)) => {
            let key = |f: &LocalFit| (f.meets(tol), f.normal_agreement >= 0.95, -f.max_residual);
            let (ka, kb) = (key(&a), key(&b));
            if (kb.0, kb.1) > (ka.0, ka.1) || ((kb.0, kb.1) == (ka.0, ka.1) && kb.2 > ka.2) {
                Some(b)
            } else {
                Some(a)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assess_measures_residual_and_agreement() {
        let pts = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.01),
            Point3::new(0.0, 1.0, -0.01),
            Point3::new(1.0, 1.0, 0.01),
            Point3::new(0.5, 0.5, 0.0),
        ];
        let up = vec![Vector3::z(); 5];
        let fr = Frame::new(Point3::origin(), Vector3::z(), 1.0).unwrap();
        let fit = fit_poly(&pts, &up, fr, Degree::Linear).unwrap();
        assert!(
            fit.max_residual > 1e-4 && fit.max_residual < 0.02,
            "{}",
            fit.max_residual
        );
        assert_eq!(fit.normal_agreement, 1.0);
        assert!(fit.meets(0.02) && !fit.meets(0.001));
        let down = vec![-Vector3::z(); 5];
        let bad = assess(fit.function.clone(), &pts, &down);
        assert_eq!(bad.normal_agreement, 0.0);
        let best = better(Some(bad), Some(fit), 0.02).unwrap();
        assert_eq!(best.normal_agreement, 1.0);
    }
}
