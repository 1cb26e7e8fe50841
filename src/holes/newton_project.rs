//! Projection of points onto an implicit surface f = 0 by Newton's method (seed 000 eq. 8-12).
//!
//! Along a given direction N (the plane normal for the first projection of the fill's nodes):
//!
//! ```text
//! r(lambda) = r0 + lambda N                           (eq. 8)
//! lambda_{i+1} = lambda_i - F(lambda_i) / F'(lambda_i)  (eq. 9)
//! F'(lambda) = N . grad f(r(lambda))                   (eq. 10, 12)
//! ```
//!
//! and along the surface normal n = grad f / |grad f| (eq. 11) for the re-projection after
//! relaxation, where the same iteration reads x <- x - f(x) grad f / |grad f|^2.
//!
//! Both are safeguarded: a step is halved while it does not decrease |f|, and the point may move
//! at most `max_dist` from where it started. They return `None` when that fails, so the caller
//! can fall back rather than place a node far off.

use crate::implicit::Implicit;
use nalgebra::{Point3, Vector3};

const MAX_ITER: usize = 40;

/// The intersection of the line `r0 + lambda dir` with f = 0 nearest along Newton's path, within
/// `max_dist` of `r0`; converged when |f| <= `tol`.
pub fn project_along(
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
        if !(slope.abs() > 1e-12) {
            return None;
        }
        let mut step = -fv / slope;
        step = step.clamp(-max_dist, max_dist);
        let mut accepted = false;
        for _ in 0..12 {
            let l = lambda + step;
            if l.abs() <= max_dist {
                let (fn_, gn) = f.value_and_gradient(&(r0 + d * l));
                if fn_.is_finite() && fn_.abs() < fv.abs() {
                    lambda = l;
                    fv = fn_;
                    g = gn;
                    accepted = true;
                    break;
                }
            }
            step *= 0.5;
        }
        if !accepted {
            return None;
        }
    }
    (fv.abs() <= tol * 10.0).then(|| r0 + d * lambda)
}

/// Projects `x0` onto f = 0 along the gradient (x <- x - f grad f / |grad f|^2), within
/// `max_dist` of `x0`.
pub fn project_gradient(
    f: &dyn Implicit,
    x0: &Point3<f64>,
    max_dist: f64,
    tol: f64,
) -> Option<Point3<f64>> {
    project_gradient_with_normal(f, x0, max_dist, tol).map(|(x, _)| x)
}

/// [`project_gradient`], also returning grad f at the result (evaluated there anyway).
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
        if !(g2 > 1e-24) {
            return None;
        }
        let mut step = -g * (fv / g2);
        let mut accepted = false;
        for _ in 0..12 {
            let y = x + step;
            if (y - x0).norm() <= max_dist {
                let (fy, gy) = f.value_and_gradient(&y);
                if fy.is_finite() && fy.abs() < fv.abs() {
                    x = y;
                    fv = fy;
                    g = gy;
                    accepted = true;
                    break;
                }
            }
            step *= 0.5;
        }
        if !accepted {
            return None;
        }
    }
    (fv.abs() <= tol * 10.0).then_some((x, g))
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

    struct Sphere(f64);
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - self.0
        }
        fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
            x.coords.normalize()
        }
    }

    #[test]
    fn projects_onto_a_sphere() {
        let s = Sphere(1.0);
        let p = project_along(&s, &Point3::new(0.3, 0.2, 0.5), &Vector3::z(), 1.0, 1e-12).unwrap();
        assert!((p.coords.norm() - 1.0).abs() < 1e-12);
        assert!((p.x - 0.3).abs() < 1e-15 && (p.y - 0.2).abs() < 1e-15 && p.z > 0.9);
        let q = project_gradient(&s, &Point3::new(0.0, 0.0, 1.3), 1.0, 1e-12).unwrap();
        assert!((q.z - 1.0).abs() < 1e-12);
        // A line that misses the sphere.
        assert!(
            project_along(&s, &Point3::new(2.0, 0.0, 0.0), &Vector3::z(), 5.0, 1e-12).is_none()
        );
        // Too far.
        assert!(project_gradient(&s, &Point3::new(0.0, 0.0, 3.0), 1.0, 1e-12).is_none());
        assert!((distance_estimate(&s, &Point3::new(0.0, 2.0, 0.0)) - 1.0).abs() < 1e-12);
    }
}
