//! Circular-arc interpolation (seed 002 eq. 3-4 and section 3.5, after Karbacher & Häusler).
//!
//! **Arc offset (eq. 3).** A vertex V with unit normal n and a neighbour V_i with unit normal n_i:
//! the circle arc that leaves V_i tangent to the surface there (normal n_i) and arrives with
//! normal n does so over a chord perpendicular to the bisector m_i = (n + n_i)/|n + n_i| of the
//! two normals. Moving V along n by
//!
//! ```text
//! delta_i = (V_i - V) . m_i / (n . m_i)  =  d_i cos(beta_i - alpha_i/2) / cos(alpha_i/2)
//! ```
//!
//! puts it on that arc, with d_i = |V_i - V|, alpha_i the angle between n and n_i and beta_i the
//! angle between n and V_i - V: this is eq. 3 written without angles.
//!
//! **Midpoints (eq. 4).** The midpoint M of an edge V1 V2 gets the normal n_M = (n1 + n2)/|n1 + n2|;
//! the arc offsets from V1 and from V2 (the distances eps^(1), eps^(2) of eq. 4 between M and the
//! arc points) are averaged and M moves by that along n_M. Points on a sphere with radial
//! normals give points on the sphere exactly.
//!
//! **Smoothing (section 3.5).** Each free vertex moves along its normal by the weighted mean of
//! the arc offsets to its neighbours, weights w_i = d_0 / d_i with d_0 the nearest neighbour's
//! distance, so that near neighbours count more.

use super::patch::Patch;
use nalgebra::{Point3, Vector3};

/// The arc offset delta_i of eq. 3; `None` when the normals are (nearly) opposite.
pub fn arc_offset(
    v: &Point3<f64>,
    n: &Vector3<f64>,
    vi: &Point3<f64>,
    ni: &Vector3<f64>,
) -> Option<f64> {
    let m = n + ni;
    let ml = m.norm();
    if !(ml > 1e-6) {
        return None;
    }
    let m = m / ml;
    let c = n.dot(&m);
    if !(c > 1e-3) {
        return None;
    }
    let delta = (vi - v).dot(&m) / c;
    delta.is_finite().then_some(delta)
}

/// Unit vector, or `fallback` when `v` has no direction.
fn unit_or(v: Vector3<f64>, fallback: Vector3<f64>) -> Vector3<f64> {
    let l = v.norm();
    if l > 1e-12 && l.is_finite() {
        v / l
    } else {
        fallback
    }
}

