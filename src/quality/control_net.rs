//! How far the patches' control points leave the input's bounding box. A patch whose
//! interpolation went wrong (a sample grid with a wild point, a degenerate parameterization)
//! can have control points many times the part's size away, and still read back as a valid
//! face and keep the input points' deviation small, since its wild part is where no point
//! lies; this measures it. By the convex hull property the surface lies within its control
//! points' box, so a patch within the bar cannot reach farther than that.
//!
//! Per patch: e = |(max(0, m_k - lo_k, hi_k - M_k))_k|, the excess of its control points' box
//! [lo, hi] over the input's [m, M] along each axis, relative to the input's diagonal.

use crate::mesh::Aabb;
use crate::nurbs::PatchNetwork;
use nalgebra::Vector3;

/// Excess (fraction of the diagonal) above which a patch counts as outside.
pub const OUTSIDE_BAR: f64 = 0.1;

/// The report's `control_net`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ControlNetReport {
    /// Largest excess of a patch's control points over the input's bounding box, relative to
    /// its diagonal (0 when all lie within).
    pub outside_max: f64,
    /// Patches whose excess is over [`OUTSIDE_BAR`].
    pub patches_outside: usize,
}

/// The excess of the box [lo, hi] over `bounds` (module doc), absolute.
pub fn excess(lo: &Vector3<f64>, hi: &Vector3<f64>, bounds: &Aabb) -> f64 {
    let e = Vector3::from_fn(|k, _| (bounds.min[k] - lo[k]).max(hi[k] - bounds.max[k]).max(0.0));
    e.norm()
}

/// Measures the control points of every patch of `network` against `bounds`.
pub fn control_net(network: &PatchNetwork, bounds: &Aabb) -> ControlNetReport {
    let diag = bounds.diagonal().max(f64::MIN_POSITIVE);
    let mut report = ControlNetReport {
        outside_max: 0.0,
        patches_outside: 0,
    };
    for face in &network.faces {
        let (lo, hi) = face.surface.ctrl_bounds();
        let e = excess(&lo, &hi, bounds) / diag;
        // A non-finite control point is as far out as can be.
        let e = if e.is_finite() { e } else { f64::INFINITY };
        report.outside_max = report.outside_max.max(e);
        if e > OUTSIDE_BAR {
            report.patches_outside += 1;
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn excess_is_the_distance_beyond_the_box() {
        let b = Aabb {
            min: Point3::new(0.0, 0.0, 0.0),
            max: Point3::new(1.0, 1.0, 1.0),
        };
        let inside = excess(&Vector3::repeat(0.1), &Vector3::repeat(0.9), &b);
        assert_eq!(inside, 0.0);
        // 3 beyond in x, 4 below in y: 5.
        let out = excess(
            &Vector3::new(0.0, -4.0, 0.5),
            &Vector3::new(4.0, 1.0, 0.5),
            &b,
        );
        assert!((out - 5.0).abs() < 1e-12);
    }
}
