//! Implicit surfaces f(x) = 0, the spine of scansurf: every input becomes one, every output is
//! extracted from one. Convention: f < 0 inside, f > 0 outside, and near the surface |grad f|
//! is close to 1 so that f approximates a signed distance.

use nalgebra::{Point3, Vector3};

/// A scalar field whose zero set is a surface.
pub trait Implicit: Sync {
    /// f(x).
    fn value(&self, x: &Point3<f64>) -> f64;
    /// grad f(x). The default is a central difference; implementations should override it with
    /// the analytic gradient.
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        let h = 1e-6 * (1.0 + x.coords.abs().max());
        let mut g = Vector3::zeros();
        for k in 0..3 {
            let mut a = *x;
            let mut b = *x;
            a[k] += h;
            b[k] -= h;
            g[k] = (self.value(&a) - self.value(&b)) / (2.0 * h);
        }
        g
    }
    /// f(x) and grad f(x) together (implementations can share work).
    fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        (self.value(x), self.gradient(x))
    }
}

pub mod framed;
pub mod local;
pub mod noise;
pub mod poly;
pub mod pou;
pub mod project;
pub mod rbf;
pub mod sharp;
pub mod tps_kernel;

pub use pou::{FitOptions, FitStats, PouImplicit};
