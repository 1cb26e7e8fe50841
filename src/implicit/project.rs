//! Newton projection of points onto the zero set of an implicit (seed 003 section 3.3's "normal
//! projection", seed 000 eq. 8-12).
//!
//! Along the gradient: `x <- x - f(x) grad f(x) / |grad f(x)|^2` (the closest-point Newton step
//! for an implicit that is about a distance). Along a fixed direction `d` (seed 000 eq. 8-12, one
//! unknown `t` on the line `x0 + t d`): `t <- t - f / (grad f . d)`. Steps are limited in length
//! so that a poor start cannot jump across the model; failure to converge is an `Err`.

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

/// Projects `x0` onto f = 0 along the line `x0 + t dir` (seed 000 eq. 8-12). Returns the point
/// and the number of steps.
pub fn project_along<F: Implicit + ?Sized>(
    f: &F,
    x0: &Point3<f64>,
    dir: &Vector3<f64>,
    opts: &ProjectOptions,
) -> Result<(Point3<f64>, usize)> {
    let d = dir
        .try_normalize(1e-300)
        .ok_or_else(|| Error::Degenerate("zero projection direction".into()))?;
    let mut t = 0.0;
    for it in 0..=opts.max_iterations {
        let x = x0 + d * t;
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
        let gd = g.dot(&d);
        if !gd.is_finite() || gd.abs() <= 1e-12 * g.norm().max(1e-300) {
            return Err(Error::Numerical(
                "projection direction is tangent to the surface".into(),
            ));
        }
        t -= (v / gd).clamp(-opts.max_step, opts.max_step);
    }
    Err(Error::Numerical(format!(
        "projection did not converge in {} steps",
        opts.max_iterations
    )))
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
        let (p, _) = project_along(
            &Sphere,
            &Point3::new(0.0, 0.0, 0.2),
            &Vector3::new(0.0, 1.0, 1.0),
            &o,
        )
        .unwrap();
        assert!((p.coords.norm() - 1.0).abs() < 1e-6);
        assert!(p.x.abs() < 1e-12 && p.y > 0.0);
    }

    #[test]
    fn failures_are_errors() {
        let o = ProjectOptions::for_diagonal(1.0);
        assert!(project(&Flat, &Point3::origin(), &o).is_err());
        assert!(project_along(&Sphere, &Point3::origin(), &Vector3::zeros(), &o).is_err());
        let few = ProjectOptions {
            max_iterations: 2,
            max_step: 1e-3,
            ..o
        };
        assert!(project(&Sphere, &Point3::new(5.0, 0.0, 0.0), &few).is_err());
    }
}
