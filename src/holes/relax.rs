//! Area-weighted centroid relaxation with re-projection (seed 000 eq. 13).
//!
//! Each free vertex moves to `P = sum A_i C_i / sum A_i` over its incident triangles (areas A_i,
//! centroids C_i), then back onto the surface along the surface normal (seed 000 eq. 8-12 with
//! the gradient direction). This evens out the triangles that projecting a planar mesh along one
//! direction stretches where the surface is steep, without losing accuracy.

use super::newton_project::project_gradient;
use super::patch::Patch;
use crate::implicit::Implicit;
use nalgebra::{Point3, Vector3};

/// `iterations` Jacobi sweeps of eq. 13 over the patch's free vertices. A vertex whose
/// re-projection fails (no surface within `max_dist`) stays where it was. Returns the number of
/// such failures in the last sweep.
pub fn relax_on_surface(
    patch: &mut Patch,
    surface: &dyn Implicit,
    iterations: usize,
    max_dist: f64,
    tol: f64,
) -> usize {
    let vf = patch.vertex_faces();
    let mut failures = 0;
    for _ in 0..iterations {
        failures = 0;
        let targets: Vec<Option<Point3<f64>>> = (0..patch.positions.len())
            .map(|v| {
                if patch.is_fixed(v as u32) || vf[v].is_empty() {
                    return None;
                }
                let mut acc = Vector3::zeros();
                let mut wsum = 0.0;
                for &f in &vf[v] {
                    let t = patch.faces[f as usize];
                    let a = 0.5 * patch.face_cross(&t).norm();
                    let c = (patch.positions[t[0] as usize].coords
                        + patch.positions[t[1] as usize].coords
                        + patch.positions[t[2] as usize].coords)
                        / 3.0;
                    acc += c * a;
                    wsum += a;
                }
                (wsum > 0.0).then(|| Point3::from(acc / wsum))
            })
            .collect();
        for (v, t) in targets.into_iter().enumerate() {
            let Some(t) = t else { continue };
            match project_gradient(surface, &t, max_dist, tol) {
                Some(p) => patch.positions[v] = p,
                None => failures += 1,
            }
        }
    }
    failures
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Plane;
    impl Implicit for Plane {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.z
        }
        fn gradient(&self, _: &Point3<f64>) -> Vector3<f64> {
            Vector3::z()
        }
    }

    #[test]
    fn off_centre_vertex_moves_to_the_middle() {
        let ring = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        let mut p = Patch::from_ring(
            ring,
            vec![Vector3::z(); 4],
            vec![0, 1, 2, 3],
            Default::default(),
        );
        p.add_vertex(Point3::new(0.9, 0.8, 0.3), Vector3::z());
        p.faces = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        let fails = relax_on_surface(&mut p, &Plane, 30, 1.0, 1e-12);
        assert_eq!(fails, 0);
        let c = p.positions[4];
        assert!((c - Point3::new(0.5, 0.5, 0.0)).norm() < 1e-3, "{c:?}");
    }
}
