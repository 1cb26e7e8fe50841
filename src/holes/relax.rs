//! Area-weighted centroid relaxation with re-projection (seed 000 eq. 13).
//!
//! Each free vertex moves to `P = sum A_i C_i / sum A_i` over its incident triangles (areas A_i,
//! centroids C_i), then back onto the surface along the surface normal (seed 000 eq. 8-12 with
//! the gradient direction). This evens out the triangles that projecting a planar mesh along one
//! direction stretches where the surface is steep, without losing accuracy.
//!
//! The re-projection of the intermediate sweeps is a single Newton step (the centroid is already
//! close to the surface, and the next sweep moves the vertex again); the last sweep converges
//! and leaves each moved vertex's normal set to the surface's.

use super::patch::Patch;
use crate::implicit::project::project_gradient_with_normal;
use crate::implicit::Implicit;
use nalgebra::{Point3, Vector3};

/// `iterations` Jacobi sweeps of eq. 13 over the patch's free vertices. A vertex whose
/// re-projection fails (no surface within `max_dist`) stays where it was. Returns, per vertex,
/// whether the last sweep placed it on the surface (its normal is then the unit gradient).
pub fn relax_on_surface(
    patch: &mut Patch,
    surface: &dyn Implicit,
    iterations: usize,
    max_dist: f64,
    tol: f64,
) -> Vec<bool> {
    let vf = patch.vertex_faces();
    let mut settled = vec![false; patch.positions.len()];
    for sweep in 0..iterations {
        let last = sweep + 1 == iterations;
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
            if last {
                if let Some((p, g)) = project_gradient_with_normal(surface, &t, max_dist, tol) {
                    let gl = g.norm();
                    if gl > 0.0 && gl.is_finite() {
                        patch.positions[v] = p;
                        patch.normals[v] = g / gl;
                        settled[v] = true;
                    }
                }
            } else {
                // One Newton step along the gradient.
                let (f, g) = surface.value_and_gradient(&t);
                let g2 = g.norm_squared();
                if g2 > 0.0 && f.is_finite() {
                    let p = t - g * (f / g2);
                    if (p - t).norm() <= max_dist && p.iter().all(|c| c.is_finite()) {
                        patch.positions[v] = p;
                    }
                }
            }
        }
    }
    settled
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
        let settled = relax_on_surface(&mut p, &Plane, 30, 1.0, 1e-12);
        assert!(settled[4] && !settled[0]);
        assert_eq!(p.normals[4], Vector3::z());
        let c = p.positions[4];
        assert!((c - Point3::new(0.5, 0.5, 0.0)).norm() < 1e-3, "{c:?}");
    }
}
