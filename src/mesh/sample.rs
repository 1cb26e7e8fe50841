//! Extra sample points on the edges and faces of a coarse triangle mesh, so that a surface fitted
//! to points follows the triangles and not only their corners.
//!
//! Inputs: a mesh and a spacing `s`. Every edge longer than `s` gets `ceil(len / s) - 1` evenly
//! spaced interior points (once per edge, shared by its faces); every triangle whose longest
//! edge is longer than `s` gets the interior points of a barycentric grid with `ceil(longest /
//! s)` steps. Outputs: the new points and their normals, interpolated from the area-weighted
//! vertex normals (`mesh::normals::vertex_normals`) and normalized. Order is deterministic
//! (edges in first appearance, faces in index order).

use super::normals::vertex_normals;
use super::Mesh;
use crate::spatial::fast_hash::IntSet;
use nalgebra::{Point3, Vector3};

/// Upper bound on the number of added points (a safety net for huge triangles at a tiny
/// spacing).
pub const MAX_SAMPLES: usize = 20_000_000;

/// The extra points and normals (see the module docs). Faces with indices past the vertex list
/// are skipped.
pub fn sample_surface(mesh: &Mesh, spacing: f64) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
    let mut pts = Vec::new();
    let mut nrm = Vec::new();
    if spacing.is_nan() || spacing <= 0.0 || mesh.faces.is_empty() {
        return (pts, nrm);
    }
    let vn = vertex_normals(mesh);
    let nv = mesh.positions.len();
    let steps = |len: f64| -> usize {
        let k = (len / spacing).ceil();
        if k.is_finite() && k >= 2.0 {
            (k as usize).min(10_000)
        } else {
            1
        }
    };
    let mut push = |p: Point3<f64>, n: Vector3<f64>, pts: &mut Vec<Point3<f64>>| {
        if pts.len() < MAX_SAMPLES {
            pts.push(p);
            nrm.push(n.try_normalize(1e-300).unwrap_or_else(Vector3::zeros));
        }
    };
    let mut seen: IntSet<(u32, u32)> = IntSet::default();
    for f in &mesh.faces {
        if f.iter().any(|&v| v as usize >= nv) {
            continue;
        }
        let p = [
            mesh.positions[f[0] as usize],
            mesh.positions[f[1] as usize],
            mesh.positions[f[2] as usize],
        ];
        let n = [vn[f[0] as usize], vn[f[1] as usize], vn[f[2] as usize]];
        // Edges, once each.
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            let (pa, pb) = (p[k], p[(k + 1) % 3]);
            let m = steps((pb - pa).norm());
            for i in 1..m {
                let t = i as f64 / m as f64;
                push(
                    pa + (pb - pa) * t,
                    n[k] * (1.0 - t) + n[(k + 1) % 3] * t,
                    &mut pts,
                );
            }
        }
        // Interior of the face.
        let longest = (0..3)
            .map(|k| (p[(k + 1) % 3] - p[k]).norm())
            .fold(0.0, f64::max);
        let m = steps(longest);
        for i in 1..m {
            for j in 1..m - i {
                let (u, v) = (i as f64 / m as f64, j as f64 / m as f64);
                let w = 1.0 - u - v;
                let q = Point3::from(p[0].coords * w + p[1].coords * u + p[2].coords * v);
                push(q, n[0] * w + n[1] * u + n[2] * v, &mut pts);
            }
        }
    }
    (pts, nrm)
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
    fn samples_cover_edges_and_faces_once() {
        let (p, n) = sample_surface(&square(), 0.25);
        // 4 outer edges of length 1 -> 3 points each; the diagonal (1.41) -> 5 points; each face
        // (longest 1.41 -> 6 steps) -> 10 interior grid points.
        assert_eq!(p.len(), 4 * 3 + 5 + 2 * 10);
        assert!(n.iter().all(|v| (v - Vector3::z()).norm() < 1e-12));
        assert!(p.iter().all(|q| q.z == 0.0 && q.x >= 0.0 && q.x <= 1.0));
        let mut keys: Vec<(i64, i64)> = p
            .iter()
            .map(|q| ((q.x * 1e9) as i64, (q.y * 1e9) as i64))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), p.len(), "no duplicates");
        // Dense enough already: nothing added.
        assert!(sample_surface(&square(), 2.0).0.is_empty());
        assert!(sample_surface(&square(), 0.0).0.is_empty());
    }
}
