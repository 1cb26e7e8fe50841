//! The frame of a machined part's plane faces, for the voxel grid of its quad net
//! (`fit --sharp`; issue 36 item 2: a crease along a grid axis gives a straight path of net
//! edges, one at an angle a staircase).
//!
//! Each smooth region whose points lie within [`PLANAR`] of their best plane (the ratio of
//! the smallest to the middle principal spread, so that it does not depend on the part's size)
//! gives its normal, weighted by its point count. The frame's third axis is the normal with
//! the most weight within [`ALIGN_DEG`] of it (a plate's top and bottom, a block's pairs of
//! faces count together), averaged over those; its first axis likewise among the normals
//! within [`ALIGN_DEG`] of perpendicular to the third, projected onto the plane across it;
//! the second completes the right-handed frame. With no second direction the first is the
//! world axis most across the third.
//!
//! `None` when less than [`MIN_PLANAR_SHARE`] of the region points lie on plane faces (no
//! frame to follow), or when each frame axis lies within [`ALIGNED_DEG`] of a world axis: the
//! part is already along the grid, which then stays as it is (the same net as without it).

use super::Segmentation;
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Largest ratio of a plane face's smallest to middle principal spread.
pub const PLANAR: f64 = 0.02;
/// Normals this close (degrees) count as one direction.
pub const ALIGN_DEG: f64 = 5.0;
/// Smallest share of the region points on plane faces for a frame.
pub const MIN_PLANAR_SHARE: f64 = 0.3;
/// A frame whose axes all lie this close (degrees) to world axes is the world's.
pub const ALIGNED_DEG: f64 = 1.0;

/// The frame chosen (the report's `grid_frame`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GridFrame {
    /// The frame's axes in world coordinates (rows of the rotation world -> frame).
    pub axes: [[f64; 3]; 3],
    /// Share of the region points on plane faces.
    pub planar_share: f64,
    /// Plane faces found.
    pub planes: usize,
}

impl GridFrame {
    /// The rotation taking world coordinates to frame coordinates.
    pub fn rotation(&self) -> Rotation3<f64> {
        let a = self.axes;
        Rotation3::from_matrix_unchecked(Matrix3::new(
            a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2],
        ))
    }
}

/// The frame of the plane faces of `seg` (module doc), or `None`.
pub fn grid_frame(seg: &Segmentation) -> Option<GridFrame> {
    let total: usize = seg.regions.iter().map(|r| r.points.len()).sum();
    let planes: Vec<(Vector3<f64>, f64)> = seg
        .regions
        .iter()
        .filter_map(|r| plane_normal(&r.points).map(|n| (n, r.points.len() as f64)))
        .collect();
    let planar: f64 = planes.iter().map(|p| p.1).sum();
    if total == 0 || planar < MIN_PLANAR_SHARE * total as f64 {
        return None;
    }
    let cos = ALIGN_DEG.to_radians().cos();
    let sin = ALIGN_DEG.to_radians().sin();
    let z = dominant(&planes, cos)?;
    let across: Vec<(Vector3<f64>, f64)> = planes
        .iter()
        .filter(|(n, _)| n.dot(&z).abs() < sin)
        .filter_map(|(n, w)| (n - z * n.dot(&z)).try_normalize(1e-9).map(|m| (m, *w)))
        .collect();
    let x = match dominant(&across, cos) {
        Some(x) => (x - z * x.dot(&z)).try_normalize(1e-9)?,
        None => {
            let e = [Vector3::x(), Vector3::y(), Vector3::z()];
            let k = (0..3).min_by(|&a, &b| e[a].dot(&z).abs().total_cmp(&e[b].dot(&z).abs()))?;
            (e[k] - z * e[k].dot(&z)).try_normalize(1e-9)?
        }
    };
    let y = z.cross(&x);
    let aligned = ALIGNED_DEG.to_radians().cos();
    let is_world = [x, y, z]
        .iter()
        .all(|a| a.iter().any(|c| c.abs() > aligned));
    if is_world {
        return None;
    }
    Some(GridFrame {
        axes: [x.into(), y.into(), z.into()],
        planar_share: planar / total as f64,
        planes: planes.len(),
    })
}

/// The unit normal of `pts` when they lie on a plane (module doc).
fn plane_normal(pts: &[nalgebra::Point3<f64>]) -> Option<Vector3<f64>> {
    if pts.len() < 10 {
        return None;
    }
    let (spread, axes) = super::local_fit::principal_axes(pts)?;
    let (lo, mid) = (spread[0].max(0.0), spread[1]);
    if mid.is_nan() || mid <= 0.0 || (lo / mid).sqrt() > PLANAR {
        return None;
    }
    axes[0].try_normalize(1e-12)
}

/// The direction of `normals` (sign-free) with the most weight within the angle of cosine
/// `cos` of it, averaged over those; ties go to the earliest.
fn dominant(normals: &[(Vector3<f64>, f64)], cos: f64) -> Option<Vector3<f64>> {
    let support = |a: &Vector3<f64>| -> f64 {
        normals
            .iter()
            .filter(|(n, _)| n.dot(a).abs() > cos)
            .map(|(_, w)| w)
            .sum()
    };
    let mut best: Option<(f64, Vector3<f64>)> = None;
    for (n, _) in normals {
        let s = support(n);
        if best.as_ref().is_none_or(|b| s > b.0) {
            best = Some((s, *n));
        }
    }
    let (_, a) = best?;
    let mut sum = Vector3::zeros();
    for (n, w) in normals {
        let d = n.dot(&a);
        if d.abs() > cos {
            sum += n * (w * d.signum());
        }
    }
    sum.try_normalize(1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{Region, SegmentStats, Segmentation};
    use nalgebra::Point3;

    /// The six faces of a box turned by `rot`, as regions of sampled points.
    fn box_regions(rot: Rotation3<f64>) -> Segmentation {
        let mut regions = Vec::new();
        for k in 0..3 {
            for s in [-1.0, 1.0] {
                let mut r = Region::default();
                for i in 0..10 {
                    for j in 0..10 {
                        let mut p = Vector3::zeros();
                        p[k] = s;
                        p[(k + 1) % 3] = -0.9 + 0.2 * i as f64;
                        p[(k + 2) % 3] = -0.9 + 0.2 * j as f64;
                        r.points.push(Point3::from(rot * p));
                        r.normals.push(rot * Vector3::ith(k, s));
                    }
                }
                regions.push(r);
            }
        }
        Segmentation::from_regions(regions, SegmentStats::default()).unwrap()
    }

    #[test]
    fn a_turned_box_gives_its_own_axes_and_an_aligned_one_none() {
        assert!(grid_frame(&box_regions(Rotation3::identity())).is_none());
        let rot = Rotation3::from_euler_angles(0.35, 0.26, 0.61);
        let frame = grid_frame(&box_regions(rot)).expect("a frame");
        // Each frame axis is one of the box's axes, so R rot is a signed permutation.
        let m = frame.rotation() * rot;
        for row in m.matrix().row_iter() {
            assert!(row.iter().any(|c| (c.abs() - 1.0).abs() < 1e-9), "{m}");
        }
        assert_eq!(frame.planes, 6);
        assert!((frame.planar_share - 1.0).abs() < 1e-12);
    }
}
