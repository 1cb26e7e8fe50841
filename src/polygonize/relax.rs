//! Area-weighted centroid relaxation with re-projection (seed 003 eq. 9, seed 000 eq. 13).
//!
//! Each vertex moves to the area-weighted mean of the centroids of its incident triangles,
//! `P = sum_i A_i C_i / sum_i A_i`, and is then projected back onto the implicit's zero set along
//! the gradient. All vertices move at once (Jacobi order, in parallel): the result does not
//! depend on the thread count. A vertex whose projection fails keeps its previous position.

use crate::implicit::project::{project, ProjectOptions};
use crate::implicit::Implicit;
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Vertex -> incident faces, as compressed rows.
pub(crate) struct VertexFaces {
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl VertexFaces {
    pub(crate) fn build(mesh: &Mesh) -> VertexFaces {
        let nv = mesh.positions.len();
        let mut start = vec![0u32; nv + 1];
        for f in &mesh.faces {
            for &v in f {
                start[v as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut faces = vec![0u32; start[nv] as usize];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                faces[fill[v as usize] as usize] = fi as u32;
                fill[v as usize] += 1;
            }
        }
        VertexFaces { start, faces }
    }
    pub(crate) fn of(&self, v: usize) -> &[u32] {
        &self.faces[self.start[v] as usize..self.start[v + 1] as usize]
    }
}

/// Runs `iterations` rounds of relaxation and projection; returns the number of failed
/// projections (summed over rounds).
pub fn relax<F: Implicit + ?Sized>(
    mesh: &mut Mesh,
    f: &F,
    iterations: usize,
    opts: &ProjectOptions,
) -> usize {
    if mesh.faces.is_empty() || iterations == 0 {
        return 0;
    }
    let vf = VertexFaces::build(mesh);
    let mut failed = 0;
    for _ in 0..iterations {
        let pos = &mesh.positions;
        let faces = &mesh.faces;
        let (next, fails): (Vec<Point3<f64>>, Vec<bool>) = (0..pos.len())
            .into_par_iter()
            .map(|v| {
                let mut acc = Vector3::zeros();
                let mut area = 0.0;
                for &fi in vf.of(v) {
                    let [a, b, c] = faces[fi as usize];
                    let (pa, pb, pc) = (pos[a as usize], pos[b as usize], pos[c as usize]);
                    let ar = 0.5 * (pb - pa).cross(&(pc - pa)).norm();
                    acc += (pa.coords + pb.coords + pc.coords) * (ar / 3.0);
                    area += ar;
                }
                if area.is_nan() || area <= 0.0 {
                    return (pos[v], false);
                }
                let target = Point3::from(acc / area);
                match project(f, &target, opts) {
                    Ok((p, _)) => (p, false),
                    Err(_) => (pos[v], true),
                }
            })
            .unzip();
        failed += fails.iter().filter(|x| **x).count();
        mesh.positions = next;
    }
    failed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Aabb;
    use crate::polygonize::marching_cubes;

    struct Sphere;
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - 0.8
        }
        fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
            x.coords.normalize()
        }
    }

    fn min_angle(m: &Mesh) -> f64 {
        let mut worst = f64::MAX;
        for f in &m.faces {
            for k in 0..3 {
                let a = m.positions[f[k] as usize];
                let b = m.positions[f[(k + 1) % 3] as usize];
                let c = m.positions[f[(k + 2) % 3] as usize];
                let ang = (b - a).angle(&(c - a));
                worst = worst.min(ang);
            }
        }
        worst
    }

    #[test]
    fn relaxation_keeps_vertices_on_surface_and_improves_shape() {
        let dom = Aabb {
            min: Point3::new(-1.0, -1.0, -1.0),
            max: Point3::new(1.0, 1.0, 1.0),
        };
        let mut m = marching_cubes(&Sphere, &[Point3::new(0.8, 0.01, 0.02)], &dom, 0.1).unwrap();
        let mean_angle_quality = |m: &Mesh| {
            m.faces
                .iter()
                .map(|f| {
                    let p: Vec<_> = f.iter().map(|&v| m.positions[v as usize]).collect();
                    let a = (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
                    let l2 = (p[1] - p[0]).norm_squared()
                        + (p[2] - p[1]).norm_squared()
                        + (p[0] - p[2]).norm_squared();
                    2.0 * 3f64.sqrt() * a / l2
                })
                .sum::<f64>()
                / m.faces.len() as f64
        };
        let q0 = mean_angle_quality(&m);
        let a0 = min_angle(&m);
        let fails = relax(&mut m, &Sphere, 3, &ProjectOptions::for_diagonal(2.0));
        assert_eq!(fails, 0);
        for p in &m.positions {
            assert!((p.coords.norm() - 0.8).abs() < 1e-6);
        }
        let q1 = mean_angle_quality(&m);
        assert!(q1 > q0, "{q0} -> {q1}");
        assert!(min_angle(&m) >= a0 * 0.99);
    }
}
