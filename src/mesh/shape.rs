//! The shape of a triangle mesh's triangles, as `reconstruct`'s report states it.
//!
//! A triangle's angle at a corner a with neighbours b, c is atan2(|ab x ac|, ab . ac), which
//! stays accurate for angles near 0 and 180 degrees where acos of the normalised dot product
//! does not. A triangle is *degenerate* when its smallest angle is under
//! [`DEGENERATE_ANGLE_DEG`] or an edge has zero length: its normal is then undefined or
//! decided by rounding, so a CAD or FEM reader sees a spike, a crack or a flipped facet
//! there. A *sliver* has its smallest angle under [`SLIVER_ANGLE_DEG`]: harmless for display,
//! poor for meshing downstream.

use super::Mesh;
use rayon::prelude::*;

/// Smallest angle (degrees) below which a triangle counts as degenerate.
pub const DEGENERATE_ANGLE_DEG: f64 = 0.1;

/// Smallest angle (degrees) below which a triangle counts as a sliver.
pub const SLIVER_ANGLE_DEG: f64 = 10.0;

/// The triangles' angles over a mesh (degrees).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TriangleShape {
    /// The smallest angle of any triangle (0 for a mesh without triangles).
    pub min_angle_deg: f64,
    /// The mean over the triangles of each one's smallest angle (60 for equilateral ones).
    pub mean_min_angle_deg: f64,
    /// Triangles whose smallest angle is under [`SLIVER_ANGLE_DEG`].
    pub slivers: usize,
    /// Triangles whose smallest angle is under [`DEGENERATE_ANGLE_DEG`], or with a zero-length
    /// edge.
    pub degenerate: usize,
}

/// The smallest angle of the triangle (a, b, c) in degrees; 0 when an edge has zero length.
pub fn min_angle_deg(
    a: &nalgebra::Point3<f64>,
    b: &nalgebra::Point3<f64>,
    c: &nalgebra::Point3<f64>,
) -> f64 {
    let corner =
        |p: &nalgebra::Point3<f64>, q: &nalgebra::Point3<f64>, r: &nalgebra::Point3<f64>| {
            let (u, v) = (q - p, r - p);
            if u.norm_squared() == 0.0 || v.norm_squared() == 0.0 {
                return 0.0;
            }
            u.cross(&v).norm().atan2(u.dot(&v)).to_degrees()
        };
    corner(a, b, c).min(corner(b, c, a)).min(corner(c, a, b))
}

/// The shape figures of `mesh`'s triangles.
pub fn triangle_shape(mesh: &Mesh) -> TriangleShape {
    let angles: Vec<f64> = mesh
        .faces
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            min_angle_deg(&a, &b, &c)
        })
        .collect();
    let n = angles.len();
    TriangleShape {
        min_angle_deg: if n == 0 {
            0.0
        } else {
            angles.iter().copied().fold(f64::INFINITY, f64::min)
        },
        mean_min_angle_deg: if n == 0 {
            0.0
        } else {
            angles.iter().sum::<f64>() / n as f64
        },
        slivers: angles.iter().filter(|&&a| a < SLIVER_ANGLE_DEG).count(),
        degenerate: angles.iter().filter(|&&a| a < DEGENERATE_ANGLE_DEG).count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn mesh(positions: Vec<Point3<f64>>, faces: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            positions,
            normals: None,
            faces,
        }
    }

    #[test]
    fn angles_of_known_triangles() {
        let o = Point3::origin();
        let x = Point3::new(1.0, 0.0, 0.0);
        let y = Point3::new(0.0, 1.0, 0.0);
        assert!((min_angle_deg(&o, &x, &y) - 45.0).abs() < 1e-12);
        let e = Point3::new(0.5, 3f64.sqrt() / 2.0, 0.0);
        assert!((min_angle_deg(&o, &x, &e) - 60.0).abs() < 1e-12);
        // A needle 1e-6 high over a unit base: its smallest angle is about 1e-6 rad.
        let n = Point3::new(0.5, 1e-6, 0.0);
        let a = min_angle_deg(&o, &x, &n);
        assert!((a - 2e-6f64.to_degrees()).abs() < 1e-9, "{a}");
        // Collinear and coincident corners.
        assert_eq!(min_angle_deg(&o, &x, &Point3::new(2.0, 0.0, 0.0)), 0.0);
        assert_eq!(min_angle_deg(&o, &o, &x), 0.0);
    }

    #[test]
    fn counts_slivers_and_degenerate_triangles() {
        let p = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.5, 3f64.sqrt() / 2.0, 0.0),
            Point3::new(0.5, 0.05, 0.0),
            Point3::new(0.5, 0.0, 0.0),
        ];
        let s = triangle_shape(&mesh(p, vec![[0, 1, 2], [0, 1, 3], [0, 4, 1]]));
        assert_eq!(s.slivers, 2);
        assert_eq!(s.degenerate, 1);
        assert_eq!(s.min_angle_deg, 0.0);
        let sliver = 0.1f64.atan().to_degrees();
        assert!((s.mean_min_angle_deg - (60.0 + sliver) / 3.0).abs() < 1e-9);
        let empty = triangle_shape(&mesh(vec![], vec![]));
        assert_eq!(
            (empty.min_angle_deg, empty.slivers, empty.degenerate),
            (0.0, 0, 0)
        );
    }
}
