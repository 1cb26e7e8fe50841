//! Vertex normals around a hole from a local quadric fit.
//!
//! Both fills lean on the normals of the vertices around the hole (seed 000 offsets its
//! off-surface points along them, seed 002 bends its circular arcs with them), and the usual
//! face-averaged normals are worst exactly there: at a border vertex all faces lie on one side,
//! so the average leans away from the hole by about half the angle between neighbouring faces,
//! and on scans they carry the noise of single triangles. Here each vertex's normal comes from
//! the least-squares quadric height field w = a u^2 + b uv + c v^2 + d u + e v + f over the
//! vertices within two face-rings, in the frame of its face-averaged normal; the normal is that
//! of the quadric at the vertex (exact to second order on smooth surfaces, one-sided or not).
//! Where too few neighbours make the fit ill-posed, the face-averaged normal stays.

use super::neighbourhood::{ring_vertices, VertexFaces};
use crate::mesh::Mesh;
use nalgebra::{DMatrix, DVector, Vector3};

/// Fitted normals of `vertices` (same order). `base` are the face-averaged vertex normals, which
/// orient the result and serve as its fallback.
pub fn fitted_normals(
    mesh: &Mesh,
    vf: &VertexFaces,
    base: &[Vector3<f64>],
    vertices: &[u32],
) -> Vec<Vector3<f64>> {
    vertices
        .iter()
        .map(|&v| fit_one(mesh, vf, base, v).unwrap_or(base[v as usize]))
        .collect()
}

fn fit_one(mesh: &Mesh, vf: &VertexFaces, base: &[Vector3<f64>], v: u32) -> Option<Vector3<f64>> {
    let n0 = base[v as usize];
    if !(n0.norm() > 0.5) {
        return None;
    }
    let nb = ring_vertices(mesh, vf, &[v], 2);
    if nb.len() < 9 {
        return None;
    }
    let a = if n0.x.abs() < 0.6 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (a - n0 * n0.dot(&a)).normalize();
    let e2 = n0.cross(&e1);
    let o = mesh.positions[v as usize];
    let scale = nb
        .iter()
        .map(|&u| (mesh.positions[u as usize] - o).norm())
        .fold(0.0, f64::max);
    if !(scale > 0.0) {
        return None;
    }
    let rows = nb.len();
    let mut m = DMatrix::<f64>::zeros(rows, 6);
    let mut rhs = DVector::<f64>::zeros(rows);
    for (r, &u) in nb.iter().enumerate() {
        let d = (mesh.positions[u as usize] - o) / scale;
        let (x, y, w) = (d.dot(&e1), d.dot(&e2), d.dot(&n0));
        m[(r, 0)] = x * x;
        m[(r, 1)] = x * y;
        m[(r, 2)] = y * y;
        m[(r, 3)] = x;
        m[(r, 4)] = y;
        m[(r, 5)] = 1.0;
        rhs[r] = w;
    }
    let svd = m.svd(true, true);
    let s = &svd.singular_values;
    let (smax, smin) = (s.max(), s.min());
    if !(smin > 1e-6 * smax) {
        return None;
    }
    let c = svd.solve(&rhs, 1e-12).ok()?;
    let n = n0 - e1 * c[3] - e2 * c[4];
    let l = n.norm();
    // A fit that turns the normal by more than 60 degrees is not trusted.
    (l.is_finite() && l > 0.0 && n.dot(&n0) / l > 0.5).then(|| n / l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::holes::cut::cut_ball;
    use crate::holes::testing::cube_sphere;
    use nalgebra::Point3;

    #[test]
    fn border_normals_on_a_sphere_are_radial() {
        let s = cube_sphere(24, 1.0);
        let cut = cut_ball(&s, &Point3::new(0.0, 0.0, 1.0), 0.4);
        let t = cut.topology();
        let ring = &t.loops[0].vertices;
        let base = crate::mesh::normals::vertex_normals(&cut);
        let vf = VertexFaces::build(&cut);
        let fitted = fitted_normals(&cut, &vf, &base, ring);
        let err = |n: &Vector3<f64>, v: u32| {
            n.dot(&cut.positions[v as usize].coords.normalize())
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        };
        let worst_base = ring
            .iter()
            .map(|&v| err(&base[v as usize], v))
            .fold(0.0, f64::max);
        let worst_fit = ring
            .iter()
            .zip(&fitted)
            .map(|(&v, n)| err(n, v))
            .fold(0.0, f64::max);
        assert!(worst_fit < 0.1, "fitted {worst_fit} degrees off");
        assert!(worst_fit < 0.2 * worst_base, "{worst_fit} vs {worst_base}");
    }
}
