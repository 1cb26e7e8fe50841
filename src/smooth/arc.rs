//! Circular-arc smoothing (seed 002 section 3.5, after Karbacher & Hausler).
//!
//! A smooth surface between two nearby points is taken to be a circular arc: the chord from V to
//! a neighbour V_i meets the tangent planes at both ends at half the angle alpha_i between their
//! normals. With d_i = |V_i - V| and beta_i the angle between V's normal n and the chord, the
//! distance along n by which V must move to satisfy this arc rule is (seed 002 eq. 3)
//!
//!   delta_i = d_i cos(beta_i - alpha_i / 2) / cos(alpha_i / 2)
//!           = (V_i - V).n + |(V_i - V)_t| tan(alpha_i / 2),
//!
//! alpha_i signed positive where the normals diverge (convex), measured in the plane of n and the
//! chord's tangential part t. Each vertex moves along n by the weighted mean
//! Delta_n = sum w_i delta_i / sum w_i with w_i = d_0 / d_i, d_0 the nearest neighbour's distance
//! (nearer neighbours count more, seed 002 Fig. 9), and the whole is iterated with normals
//! recomputed each time. On a sphere the rule is exact (delta = 0), so the pass does not shrink.
//!
//! All vertices move at once (Jacobi), so a full step would leave the highest-frequency noise
//! oscillating; the default moves half of Delta_n per iteration, and each delta_i is clamped to
//! [-d_i, d_i]. Boundary and non-manifold
//! vertices stay put by default. Neighbours whose normal is turned by more than
//! [`ArcParams::max_normal_angle_deg`] (a crease) do not vote.

use super::common::{
    check_finite, displacement_stats, face_crosses, mean_edge_length, movable, vertex_normals,
    Control, SmoothReport,
};
use crate::error::{Error, Result};
use crate::mesh::adjacency::Adjacency;
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::time::Instant;

/// Parameters of [`arc`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ArcParams {
    /// Iterations (default 10).
    pub iterations: usize,
    /// Fraction of Delta_n applied per iteration, in (0, 1] (default 0.5).
    pub step: f64,
    /// Neighbours whose normal differs by more than this many degrees are ignored (default 90).
    pub max_normal_angle_deg: f64,
    /// Keep boundary and non-manifold vertices fixed (default true).
    pub fix_boundary: bool,
}

impl Default for ArcParams {
    fn default() -> Self {
        ArcParams {
            iterations: 10,
            step: 0.5,
            max_normal_angle_deg: 90.0,
            fix_boundary: true,
        }
    }
}

/// Arc-rule error delta_i of eq. 3 for vertex `p` with unit normal `n` and neighbour `q` with unit
/// normal `nq`; `None` when undefined (coincident points, chord along the normal, opposite
/// normals).
fn arc_error(
    p: &Point3<f64>,
    n: &Vector3<f64>,
    q: &Point3<f64>,
    nq: &Vector3<f64>,
    min_cos: f64,
) -> Option<(f64, f64)> {
    let chord = q - p;
    let d = chord.norm();
    if d <= 0.0 || !d.is_finite() || nq.norm_squared() == 0.0 {
        return None;
    }
    let cn = chord.dot(n);
    let tv = chord - n * cn;
    let ct = tv.norm();
    if ct <= 1e-9 * d {
        return None;
    }
    let t = tv / ct;
    // alpha in the (t, n) plane: (sin, cos) up to a common positive factor.
    let (s, c) = (nq.dot(&t), nq.dot(n));
    let h = (s * s + c * c).sqrt();
    if h <= 0.0 || nq.dot(n) < min_cos {
        return None;
    }
    let (s, c) = (s / h, c / h);
    // tan(alpha / 2) = sin alpha / (1 + cos alpha).
    if 1.0 + c < 1e-6 {
        return None;
    }
    // Clamped to the neighbour's distance: a larger move means the arc model does not hold
    // (normals too far apart for the spacing), and the clamp keeps the pass stable there.
    Some(((cn + ct * s / (1.0 + c)).clamp(-d, d), d))
}

