//! Area-weighted centroid relaxation (seed 003 eq. 9; seed 000 eq. 13).
//!
//! Each vertex moves towards P = sum A_i C_i / sum A_i over its faces (A_i area, C_i centroid),
//! which evens out triangle sizes and shapes. Without a surface to stay on, only the part of
//! P - V tangent to the surface (perpendicular to the vertex normal) is applied, so the shape is
//! kept to first order. When an implicit surface f = 0 is given (the one the mesh was extracted
//! from), the vertex moves to P and is projected back with Newton steps along the gradient,
//! x <- x - f(x) grad f(x) / |grad f(x)|^2, as seed 003 does after marching cubes.
//!
//! Not feature preserving: run it on meshes from an implicit, or on a region (a hole fill).

use super::common::{
    check_finite, displacement_stats, face_crosses, mean_edge_length, movable, vertex_normals,
    Control, SmoothReport,
};
use crate::error::{Error, Result};
use crate::implicit::Implicit;
use crate::mesh::adjacency::Adjacency;
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::time::Instant;

/// Parameters of [`centroid`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CentroidParams {
    /// Iterations (default 5).
    pub iterations: usize,
    /// Fraction of the move to P per iteration, in (0, 1] (default 1: eq. 9 moves to P).
    pub step: f64,
    /// Newton steps of the projection onto the implicit (default 5).
    pub newton_steps: usize,
    /// Keep boundary and non-manifold vertices fixed (default true).
    pub fix_boundary: bool,
}

impl Default for CentroidParams {
    fn default() -> Self {
        CentroidParams {
            iterations: 5,
            step: 1.0,
            newton_steps: 5,
            fix_boundary: true,
        }
    }
}

/// Projects `x` onto f = 0 by Newton steps along the gradient; `None` when the gradient vanishes
/// or the iteration leaves `reach` of the start.
fn project(
    f: &dyn Implicit,
    x: Point3<f64>,
    steps: usize,
    tol: f64,
    reach: f64,
) -> Option<Point3<f64>> {
    let mut y = x;
    for _ in 0..steps {
        let (v, g) = f.value_and_gradient(&y);
        let g2 = g.norm_squared();
        if !(v.is_finite() && g2 > 0.0 && g2.is_finite()) {
            return None;
        }
        if v.abs() <= tol * g2.sqrt() {
            break;
        }
        y -= g * (v / g2);
        if (y - x).norm() > reach {
            return None;
        }
    }
    y.iter().all(|c| c.is_finite()).then_some(y)
}

/// Relaxes `mesh` in place towards area-weighted centroids (seed 003 eq. 9), tangentially, or
/// with re-projection onto `surface` when one is given.
///
/// Errors: bad parameters, a non-finite coordinate, an adjacency of another mesh.
pub fn centroid(
    mesh: &mut Mesh,
    adj: &Adjacency,
    params: &CentroidParams,
    surface: Option<&dyn Implicit>,
    control: &Control,
) -> Result<SmoothReport> {
    let start = Instant::now();
    check_finite(mesh, adj)?;
    if !(params.step > 0.0 && params.step <= 1.0) {
        return Err(Error::InvalidOption(format!(
            "centroid relaxation: step must be in (0, 1], got {}",
            params.step
        )));
    }
    let l = mean_edge_length(&mesh.positions, adj);
    let mov = movable(adj, control.region, params.fix_boundary);
    let initial = mesh.positions.clone();
    let (mut crosses, mut normals, mut next) = (Vec::new(), Vec::new(), Vec::new());
    let tol = 1e-9 * l;
    for it in 0..params.iterations {
        let pos = &mesh.positions;
        face_crosses(pos, &mesh.faces, &mut crosses);
        if surface.is_none() {
            vertex_normals(adj, &crosses, &mut normals);
        }
        (0..pos.len())
            .into_par_iter()
            .map(|v| {
                let p = pos[v];
                if !mov[v] {
                    return p;
                }
                let mut sum_a = 0.0;
                let mut sum_ac = Vector3::zeros();
                for &f in adj.faces_of_vertex(v) {
                    let a = 0.5 * crosses[f as usize].norm();
                    let t = mesh.faces[f as usize];
                    let c = (pos[t[0] as usize].coords
                        + pos[t[1] as usize].coords
                        + pos[t[2] as usize].coords)
                        / 3.0;
                    sum_a += a;
                    sum_ac += c * a;
                }
                if sum_a.is_nan() || sum_a <= 0.0 {
                    return p;
                }
                let d = (sum_ac / sum_a - p.coords) * params.step;
                let tangential = |n: &Vector3<f64>| p + (d - n * d.dot(n));
                let q = match surface {
                    None => tangential(&normals[v]),
                    Some(f) => {
                        match project(f, p + d, params.newton_steps, tol, 4.0 * l.max(d.norm())) {
                            Some(q) => q,
                            // No usable gradient: fall back to the tangential move.
                            None => {
                                let g = f.gradient(&p);
                                let n = g.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
                                tangential(&n)
                            }
                        }
                    }
                };
                if q.iter().all(|x| x.is_finite()) {
                    q
                } else {
                    p
                }
            })
            .collect_into_vec(&mut next);
        std::mem::swap(&mut mesh.positions, &mut next);
        if let Some(cb) = control.progress {
            cb(it + 1, params.iterations);
        }
    }
    let (n, mean, max) = displacement_stats(&initial, &mesh.positions, &mov);
    Ok(SmoothReport {
        method: "centroid",
        iterations: params.iterations,
        movable_vertices: n,
        mean_displacement: mean,
        max_displacement: max,
        mean_edge_length: l,
        seconds: start.elapsed().as_secs_f64(),
        parameters: serde_json::json!({
            "iterations": params.iterations,
            "step": params.step,
            "newton_steps": params.newton_steps,
            "fix_boundary": params.fix_boundary,
            "implicit": surface.is_some(),
        }),
    })
}
