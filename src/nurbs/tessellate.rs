//! Tessellation of a patch network for pictures: each patch evaluated on an n x n grid of its
//! parameter rectangle and split into triangles (no vertices shared between patches: this is
//! for display, not for topology), plus each net edge's curve as a polyline.

use super::PatchNetwork;
use crate::mesh::Mesh;
use nalgebra::Point3;

/// Triangles of every patch (`n` intervals per direction, at least 1), oriented by the face's
/// `same_sense`, and the net edges as polylines of `n` segments.
pub fn tessellate(net: &PatchNetwork, n: usize) -> (Mesh, Vec<Vec<Point3<f64>>>) {
    let n = n.max(1);
    let mut mesh = Mesh::default();
    for f in &net.faces {
        let (u0, u1) = f.surface.domain_u();
        let (v0, v1) = f.surface.domain_v();
        let base = mesh.positions.len() as u32;
        for i in 0..=n {
            for j in 0..=n {
                let u = u0 + (u1 - u0) * i as f64 / n as f64;
                let v = v0 + (v1 - v0) * j as f64 / n as f64;
                mesh.positions.push(f.surface.evaluate(u, v));
            }
        }
        let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if f.same_sense {
                    mesh.faces.push([a, b, c]);
                    mesh.faces.push([a, c, d]);
                } else {
                    mesh.faces.push([a, c, b]);
                    mesh.faces.push([a, d, c]);
                }
            }
        }
    }
    let lines = net
        .edges
        .iter()
        .map(|e| {
            let (t0, t1) = e.curve.domain();
            (0..=n)
                .map(|k| e.curve.evaluate(t0 + (t1 - t0) * k as f64 / n as f64))
                .collect()
        })
        .collect();
    (mesh, lines)
}