/// The circular-arc midpoint of edge (p1, n1)-(p2, n2) and its normal (eq. 3-4). The offset is
/// limited to the sagitta (c/2) tan(alpha/4) of the circle arc whose end normals differ by the
/// angle alpha between n1 and n2 (exactly the offset on a sphere): where the normals disagree
/// with the chord (noise, a crease), the midpoint does not shoot off.
pub fn arc_midpoint(
    p1: &Point3<f64>,
    n1: &Vector3<f64>,
    p2: &Point3<f64>,
    n2: &Vector3<f64>,
) -> (Point3<f64>, Vector3<f64>) {
    let m = nalgebra::center(p1, p2);
    let chord = (p2 - p1).norm();
    let nm = unit_or(n1 + n2, unit_or(*n1, Vector3::z()));
    let eps = match (arc_offset(&m, &nm, p1, n1), arc_offset(&m, &nm, p2, n2)) {
        (Some(a), Some(b)) => 0.5 * (a + b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => 0.0,
    };
    let alpha = n1
        .dot(n2)
        .clamp(-1.0, 1.0)
        .acos()
        .min(std::f64::consts::FRAC_PI_2);
    let limit = 0.5 * chord * (0.25 * alpha).tan() * (1.0 + 1e-9);
    let eps = eps.clamp(-limit, limit);
    (m + nm * eps, nm)
}

/// Circular-arc smoothing of the patch's free vertices (section 3.5), `iterations` Jacobi sweeps.
/// Normals stay as they are (they carry the ring's tangent planes into the fill). A move that
/// would turn one of the vertex's faces by more than 60 degrees (a fold in the making, where the
/// normals around the hole disagree) is not made.
pub fn arc_smooth(patch: &mut Patch, iterations: usize) {
    if iterations == 0 {
        return;
    }
    let nb = patch.neighbours();
    for _ in 0..iterations {
        let moved: Vec<Option<Point3<f64>>> = (0..patch.positions.len())
            .map(|v| {
                if patch.is_fixed(v as u32) || nb[v].is_empty() {
                    return None;
                }
                let (pv, nv) = (patch.positions[v], patch.normals[v]);
                let dists: Vec<f64> = nb[v]
                    .iter()
                    .map(|&u| (patch.positions[u as usize] - pv).norm())
                    .collect();
                let d0 = dists.iter().copied().fold(f64::INFINITY, f64::min);
                if !(d0 > 0.0) {
                    return None;
                }
                let (mut sum, mut wsum) = (0.0, 0.0);
                for (&u, &d) in nb[v].iter().zip(&dists) {
                    let u = u as usize;
                    if let Some(delta) =
                        arc_offset(&pv, &nv, &patch.positions[u], &patch.normals[u])
                    {
                        let w = d0 / d;
                        sum += w * delta.clamp(-d, d);
                        wsum += w;
                    }
                }
                (wsum > 0.0).then(|| pv + nv * (sum / wsum))
            })
            .collect();
        let before: Vec<Vector3<f64>> = patch.faces.iter().map(|f| patch.face_cross(f)).collect();
        let old = patch.positions.clone();
        for (v, p) in moved.iter().enumerate() {
            if let Some(p) = p {
                patch.positions[v] = *p;
            }
        }
        // Undo the moves around faces that turned too far, until none does.
        for _ in 0..8 {
            let mut undo: Vec<usize> = Vec::new();
            for (fi, f) in patch.faces.iter().enumerate() {
                let (a, b) = (before[fi], patch.face_cross(f));
                if !(a.dot(&b) > 0.5 * a.norm() * b.norm()) {
                    undo.extend(f.iter().map(|&v| v as usize));
                }
            }
            undo.retain(|&v| patch.positions[v] != old[v]);
            if undo.is_empty() {
                break;
            }
            for v in undo {
                patch.positions[v] = old[v];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_midpoints_are_exact() {
        let r = 2.0;
        let a = Vector3::new(1.0, 0.2, 0.3).normalize();
        let b = Vector3::new(0.1, 1.0, -0.4).normalize();
        let (m, n) = arc_midpoint(&Point3::from(a * r), &a, &Point3::from(b * r), &b);
        assert!((m.coords.norm() - r).abs() < 1e-12, "{}", m.coords.norm());
        assert!((n - (a + b).normalize()).norm() < 1e-12);
        // Concave side (inward normals): the midpoint bulges the other way, still on the sphere.
        let (m2, _) = arc_midpoint(&Point3::from(a * r), &-a, &Point3::from(b * r), &-b);
        assert!((m2.coords.norm() - r).abs() < 1e-12);
        // Plane: no offset.
        let (m3, _) = arc_midpoint(
            &Point3::new(0.0, 0.0, 0.0),
            &Vector3::z(),
            &Point3::new(1.0, 0.0, 0.0),
            &Vector3::z(),
        );
        assert!(m3.z.abs() < 1e-15);
        // Opposite normals: plain midpoint, no NaN.
        let (m4, n4) = arc_midpoint(
            &Point3::new(0.0, 0.0, 0.0),
            &Vector3::z(),
            &Point3::new(1.0, 0.0, 0.0),
            &-Vector3::z(),
        );
        assert!(m4.coords.iter().all(|c| c.is_finite()) && (n4.norm() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn offset_matches_the_angle_form_of_eq3() {
        // 2D check in the x-z plane: delta = d cos(beta - alpha/2) / cos(alpha/2).
        let v = Point3::new(0.0, 0.0, 0.0);
        let n = Vector3::z();
        let alpha: f64 = 0.4;
        let ni = Vector3::new(alpha.sin(), 0.0, alpha.cos());
        let (d, beta): (f64, f64) = (0.7, 1.9);
        let vi = v + Vector3::new(beta.sin(), 0.0, beta.cos()) * d;
        let delta = arc_offset(&v, &n, &vi, &ni).unwrap();
        let want = d * (beta - alpha / 2.0).cos() / (alpha / 2.0).cos();
        assert!((delta - want).abs() < 1e-12, "{delta} vs {want}");
    }
}
