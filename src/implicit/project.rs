//! Newton projection of points onto the zero set of an implicit (seed 003 section 3.3's "normal
//! projection", seed 000 eq. 8-12).
//!
//! Along the gradient: `x <- x - f(x) grad f(x) / |grad f(x)|^2` (the closest-point Newton step
//! for an implicit that is about a distance; seed 000 eq. 11). Along a fixed direction `d` (seed
//! 000 eq. 8-12, one unknown `lambda` on the line `r0 + lambda d`):
//!
//! ```text
//! r(lambda) = r0 + lambda N                           (eq. 8)
//! lambda_{i+1} = lambda_i - F(lambda_i) / F'(lambda_i)  (eq. 9)
//! F'(lambda) = N . grad f(r(lambda))                   (eq. 10, 12)
//! ```
//!
//! Two step policies, one per use:
//! - [`project`] (the reconstruction's subdivision and relaxation): steps clamped to
//!   `max_step` so that a poor start cannot jump across the model; failure to converge is an
//!   `Err`.
//! - [`project_along_within`] and [`project_gradient_within`] (the hole fills): safeguarded, a
//!   step is halved while it does not decrease |f|, and the point may move at most `max_dist`
//!   from where it started; `None` when that fails, so the caller can fall back rather than
//!   place a node far off.

use super::Implicit;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// Options of the projections.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ProjectOptions {
    /// Stop when |f| is at most this (absolute, in the implicit's units).
    pub tolerance: f64,
    /// Give up after this many steps.
    pub max_iterations: usize,
    /// Longest single step (absolute length).
    pub max_step: f64,
}

impl ProjectOptions {
    /// Options scaled to a model of bounding-box diagonal `diag`: tolerance 1e-7 diag, 30
    /// iterations, steps of at most 1 % of the diagonal.
    pub fn for_diagonal(diag: f64) -> ProjectOptions {
        ProjectOptions {
            tolerance: 1e-7 * diag,
            max_iterations: 30,
            max_step: 0.01 * diag,
        }
    }
}

/// Projects `x0` onto f = 0 along the gradient. Returns the point and the number of steps.
pub fn project<F: Implicit + ?Sized>(
    f: &F,
    x0: &Point3<f64>,
    opts: &ProjectOptions,
) -> Result<(Point3<f64>, usize)> {
    let mut x = *x0;
    for it in 0..=opts.max_iterations {
        let (v, g) = f.value_and_gradient(&x);
        if !v.is_finite() {
            return Err(Error::Numerical("implicit value is not finite".into()));
        }
        if v.abs() <= opts.tolerance {
            return Ok((x, it));
        }
        if it == opts.max_iterations {
            break;
        }
        let g2 = g.norm_squared();
        if !(g2.is_finite()) || g2 <= 1e-300 {
            return Err(Error::Numerical("vanishing gradient in projection".into()));
        }
        let mut step = g * (v / g2);
        let len = step.norm();
        if len > opts.max_step {
            step *= opts.max_step / len;
        }
        x -= step;
    }
    Err(Error::Numerical(format!(
        "projection did not converge in {} steps",
        opts.max_iterations
    )))
}

// Safeguarded projections (seed 000 eq. 8-12, the hole fills): a step is halved while it does
// not decrease |f|, and the point may move at most `max_dist` from where it started; `None`
// when that fails, so the caller can fall back rather than place a node far off.

/// Iterations of the safeguarded projections.
const MAX_ITER: usize = 40;

/// The intersection of the line `r0 + lambda dir` with f = 0 nearest along Newton's path, within
/// `max_dist` of `r0`; converged when |f| <= `tol`.
pub fn project_along_within(
    f: &dyn Implicit,
    r0: &Point3<f64>,
    dir: &Vector3<f64>,
    max_dist: f64,
    tol: f64,
) -> Option<Point3<f64>> {
    let dn = dir.norm();
    if !(dn > 0.0 && dn.is_finite()) {
        return None;
    }
    let d = dir / dn;
    let mut lambda = 0.0;
    let (mut fv, mut g) = f.value_and_gradient(r0);
    for _ in 0..MAX_ITER {
        if !fv.is_finite() {
            return None;
        }
        if fv.abs() <= tol {
            return Some(r0 + d * lambda);
        }
        let slope = d.dot(&g);
        if slope.is_nan() || slope.abs() <= 1e-12 {
            return None;
        }
        let step = (-fv / slope).clamp(-max_dist, max_dist);
        (fv, (lambda, g)) = backtrack(fv, 12, |s| {
            let l = lambda + step * s;
            (l.abs() <= max_dist).then(|| {
                let (fl, gl) = f.value_and_gradient(&(r0 + d * l));
                (fl, (l, gl))
            })
        })?;
    }
    (fv.abs() <= tol * 10.0).then(|| r0 + d * lambda)
}

/// Projects `x0` onto f = 0 along the gradient (x <- x - f grad f / |grad f|^2), within
/// `max_dist` of `x0`.
pub fn project_gradient_within(
    f: &dyn Implicit,
    x0: &Point3<f64>,
    max_dist: f64,
    tol: f64,
) -> Option<Point3<f64>> {
    project_gradient_with_normal(f, x0, max_dist, tol).map(|(x, _)| x)
}