/// Smooths `mesh` in place by circular-arc smoothing (seed 002 section 3.5, eq. 3).
///
/// Errors: bad parameters, a non-finite coordinate, an adjacency of another mesh.
pub fn arc(
    mesh: &mut Mesh,
    adj: &Adjacency,
    params: &ArcParams,
    control: &Control,
) -> Result<SmoothReport> {
    let start = Instant::now();
    check_finite(mesh, adj)?;
    if !(params.step > 0.0 && params.step <= 1.0) {
        return Err(Error::InvalidOption(format!(
            "arc smoothing: step must be in (0, 1], got {}",
            params.step
        )));
    }
    if !(params.max_normal_angle_deg.is_finite() && params.max_normal_angle_deg > 0.0) {
        return Err(Error::InvalidOption(format!(
            "arc smoothing: max_normal_angle_deg must be > 0, got {}",
            params.max_normal_angle_deg
        )));
    }
    let min_cos = params.max_normal_angle_deg.min(180.0).to_radians().cos();
    let l = mean_edge_length(&mesh.positions, adj);
    let mov = movable(adj, control.region, params.fix_boundary);
    let initial = mesh.positions.clone();
    let (mut crosses, mut normals, mut next) = (Vec::new(), Vec::new(), Vec::new());
    for it in 0..params.iterations {
        let pos = &mesh.positions;
        face_crosses(pos, &mesh.faces, &mut crosses);
        vertex_normals(adj, &crosses, &mut normals);
        (0..pos.len())
            .into_par_iter()
            .map(|v| {
                let p = pos[v];
                let n = normals[v];
                if !mov[v] || n.norm_squared() == 0.0 {
                    return p;
                }
                // (delta_i, d_i) per neighbour; weights d_0 / d_i.
                let mut d0 = f64::INFINITY;
                let mut sum_w = 0.0;
                let mut sum_wd = 0.0;
                for &u in adj.neighbors_of(v) {
                    if let Some((delta, d)) =
                        arc_error(&p, &n, &pos[u as usize], &normals[u as usize], min_cos)
                    {
                        d0 = d0.min(d);
                        sum_w += 1.0 / d;
                        sum_wd += delta / d;
                    }
                }
                // sum (d0/d_i) delta_i / sum (d0/d_i): d0 cancels.
                if sum_w <= 0.0 || !d0.is_finite() {
                    return p;
                }
                let q = p + n * (params.step * sum_wd / sum_w);
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
        method: "arc",
        iterations: params.iterations,
        movable_vertices: n,
        mean_displacement: mean,
        max_displacement: max,
        mean_edge_length: l,
        seconds: start.elapsed().as_secs_f64(),
        parameters: serde_json::to_value(params).unwrap_or(serde_json::Value::Null),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smooth::testing::*;

    fn run(m: &mut Mesh, p: &ArcParams) -> SmoothReport {
        let adj = Adjacency::build(m).unwrap();
        arc(m, &adj, p, &Control::default()).unwrap()
    }

    #[test]
    fn arc_rule_is_exact_on_a_circle() {
        // Two points on the unit circle 30 degrees apart with their radial normals: delta = 0.
        let (a, b) = (0.0f64, 30f64.to_radians());
        let p = Point3::new(a.cos(), a.sin(), 0.0);
        let q = Point3::new(b.cos(), b.sin(), 0.0);
        let (np, nq) = (p.coords, q.coords);
        let (delta, d) = arc_error(&p, &np, &q, &nq, -1.0).unwrap();
        assert!(delta.abs() < 1e-12 && (d - 2.0 * 15f64.to_radians().sin()).abs() < 1e-12);
        // Moved outwards by 0.01 along its normal, p is told to come back by 0.01 (to first order).
        let p2 = p + np * 0.01;
        let (delta, _) = arc_error(&p2, &np, &q, &nq, -1.0).unwrap();
        assert!((delta + 0.01).abs() < 1e-3, "{delta}");
    }

    #[test]
    fn noisy_plane_becomes_flat() {
        let n = 30;
        let mut m = plane(n);
        let h = 1.0 / n as f64;
        let mut g = Noise::new(4);
        for p in m.positions.iter_mut() {
            if p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0 {
                p.z = 0.3 * h * g.gauss();
            }
        }
        let before = mean_normal_error(&m, &Vector3::z());
        run(&mut m, &ArcParams::default());
        let after = mean_normal_error(&m, &Vector3::z());
        assert!(
            after < 0.3 * before && after < 6.0,
            "normal error {before} -> {after} deg"
        );
        let mut m2 = m.clone();
        run(
            &mut m2,
            &ArcParams {
                iterations: 100,
                ..Default::default()
            },
        );
        let longer = mean_normal_error(&m2, &Vector3::z());
        assert!(longer < 1.5, "after 110 iterations {longer} deg");
    }

    #[test]
    fn noisy_sphere_keeps_its_volume_and_roundness() {
        let clean = sphere(4);
        let v0 = clean.signed_volume();
        let mut m = clean.clone();
        let h = m.mean_edge_length();
        add_normal_noise(&mut m, 0.3 * h, 11);
        let radial = |m: &Mesh| {
            let r: Vec<f64> = m.positions.iter().map(|p| p.coords.norm()).collect();
            let mean = r.iter().sum::<f64>() / r.len() as f64;
            (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / r.len() as f64).sqrt()
        };
        let spread0 = radial(&m);
        run(
            &mut m,
            &ArcParams {
                iterations: 20,
                ..Default::default()
            },
        );
        let v = m.signed_volume();
        assert!(((v - v0) / v0).abs() < 0.01, "volume {v0} -> {v}");
        assert!(
            radial(&m) < 0.3 * spread0,
            "radius spread {spread0} -> {}",
            radial(&m)
        );
    }

    #[test]
    fn degenerate_input_gives_finite_positions() {
        let mut m = degenerate();
        for fix_boundary in [true, false] {
            let p = ArcParams {
                fix_boundary,
                ..Default::default()
            };
            run(&mut m, &p);
            assert!(all_finite(&m), "{:?}", m.positions);
        }
        let mut m = plane(2);
        let adj = Adjacency::build(&m).unwrap();
        let p = ArcParams {
            step: 0.0,
            ..Default::default()
        };
        assert!(arc(&mut m, &adj, &p, &Control::default()).is_err());
    }
}
