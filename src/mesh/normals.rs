//! Vertex normals of a triangle mesh: the area-weighted mean of the incident faces' normals
//! (the sum of the unnormalized face cross products).

use super::Mesh;
use nalgebra::Vector3;

/// Unit vertex normals; a vertex with no (non-degenerate) face gets the zero vector.
pub fn vertex_normals(mesh: &Mesh) -> Vec<Vector3<f64>> {
    let mut n = vec![Vector3::zeros(); mesh.positions.len()];
    for (fi, f) in mesh.faces.iter().enumerate() {
        let c = mesh.face_cross(fi);
        if !c.iter().all(|x| x.is_finite()) {
            continue;
        }
        for &v in f {
            n[v as usize] += c;
        }
    }
    for x in &mut n {
        let l = x.norm();
        if l > 0.0 && l.is_finite() {
            *x /= l;
        } else {
            *x = Vector3::zeros();
        }
    }
    n
}