/// [`project_gradient_within`], also returning grad f at the result (evaluated there anyway).
pub fn project_gradient_with_normal(
    f: &dyn Implicit,
    x0: &Point3<f64>,
    max_dist: f64,
    tol: f64,
) -> Option<(Point3<f64>, Vector3<f64>)> {
    let mut x = *x0;
    let (mut fv, mut g) = f.value_and_gradient(&x);
    for _ in 0..MAX_ITER {
        if !fv.is_finite() {
            return None;
        }
        if fv.abs() <= tol {
            return Some((x, g));
        }
        let g2 = g.norm_squared();
        if g2.is_nan() || g2 <= 1e-24 {
            return None;
        }
        let step = -g * (fv / g2);
        (fv, (x, g)) = backtrack(fv, 12, |s| {
            let y = x + step * s;
            ((y - x0).norm() <= max_dist).then(|| {
                let (fy, gy) = f.value_and_gradient(&y);
                (fy, (y, gy))
            })
        })?;
    }
    (fv.abs() <= tol * 10.0).then_some((x, g))
}

/// The backtracking of the damped Newton iterations (here and in `polygonize::newton`): tries
/// the fractions s = 1, 1/2, 1/4, ... of a full step, at most `tries` of them; `trial(s)` gives
/// f at the candidate that fraction of the step away and the candidate itself, or `None` when
/// the candidate leaves the allowed region. Returns the first candidate where f is finite and
/// |f| < |`f_now`|, or `None` when no fraction decreases |f|.
pub(crate) fn backtrack<C>(
    f_now: f64,
    tries: usize,
    mut trial: impl FnMut(f64) -> Option<(f64, C)>,
) -> Option<(f64, C)> {
    let mut s = 1.0;
    for _ in 0..tries {
        if let Some((fv, c)) = trial(s) {
            if fv.is_finite() && fv.abs() < f_now.abs() {
                return Some((fv, c));
            }
        }
        s *= 0.5;
    }
    None
}

/// Distance estimate |f| / |grad f| of `x` from the surface.
pub fn distance_estimate(f: &dyn Implicit, x: &Point3<f64>) -> f64 {
    let (v, g) = f.value_and_gradient(x);
    let gn = g.norm();
    if gn > 0.0 {
        v.abs() / gn
    } else {
        v.abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sphere;
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - 1.0
        }
        fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
            x.coords.normalize()
        }
    }
    struct Flat;
    impl Implicit for Flat {
        fn value(&self, _: &Point3<f64>) -> f64 {
            1.0
        }
        fn gradient(&self, _: &Point3<f64>) -> Vector3<f64> {
            Vector3::zeros()
        }
    }

    #[test]
    fn projects_onto_sphere() {
        let o = ProjectOptions::for_diagonal(3.0);
        let (p, it) = project(&Sphere, &Point3::new(0.5, 0.4, 0.9), &o).unwrap();
        assert!((p.coords.norm() - 1.0).abs() < 1e-6);
        assert!(it <= 10);
        let p = project_along_within(
            &Sphere,
            &Point3::new(0.0, 0.0, 0.2),
            &Vector3::new(0.0, 1.0, 1.0),
            1.0,
            1e-12,
        )
        .unwrap();
        assert!((p.coords.norm() - 1.0).abs() < 1e-12);
        assert!(p.x.abs() < 1e-12 && p.y > 0.0);
        let p = project_along_within(
            &Sphere,
            &Point3::new(0.3, 0.2, 0.5),
            &Vector3::z(),
            1.0,
            1e-12,
        )
        .unwrap();
        assert!((p.x - 0.3).abs() < 1e-15 && (p.y - 0.2).abs() < 1e-15 && p.z > 0.9);
        let q = project_gradient_within(&Sphere, &Point3::new(0.0, 0.0, 1.3), 1.0, 1e-12).unwrap();
        assert!((q.z - 1.0).abs() < 1e-12);
        assert!((distance_estimate(&Sphere, &Point3::new(0.0, 2.0, 0.0)) - 1.0).abs() < 1e-12);
    }

    /// Halves until |f| decreases, skips disallowed candidates, gives up after `tries`.
    #[test]
    fn backtrack_halves_until_f_decreases() {
        // f(x) = |x - 1| - 0.5 from x = 0 (f = 0.5), full step 4: fractions 1, 1/2 land at 4
        // and 2 (f = 2.5, 0.5), 1/4 at 1 (f = -0.5, |f| not smaller), 1/8 at 0.5 (f = 0).
        let f = |x: f64| (x - 1.0).abs() - 0.5;
        let r = backtrack(0.5, 10, |s| Some((f(4.0 * s), 4.0 * s)));
        assert_eq!(r, Some((0.0, 0.5)));
        let r = backtrack(0.5, 10, |s| (4.0 * s < 0.6).then(|| (f(4.0 * s), 4.0 * s)));
        assert_eq!(r, Some((0.0, 0.5)));
        assert_eq!(backtrack(0.5, 3, |s| Some((f(4.0 * s), 4.0 * s))), None);
        assert_eq!(backtrack(0.5, 10, |_| Some((f64::NAN, 0.0))), None);
    }

    #[test]
    fn failures_are_errors_or_none() {
        let o = ProjectOptions::for_diagonal(1.0);
        assert!(project(&Flat, &Point3::origin(), &o).is_err());
        let origin = Point3::origin();
        assert!(project_along_within(&Sphere, &origin, &Vector3::zeros(), 1.0, 1e-9).is_none());
        // A line that misses the sphere; a start too far for max_dist.
        let x = Point3::new(2.0, 0.0, 0.0);
        assert!(project_along_within(&Sphere, &x, &Vector3::z(), 5.0, 1e-12).is_none());
        let z = Point3::new(0.0, 0.0, 3.0);
        assert!(project_gradient_within(&Sphere, &z, 1.0, 1e-12).is_none());
        let few = ProjectOptions {
            max_iterations: 2,
            max_step: 1e-3,
            ..o
        };
        assert!(project(&Sphere, &Point3::new(5.0, 0.0, 0.0), &few).is_err());
    }
}
