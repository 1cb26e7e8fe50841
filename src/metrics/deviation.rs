//! Deviation of points from a triangle mesh: the exact Euclidean distance from each point to the
//! nearest point of any triangle, and its statistics (mean, rms, p95, p99, max), absolute and as
//! fractions of a reference length (the bounding-box diagonal of the input).
//!
//! The nearest triangle is found with a bounding-volume hierarchy ([`TriangleBvh`]), exactly.

use crate::mesh::Mesh;
use crate::spatial::TriangleBvh;
use crate::{Error, Result};
use nalgebra::Point3;
use rayon::prelude::*;

/// Statistics of a set of distances.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct DistanceStats {
    pub mean: f64,
    pub rms: f64,
    pub p95: f64,
    pub p99: f64,
    pub max: f64,
}

/// Deviation of points from a mesh.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Deviation {
    pub count: usize,
    /// Reference length (e.g. the bounding-box diagonal of the input).
    pub reference: f64,
    pub absolute: DistanceStats,
    /// `absolute` divided by `reference`.
    pub relative: DistanceStats,
}

/// Closest point to `p` on triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
pub fn closest_point_on_triangle(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Point3<f64> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() <= f64::MIN_POSITIVE {
        // Degenerate triangle: fall back to its vertices and edges.
        return [*a, *b, *c]
            .into_iter()
            .min_by(|x, y| (x - p).norm_squared().total_cmp(&(y - p).norm_squared()))
            .unwrap_or(*a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

/// Exact distance from every point to the mesh (parallel, deterministic).
pub fn point_to_mesh_distances(points: &[Point3<f64>], mesh: &Mesh) -> Result<Vec<f64>> {
    if mesh.faces.is_empty() {
        return Err(Error::Degenerate(
            "deviation from a mesh without faces".into(),
        ));
    }
    let bvh = TriangleBvh::build(mesh)?;
    Ok(points.par_iter().map(|p| bvh.closest(mesh, p).2).collect())
}

/// Mean, rms, 95th and 99th percentile (nearest rank) and maximum of `d`.
pub fn distance_stats(d: &[f64]) -> DistanceStats {
    if d.is_empty() {
        return DistanceStats::default();
    }
    let n = d.len() as f64;
    let mut s = d.to_vec();
    s.sort_by(f64::total_cmp);
    let rank = |q: f64| s[((q * n).ceil() as usize).clamp(1, s.len()) - 1];
    DistanceStats {
        mean: d.iter().sum::<f64>() / n,
        rms: (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
        p95: rank(0.95),
        p99: rank(0.99),
        max: s[s.len() - 1],
    }
}

/// Deviation of `points` from `mesh`, relative figures divided by `reference`.
pub fn deviation(points: &[Point3<f64>], mesh: &Mesh, reference: f64) -> Result<Deviation> {
    let d = point_to_mesh_distances(points, mesh)?;
    Ok(Deviation::from_distances(&d, reference))
}

impl Deviation {
    /// Statistics of the distances `d`, relative figures divided by `reference`.
    pub fn from_distances(d: &[f64], reference: f64) -> Deviation {
        let a = distance_stats(d);
        let r = if reference > 0.0 { reference } else { 1.0 };
        Deviation {
            count: d.len(),
            reference: r,
            absolute: a,
            relative: DistanceStats {
                mean: a.mean / r,
                rms: a.rms / r,
                p95: a.p95 / r,
                p99: a.p99 / r,
                max: a.max / r,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        Mesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            normals: None,
            faces: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        );
        let q = |x, y, z| closest_point_on_triangle(&Point3::new(x, y, z), &a, &b, &c);
        let near = |x: Point3<f64>, y: Point3<f64>| (x - y).norm() < 1e-12;
        assert!(near(q(0.2, 0.2, 1.0), Point3::new(0.2, 0.2, 0.0)));
        assert_eq!(q(-1.0, -1.0, 0.0), a);
        assert_eq!(q(2.0, -0.5, 0.0), b);
        assert!(near(q(0.5, -1.0, 0.3), Point3::new(0.5, 0.0, 0.0)));
        let e = q(1.0, 1.0, 0.0);
        assert!((e - Point3::new(0.5, 0.5, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn distances_and_stats() {
        let m = square();
        let pts = vec![
            Point3::new(0.5, 0.5, 0.1),
            Point3::new(0.25, 0.75, -0.2),
            Point3::new(2.0, 0.5, 0.0),
            Point3::new(0.0, 0.0, 0.0),
        ];
        let d = point_to_mesh_distances(&pts, &m).unwrap();
        let want = [0.1, 0.2, 1.0, 0.0];
        for (x, y) in d.iter().zip(want) {
            assert!((x - y).abs() < 1e-12);
        }
        let dev = deviation(&pts, &m, 2.0).unwrap();
        assert!((dev.absolute.mean - 0.325).abs() < 1e-12);
        assert_eq!(dev.absolute.max, 1.0);
        assert_eq!(dev.relative.max, 0.5);
        assert_eq!(dev.absolute.p99, 1.0);
        assert!(deviation(&pts, &Mesh::default(), 1.0).is_err());
    }
}
