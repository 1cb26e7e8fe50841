//! Unoriented normals of a point cloud by principal component analysis: the normal of a point is
//! the eigenvector of the smallest eigenvalue of the covariance of its k nearest neighbours
//! (Hoppe et al. 1992, "Surface reconstruction from unorganized points").

use crate::spatial::KdTree;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;

/// Unit normals (sign arbitrary) from the `k` nearest neighbours of every point (the point
/// included). A point whose neighbours are all coincident or collinear gets the zero vector.
pub fn estimate_normals(points: &[Point3<f64>], kd: &KdTree, k: usize) -> Vec<Vector3<f64>> {
    let k = k.max(3);
    points
        .par_iter()
        .map(|p| {
            let nb = kd.knn(p, k);
            if nb.len() < 3 {
                return Vector3::zeros();
            }
            let mut c = Vector3::zeros();
            for (i, _) in &nb {
                c += points[*i].coords;
            }
            c /= nb.len() as f64;
            let mut cov = Matrix3::zeros();
            for (i, _) in &nb {
                let d = points[*i].coords - c;
                cov += d * d.transpose();
            }
            let e = SymmetricEigen::new(cov);
            let (mut lo, mut mid) = (0, 1);
            for j in 0..3 {
                if e.eigenvalues[j] < e.eigenvalues[lo] {
                    lo = j;
                }
            }
            for j in 0..3 {
                if j != lo && (mid == lo || e.eigenvalues[j] < e.eigenvalues[mid]) {
                    mid = j;
                }
            }
            // A line or a single point has no plane.
            let floor = 1e-12 * e.eigenvalues.max().max(f64::MIN_POSITIVE);
            if e.eigenvalues[mid].is_nan() || e.eigenvalues[mid] <= floor {
                return Vector3::zeros();
            }
            let n: Vector3<f64> = e.eigenvectors.column(lo).into_owned();
            n.try_normalize(1e-300).unwrap_or_else(Vector3::zeros)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_and_sphere_normals() {
        let mut pts = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                pts.push(Point3::new(
                    i as f64 * 0.1,
                    j as f64 * 0.1,
                    0.3 * i as f64 * 0.1,
                ));
            }
        }
        let kd = KdTree::build(&pts).unwrap();
        let n = estimate_normals(&pts, &kd, 10);
        let want = Vector3::new(-0.3, 0.0, 1.0).normalize();
        for x in &n {
            assert!(x.dot(&want).abs() > 0.999);
        }
        let line: Vec<_> = (0..10).map(|i| Point3::new(i as f64, 0.0, 0.0)).collect();
        let kd = KdTree::build(&line).unwrap();
        assert!(estimate_normals(&line, &kd, 5)
            .iter()
            .all(|n| n.norm() == 0.0));
    }
}
