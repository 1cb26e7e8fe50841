//! An implicit seen in a rotated frame: g(y) = f(R^T y), grad g(y) = R grad f(R^T y), for a
//! rotation R taking world coordinates x to frame coordinates y = R x. The quad net of a part
//! whose faces are not along the world axes is built in the frame of its faces
//! ([`crate::features::grid_frame`]), so that the voxel grid, and the net, follow them.

use super::Implicit;
use nalgebra::{Point3, Rotation3, Vector3};

/// `f` in the frame y = R x.
pub struct Framed<'a, I: Implicit + ?Sized> {
    pub f: &'a I,
    /// World to frame.
    pub r: Rotation3<f64>,
}

impl<I: Implicit + ?Sized> Implicit for Framed<'_, I> {
    fn value(&self, y: &Point3<f64>) -> f64 {
        self.f.value(&(self.r.inverse() * y))
    }
    fn gradient(&self, y: &Point3<f64>) -> Vector3<f64> {
        self.r * self.f.gradient(&(self.r.inverse() * y))
    }
    fn value_and_gradient(&self, y: &Point3<f64>) -> (f64, Vector3<f64>) {
        let (v, g) = self.f.value_and_gradient(&(self.r.inverse() * y));
        (v, self.r * g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Plane;
    impl Implicit for Plane {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.z - 1.0
        }
        fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
            (self.value(x), Vector3::z())
        }
    }

    #[test]
    fn a_plane_seen_in_a_turned_frame() {
        // R takes the world's z axis to the frame's x axis.
        let r = Rotation3::rotation_between(&Vector3::z(), &Vector3::x()).unwrap();
        let g = Framed { f: &Plane, r };
        let y = Point3::new(1.0, 0.3, -0.2);
        assert!(g.value(&y).abs() < 1e-12);
        let (_, grad) = g.value_and_gradient(&y);
        assert!((grad - Vector3::x()).norm() < 1e-12);
        // (The plane's gradient is the default central difference.)
        assert!((g.gradient(&y) - Vector3::x()).norm() < 1e-6);
    }
}
