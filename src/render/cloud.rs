//! What shading a bare point cloud needs: a normal and a spacing per point, both from the `K`
//! nearest neighbours (kiddo k-d tree).
//!
//! The normal is the eigenvector of the smallest eigenvalue of the neighbourhood's covariance
//! `C = 1/K sum (q - m)(q - m)^T` (the direction the neighbours spread least in: the local
//! plane's normal). Its sign is left arbitrary: the renderer lights points two-sided. The
//! spacing is the median over all points of the distance to the `SPACING_K`-th neighbour, a
//! robust scale for the splat size that is blind to a few stray points.

use crate::error::{Error, Result};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Neighbours per normal estimate.
const K: usize = 12;
/// Which neighbour's distance measures the spacing (the point itself is neighbour 0).
const SPACING_K: usize = 4;

/// Unit normals (arbitrary sign; zero where the neighbourhood is degenerate) and the median
/// spacing of the points. With `want_normals` false only the spacing is measured (a cheaper
/// query) and the normals come back empty.
pub fn normals_and_spacing(
    points: &[Point3<f64>],
    want_normals: bool,
) -> Result<(Vec<Vector3<f64>>, f64)> {
    if points.is_empty() {
        return Err(Error::Degenerate("no points".into()));
    }
    if points.len() > u32::MAX as usize {
        return Err(Error::Degenerate("too many points for a k-d tree".into()));
    }
    let entries: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&entries)
        .map_err(|e| Error::Degenerate(format!("k-d tree construction: {e:?}")))?;
    let k = if want_normals { K } else { SPACING_K + 1 };
    let k = NonZeroUsize::new(k.min(points.len())).unwrap_or(NonZeroUsize::MIN);
    let per_point: Vec<(Vector3<f64>, f64)> = entries
        .par_iter()
        .map(|q| {
            let nn = tree
                .query(q)
                .nearest_n::<SquaredEuclidean<f64>>(k)
                .execute();
            let spacing = nn
                .get(SPACING_K.min(nn.len().saturating_sub(1)))
                .map(|r| r.distance.max(0.0).sqrt())
                .unwrap_or(0.0);
            let pts: Vec<Vector3<f64>> =
                nn.iter().map(|r| points[r.item as usize].coords).collect();
            (plane_normal(&pts), spacing)
        })
        .collect();
    let mut sp: Vec<f64> = per_point.iter().map(|p| p.1).filter(|s| *s > 0.0).collect();
    let spacing = if sp.is_empty() {
        0.0
    } else {
        let mid = sp.len() / 2;
        *sp.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
    };
    let normals = if want_normals {
        per_point.into_iter().map(|p| p.0).collect()
    } else {
        Vec::new()
    };
    Ok((normals, spacing))
}

/// Normal of the least-squares plane through `pts` (zero when fewer than 3 or degenerate).
fn plane_normal(pts: &[Vector3<f64>]) -> Vector3<f64> {
    if pts.len() < 3 {
        return Vector3::zeros();
    }
    let m = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
    let c = pts
        .iter()
        .fold(Matrix3::zeros(), |c, q| c + (q - m) * (q - m).transpose());
    let e = SymmetricEigen::new(c);
    let (mut best, mut val) = (0, f64::INFINITY);
    for i in 0..3 {
        if e.eigenvalues[i] < val {
            val = e.eigenvalues[i];
            best = i;
        }
    }
    let n = e.eigenvectors.column(best).into_owned();
    let l = n.norm();
    if l > 0.0 && l.is_finite() && c.trace() > 0.0 {
        n / l
    } else {
        Vector3::zeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_and_sphere_normals() {
        let mut pts = Vec::new();
        for i in 0..30 {
            for j in 0..30 {
                pts.push(Point3::new(
                    i as f64 * 0.1,
                    j as f64 * 0.1,
                    0.3 * i as f64 * 0.1,
                ));
            }
        }
        let (n, s) = normals_and_spacing(&pts, true).unwrap();
        let (none, s2) = normals_and_spacing(&pts, false).unwrap();
        assert!(none.is_empty() && s2 == s);
        let expect = Vector3::new(-0.3, 0.0, 1.0).normalize();
        assert!(n.iter().all(|v| v.dot(&expect).abs() > 0.999));
        // The fourth neighbour on a grid of step 0.1 is an edge neighbour (0.104 across the slope).
        assert!(s > 0.1 && s < 0.16, "{s}");
        let one = [Point3::origin()];
        let (n, s) = normals_and_spacing(&one, true).unwrap();
        assert_eq!((n[0], s), (Vector3::zeros(), 0.0));
        assert!(normals_and_spacing(&[], true).is_err());
    }
}
