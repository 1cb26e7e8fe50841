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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smooth::testing::*;

    struct UnitSphere;
    impl Implicit for UnitSphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - 1.0
        }
    }

    /// Smallest angle of any triangle, in degrees.
    fn min_angle(m: &Mesh) -> f64 {
        let mut best = 180.0f64;
        for f in &m.faces {
            for k in 0..3 {
                let a = m.positions[f[k] as usize];
                let b = m.positions[f[(k + 1) % 3] as usize];
                let c = m.positions[f[(k + 2) % 3] as usize];
                best = best.min((b - a).angle(&(c - a)).to_degrees());
            }
        }
        best
    }

    /// A unit sphere whose vertices were pushed around tangentially (bad triangles, same shape).
    fn jittered_sphere() -> Mesh {
        let mut m = sphere(3);
        let mut g = Noise::new(2);
        let h = m.mean_edge_length();
        for p in m.positions.iter_mut() {
            let n = p.coords;
            let t = Vector3::new(g.gauss(), g.gauss(), g.gauss()) * (0.25 * h);
            *p = Point3::from((n + (t - n * t.dot(&n))).normalize());
        }
        m
    }

    #[test]
    fn relaxation_on_an_implicit_improves_triangles_and_stays_on_it() {
        let mut m = jittered_sphere();
        let before = min_angle(&m);
        let adj = Adjacency::build(&m).unwrap();
        let rep = centroid(
            &mut m,
            &adj,
            &CentroidParams::default(),
            Some(&UnitSphere),
            &Control::default(),
        )
        .unwrap();
        let after = min_angle(&m);
        assert!(after > before + 5.0, "min angle {before} -> {after}");
        let off = m
            .positions
            .iter()
            .map(|p| (p.coords.norm() - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(off < 1e-9, "off the sphere by {off}");
        assert!(rep.mean_displacement > 0.0);
    }

    #[test]
    fn tangential_relaxation_keeps_the_shape() {
        let mut m = jittered_sphere();
        let v0 = m.signed_volume();
        let before = min_angle(&m);
        let adj = Adjacency::build(&m).unwrap();
        let p = CentroidParams {
            iterations: 20,
            ..Default::default()
        };
        centroid(&mut m, &adj, &p, None, &Control::default()).unwrap();
        assert!(min_angle(&m) > before + 5.0);
        let v = m.signed_volume();
        assert!(((v - v0) / v0).abs() < 0.01, "volume {v0} -> {v}");
        // A plane stays exactly a plane.
        let mut pl = plane(8);
        let mut g = Noise::new(6);
        for p in pl.positions.iter_mut() {
            if p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0 {
                p.x += 0.03 * g.gauss();
                p.y += 0.03 * g.gauss();
            }
        }
        let adj = Adjacency::build(&pl).unwrap();
        centroid(&mut pl, &adj, &p, None, &Control::default()).unwrap();
        assert!(pl.positions.iter().all(|p| p.z == 0.0));
    }

    #[test]
    fn degenerate_input_gives_finite_positions() {
        let mut m = degenerate();
        for fix_boundary in [true, false] {
            let p = CentroidParams {
                fix_boundary,
                ..Default::default()
            };
            let adj = Adjacency::build(&m).unwrap();
            centroid(&mut m, &adj, &p, None, &Control::default()).unwrap();
            assert!(all_finite(&m));
            centroid(&mut m, &adj, &p, Some(&UnitSphere), &Control::default()).unwrap();
            assert!(all_finite(&m), "{:?}", m.positions);
        }
    }
}
