//! Anisotropic, feature-preserving mean-curvature flow (seed 000 section 3, eq. 14-20, after
//! Hildebrandt & Polthier 2004, "Anisotropic filtering of non-linear surface features").
//!
//! Per interior edge e with dihedral angle theta_e and faces of unit normals N1, N2:
//! - mean curvature magnitude H_e = 2 |e| cos(theta_e / 2) (eq. 14),
//! - edge normal N_e = (N1 + N2) / |N1 + N2| (eq. 15),
//! - weight W_lambda(H_e) = 1 for |H_e| < lambda, lambda^2 / (r (lambda - |H_e|)^2 + lambda^2)
//!   above (eq. 19-20): edges that bend much (features) are kept out of the flow,
//! - `Delta[V]` -= W_lambda(H_e) H_e N_e at both endpoints V_i, V_j (eq. 16-17),
//!
//! then every vertex moves V += 3 s / (2 `AREA[V]`) `Delta[V]` (eq. 18), `AREA[V]` the area of
//! its faces.
//!
//! H_e N_e is computed as |e| (u1 + u2), u_k the unit vector in face k perpendicular to e pointing
//! away from that face's third vertex: |u1 + u2| = 2 cos(theta_e / 2) and u1 + u2 is parallel to
//! N_e, with the sign of the bend (positive at convex edges, negative at concave ones), and it
//! needs no consistent face orientation. Summed over the edges at V, (1/2) sum H_e N_e is exactly
//! the area gradient at V, so with W = 1 the scheme is the explicit cotangent mean-curvature flow
//! with time step s.
//!
//! Additions to the seed, each needed for the defaults to work on noisy scans (measured in
//! docs/BENCHMARKS.md, "## smooth"):
//! - The weight's |H_e| is taken on face normals after two bilateral filter passes
//!   (`normal_filter.rs`): |H_e| = |e| |m1 - m2| = 2 |e| sin(angle(m1, m2) / 2), the same
//!   quantity as eq. 14 on a denoised normal field. On raw normals, noise of a third of an edge
//!   length bends edges as much as a feature does, so eq. 19-20 either freeze the noise or let
//!   the features melt (noisy fandisk with r = 10: 7.0 degrees mean normal error after 5
//!   iterations with the sharp edges' angles off by 25 degrees, 12 degrees and 57 after 15; with
//!   r = 1000: 5.7 degrees, edges off by 17; with the filtered normals: 2.8 degrees, 6.5). The motion itself (H_e N_e, eq. 16-18) stays on the real geometry.
//! - The step is capped per vertex (`STABILITY`) so that obtuse or sliver triangles cannot make
//!   the explicit step overshoot, flip faces or explode.
//! - The volume of closed, consistently oriented components is held at its initial value (the
//!   flow otherwise shrinks a sphere of radius R by about 2 s / R per iteration).
//! - Boundary and non-manifold vertices stay put (unless `fix_boundary` is false; boundary edges
//!   never contribute, so a free boundary does not curl inwards).
//!
//! The flow is not idempotent: past the default iterations, curved parts slowly round off and
//! flat parts move out to keep the volume (noisy fandisk: mean vertex distance 0.10 edge lengths
//! at 15 iterations, 0.14 at 30, 0.22 at 60). Organic meshes whose detail is at the scale of
//! the triangles lose some of it, as under any smoothing (see docs/BENCHMARKS.md); there
//! [`super::arc()`] keeps more.

use super::common::{
    check_finite, displacement_stats, mean_edge_length, movable, Control, SmoothReport,
    VolumeConstraint,
};
use super::normal_filter::{filter_normals, unpack, PackedNormal};
use crate::error::{Error, Result};
use crate::mesh::adjacency::Adjacency;
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::time::Instant;

/// Parameters of [`anisotropic`]. Lengths left `None` are scaled to the mesh's mean edge length
/// l (the defaults need no tuning by the user).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AnisotropicParams {
    /// Iterations (default 15).
    pub iterations: usize,
    /// Time step s of eq. 18, an area (default 0.2 l^2; see also the per-vertex cap).
    pub step: Option<f64>,
    /// Curvature threshold lambda of eq. 19-20, a length (default 0.2 l: an edge of mean length
    /// whose faces' filtered normals differ by about 11.5 degrees). 0 holds every edge still.
    pub lambda: Option<f64>,
    /// Fall-off r of eq. 20 (default 100): how fast the weight drops past lambda.
    pub r: f64,
    /// Bilateral passes over the face normals before the weight is taken (default 2; 0 takes
    /// H_e from the raw geometry as the seed does, which lets noise pass for features).
    pub guide_passes: usize,
    /// Range sigma of those passes, on |n1 - n2| (default 0.7).
    pub guide_sigma: f64,
    /// Hold the volume of every consistently oriented component, open ones with their holes
    /// capped (default true; see `VolumeConstraint` in `common.rs`).
    pub preserve_volume: bool,
    /// Keep boundary and non-manifold vertices fixed (default true).
    pub fix_boundary: bool,
}

impl Default for AnisotropicParams {
    fn default() -> Self {
        AnisotropicParams {
            iterations: 15,
            step: None,
            lambda: None,
            r: 100.0,
            guide_passes: 2,
            guide_sigma: 0.7,
            preserve_volume: true,
            fix_boundary: true,
        }
    }
}

/// The factor 3 s / (2 `AREA[V]`) of eq. 18 is capped at `STABILITY / sum of the stiffnesses` of
/// the edges at V (see [`edge_curvature`]): below 1 the explicit step cannot overshoot the
/// neighbours, so obtuse and sliver triangles cannot make it blow up or flip faces. On an
/// equilateral mesh the cap is 0.8 / 6.93 = 0.115, what the default step gives there.
const STABILITY: f64 = 0.8;

/// Weight of eq. 19-20.
fn weight(h: f64, lambda: f64, r: f64) -> f64 {
    let h = h.abs();
    if h < lambda {
        1.0
    } else {
        let d = lambda - h;
        lambda * lambda / (r * d * d + lambda * lambda)
    }
}

/// H_e N_e of eq. 14-15 for edge (a, b) with third vertices c1, c2 (see the module docs), and
/// the edge's stiffness |cot alpha1| + |cot alpha2| (alpha_k the angle at c_k): with W = 1 the
/// sum of H_e N_e at a vertex is sum_j (cot alpha_j + cot beta_j) (V - V_j), so the explicit step
/// is a convex combination of V and its neighbours while the factor of eq. 18 stays under
/// 1 / sum of the stiffnesses. A degenerate edge or face gives zero curvature and infinite
/// stiffness (its vertices hold still).
fn edge_curvature(
    a: &Point3<f64>,
    b: &Point3<f64>,
    c1: &Point3<f64>,
    c2: &Point3<f64>,
) -> (Vector3<f64>, f64) {
    let e = b - a;
    let len = e.norm();
    if len <= 0.0 || !len.is_finite() {
        return (Vector3::zeros(), f64::INFINITY);
    }
    let t = e / len;
    // Unit vector from c's side across the edge, and |cot| of the angle at c.
    let out = |c: &Point3<f64>| -> Option<(Vector3<f64>, f64)> {
        let (ca, cb) = (a - c, b - c);
        let w = ca - t * ca.dot(&t);
        let l = w.norm();
        // |ca x cb| = |e| l.
        (l > 1e-12 * len && l.is_finite()).then(|| (w / l, (ca.dot(&cb) / (len * l)).abs()))
    };
    match (out(c1), out(c2)) {
        (Some((u1, k1)), Some((u2, k2))) => ((u1 + u2) * len, k1 + k2),
        _ => (Vector3::zeros(), f64::INFINITY),
    }
}

/// The vertex of `f` that is neither `a` nor `b`.
fn third(f: &[u32; 3], a: u32, b: u32) -> Option<u32> {
    f.iter().copied().find(|&x| x != a && x != b)
}

/// Smooths `mesh` in place by anisotropic mean-curvature flow (seed 000 eq. 14-20).
///
/// Inputs: a triangle mesh, its [`Adjacency`], parameters, and [`Control`] (region, progress).
/// Errors: bad parameters, a non-finite coordinate, an adjacency of another mesh.
pub fn anisotropic(
    mesh: &mut Mesh,
    adj: &Adjacency,
    params: &AnisotropicParams,
    control: &Control,
) -> Result<SmoothReport> {
    let start = Instant::now();
    check_finite(mesh, adj)?;
    let l = mean_edge_length(&mesh.positions, adj);
    let step = params.step.unwrap_or(0.2 * l * l);
    let lambda = params.lambda.unwrap_or(0.2 * l);
    let r = params.r;
    let sigma = params.guide_sigma;
    let passes = params.guide_passes;
    for (name, v) in [
        ("step", step),
        ("lambda", lambda),
        ("r", r),
        ("guide_sigma", sigma),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::InvalidOption(format!(
                "anisotropic smoothing: {name} must be finite and >= 0, got {v}"
            )));
        }
    }
    let mov = movable(adj, control.region, params.fix_boundary);
    let volume = params
        .preserve_volume
        .then(|| VolumeConstraint::new(mesh, adj));
    let initial = mesh.positions.clone();
    let nf = mesh.faces.len();
    let mut normals: Vec<Vector3<f64>> = Vec::with_capacity(nf);
    let mut areas: Vec<f64> = Vec::with_capacity(nf);
    let mut guide: Vec<PackedNormal> = Vec::with_capacity(nf);
    let mut edge_vec: Vec<(Vector3<f64>, f64)> = Vec::with_capacity(adj.edges.len());
    let mut next: Vec<Point3<f64>> = Vec::with_capacity(mesh.positions.len());
    let mut grads: Vec<Vector3<f64>> = Vec::new();

    let ran = if l > 0.0 && lambda > 0.0 {
        params.iterations
    } else {
        0
    };
    for it in 0..ran {
        let pos = &mesh.positions;
        mesh.faces
            .par_iter()
            .map(|f| {
                let a = pos[f[0] as usize];
                let c = (pos[f[1] as usize] - a).cross(&(pos[f[2] as usize] - a));
                let len = c.norm();
                if len > 0.0 && len.is_finite() {
                    (c / len, 0.5 * len)
                } else {
                    (Vector3::zeros(), 0.0)
                }
            })
            .unzip_into_vecs(&mut normals, &mut areas);
        filter_normals(
            &mesh.faces,
            adj,
            &areas,
            &normals,
            sigma,
            passes,
            &mut guide,
        );
        // Per edge: W_lambda(H_e) H_e N_e (eq. 14-15, 19-20), the weight taken on the filtered
        // normals: H_e = |e| |m1 - m2| = 2 |e| sin(angle / 2).
        adj.edges
            .par_iter()
            .enumerate()
            .map(|(e, &[a, b])| {
                let fs = adj.faces_of_edge(e);
                if fs.len() != 2 {
                    // Boundary and non-manifold edges take no part.
                    return (Vector3::zeros(), 0.0);
                }
                let (f1, f2) = (fs[0] as usize, fs[1] as usize);
                let (Some(c1), Some(c2)) =
                    (third(&mesh.faces[f1], a, b), third(&mesh.faces[f2], a, b))
                else {
                    return (Vector3::zeros(), f64::INFINITY);
                };
                let (pa, pb) = (&pos[a as usize], &pos[b as usize]);
                let (hn, stiff) = edge_curvature(pa, pb, &pos[c1 as usize], &pos[c2 as usize]);
                let (m1, m2) = (unpack(&guide[f1]), unpack(&guide[f2]));
                let h = if m1.norm_squared() > 0.0 && m2.norm_squared() > 0.0 {
                    (m1 - m2).norm() * (pb - pa).norm()
                } else {
                    hn.norm()
                };
                (hn * weight(h, lambda, r), stiff)
            })
            .collect_into_vec(&mut edge_vec);
        // Per vertex: gather eq. 16-17, move by eq. 18; also the volume gradient (1/3) sum A n.
        (0..pos.len())
            .into_par_iter()
            .map(|v| {
                let p = pos[v];
                if !mov[v] {
                    return (p, Vector3::zeros());
                }
                let mut area = 0.0;
                let mut grad = Vector3::zeros();
                for &f in adj.faces_of_vertex(v) {
                    area += areas[f as usize];
                    grad += normals[f as usize] * areas[f as usize];
                }
                if area <= 0.0 {
                    return (p, Vector3::zeros());
                }
                let mut delta = Vector3::zeros();
                let mut stiff = 0.0;
                for &e in adj.edges_of(v) {
                    let (hn, k) = edge_vec[e as usize];
                    delta -= hn;
                    stiff += k;
                }
                let cap = if stiff > 0.0 { STABILITY / stiff } else { 0.0 };
                let factor = (1.5 * step / area).min(cap);
                let q = p + delta * factor;
                if q.iter().all(|x| x.is_finite()) {
                    (q, grad / 3.0)
                } else {
                    (p, Vector3::zeros())
                }
            })
            .unzip_into_vecs(&mut next, &mut grads);
        std::mem::swap(&mut mesh.positions, &mut next);
        if let Some(vc) = &volume {
            vc.apply(&mesh.faces, &mut mesh.positions, &grads);
        }
        if let Some(cb) = control.progress {
            cb(it + 1, ran);
        }
    }
    let (n, mean, max) = displacement_stats(&initial, &mesh.positions, &mov);
    Ok(SmoothReport {
        method: "anisotropic",
        iterations: ran,
        movable_vertices: n,
        mean_displacement: mean,
        max_displacement: max,
        mean_edge_length: l,
        seconds: start.elapsed().as_secs_f64(),
        parameters: serde_json::json!({
            "iterations": params.iterations,
            "step": step,
            "lambda": lambda,
            "r": r,
            "guide_passes": passes,
            "guide_sigma": sigma,
            "preserve_volume": params.preserve_volume,
            "fix_boundary": params.fix_boundary,
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smooth::testing::*;

    fn run(m: &mut Mesh, p: &AnisotropicParams) -> SmoothReport {
        let adj = Adjacency::build(m).unwrap();
        anisotropic(m, &adj, p, &Control::default()).unwrap()
    }

    #[test]
    fn noisy_plane_becomes_flat() {
        let n = 30;
        let mut m = plane(n);
        let h = 1.0 / n as f64;
        let mut g = Noise::new(3);
        for p in m.positions.iter_mut() {
            if p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0 {
                p.z = 0.3 * h * g.gauss();
            }
        }
        let before = mean_normal_error(&m, &Vector3::z());
        run(&mut m, &AnisotropicParams::default());
        let after = mean_normal_error(&m, &Vector3::z());
        let zmax = m.positions.iter().map(|p| p.z.abs()).fold(0.0, f64::max);
        let zrms =
            (m.positions.iter().map(|p| p.z * p.z).sum::<f64>() / m.positions.len() as f64).sqrt();
        assert!(
            after < 1.0 && before > 15.0,
            "normal error {before} -> {after} deg"
        );
        // Noise of 0.3 h rms: what is left (about 0.04 h) are long waves of small amplitude.
        assert!(
            zrms < 0.06 * h && zmax < 0.15 * h,
            "|z| rms {} max {} h",
            zrms / h,
            zmax / h
        );
    }

    /// Mean dihedral angle (between face normals) along each of the cube's 12 edges.
    fn cube_edge_angles(clean: &Mesh, m: &Mesh) -> Vec<f64> {
        let adj = Adjacency::build(m).unwrap();
        let mut sum = std::collections::BTreeMap::<(usize, usize, i8, i8), (f64, usize)>::new();
        for (e, &[a, b]) in adj.edges.iter().enumerate() {
            let (pa, pb) = (clean.positions[a as usize], clean.positions[b as usize]);
            let on: Vec<usize> = (0..3)
                .filter(|&k| pa[k].abs() == 1.0 && pb[k] == pa[k])
                .collect();
            if on.len() != 2 {
                continue;
            }
            let fs = adj.faces_of_edge(e);
            let n1 = m.face_cross(fs[0] as usize).normalize();
            let n2 = m.face_cross(fs[1] as usize).normalize();
            let ang = n1.dot(&n2).clamp(-1.0, 1.0).acos().to_degrees();
            let k = (on[0], on[1], pa[on[0]] as i8, pa[on[1]] as i8);
            let s = sum.entry(k).or_insert((0.0, 0));
            s.0 += ang;
            s.1 += 1;
        }
        sum.values().map(|(s, n)| s / *n as f64).collect()
    }

    #[test]
    fn noisy_cube_keeps_its_edges() {
        let clean = cube(12);
        let mut m = clean.clone();
        let h = m.mean_edge_length();
        add_normal_noise(&mut m, 0.2 * h, 5);
        let rep = run(&mut m, &AnisotropicParams::default());
        let angles = cube_edge_angles(&clean, &m);
        assert_eq!(angles.len(), 12);
        for a in &angles {
            assert!((a - 90.0).abs() < 5.0, "edge angles {angles:?}");
        }
        // The sides became flat: mean face normal error against the clean cube.
        let err: f64 = (0..m.faces.len())
            .map(|f| {
                let a = clean.face_cross(f).normalize();
                let b = m.face_cross(f).normalize();
                a.dot(&b).clamp(-1.0, 1.0).acos().to_degrees()
            })
            .sum::<f64>()
            / m.faces.len() as f64;
        assert!(err < 4.0, "mean normal error {err} deg, {rep:?}");
    }

    #[test]
    fn noisy_sphere_keeps_its_volume() {
        let clean = sphere(4);
        let v0 = clean.signed_volume();
        let mut m = clean.clone();
        let h = m.mean_edge_length();
        add_normal_noise(&mut m, 0.3 * h, 9);
        let p = AnisotropicParams {
            iterations: 20,
            ..Default::default()
        };
        run(&mut m, &p);
        let v = m.signed_volume();
        assert!(((v - v0) / v0).abs() < 0.01, "volume {v0} -> {v}");
        // And without the constraint the flow shrinks it measurably (the test can fail).
        let mut m2 = clean.clone();
        add_normal_noise(&mut m2, 0.3 * h, 9);
        run(
            &mut m2,
            &AnisotropicParams {
                preserve_volume: false,
                ..p
            },
        );
        assert!(
            m2.signed_volume() < v0 * 0.99,
            "{} vs {v0}",
            m2.signed_volume()
        );
    }

    #[test]
    fn open_cap_does_not_sink() {
        // The sphere's faces above z = 0.3: an open cap with a fixed rim.
        let mut cap = sphere(4);
        let keep: Vec<[u32; 3]> = cap
            .faces
            .iter()
            .copied()
            .filter(|f| f.iter().all(|&v| cap.positions[v as usize].z > 0.3))
            .collect();
        cap.faces = keep;
        let h = cap.mean_edge_length();
        add_normal_noise(&mut cap, 0.3 * h, 21);
        let adj = Adjacency::build(&cap).unwrap();
        let inner: Vec<usize> = (0..cap.positions.len())
            .filter(|&v| !adj.faces_of_vertex(v).is_empty() && !adj.is_boundary_or_singular(v))
            .collect();
        let mean_radius = |m: &Mesh| {
            inner
                .iter()
                .map(|&v| m.positions[v].coords.norm())
                .sum::<f64>()
                / inner.len() as f64
        };
        let r0 = mean_radius(&cap);
        let p = AnisotropicParams {
            iterations: 20,
            ..Default::default()
        };
        let mut a = cap.clone();
        anisotropic(&mut a, &adj, &p, &Control::default()).unwrap();
        assert!(
            (mean_radius(&a) - r0).abs() < 0.02 * h,
            "{r0} -> {}",
            mean_radius(&a)
        );
        let mut b = cap.clone();
        let free = AnisotropicParams {
            preserve_volume: false,
            ..p
        };
        anisotropic(&mut b, &adj, &free, &Control::default()).unwrap();
        assert!(
            mean_radius(&b) < r0 - 0.2 * h,
            "{r0} -> {}",
            mean_radius(&b)
        );
    }

    #[test]
    fn degenerate_input_gives_finite_positions() {
        let mut m = degenerate();
        for fix_boundary in [true, false] {
            let p = AnisotropicParams {
                fix_boundary,
                ..Default::default()
            };
            run(&mut m, &p);
            assert!(all_finite(&m), "{:?}", m.positions);
        }
        // Empty and face-less meshes are fine too.
        let mut empty = Mesh::default();
        assert_eq!(run(&mut empty, &AnisotropicParams::default()).iterations, 0);
        let mut cloud = Mesh::from_points(vec![Point3::new(1.0, 2.0, 3.0)], None);
        run(&mut cloud, &AnisotropicParams::default());
        assert_eq!(cloud.positions[0], Point3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn non_finite_input_and_bad_options_are_errors() {
        let mut m = plane(3);
        m.positions[5].x = f64::NAN;
        let adj = Adjacency::build(&m).unwrap();
        assert!(anisotropic(
            &mut m,
            &adj,
            &AnisotropicParams::default(),
            &Control::default()
        )
        .is_err());
        let mut m = plane(3);
        let p = AnisotropicParams {
            step: Some(-1.0),
            ..Default::default()
        };
        assert!(anisotropic(&mut m, &adj, &p, &Control::default()).is_err());
        // An adjacency of another mesh is refused, not indexed out of bounds.
        let mut other = plane(3);
        other.faces.truncate(5);
        assert!(anisotropic(
            &mut other,
            &adj,
            &AnisotropicParams::default(),
            &Control::default()
        )
        .is_err());
    }

    #[test]
    fn region_progress_and_thread_independence() {
        let mut m = sphere(3);
        let h = m.mean_edge_length();
        add_normal_noise(&mut m, 0.3 * h, 1);
        let adj = Adjacency::build(&m).unwrap();
        let mut seed = vec![false; m.positions.len()];
        seed[0] = true;
        let region = adj.grow_rings(&seed, 2);
        let calls = std::cell::Cell::new(0);
        let progress = |done: usize, total: usize| {
            calls.set(calls.get() + 1);
            assert!(done <= total);
        };
        let ctl = Control {
            region: Some(&region),
            progress: Some(&progress),
        };
        let p = AnisotropicParams {
            preserve_volume: false,
            ..Default::default()
        };
        let mut a = m.clone();
        let rep = anisotropic(&mut a, &adj, &p, &ctl).unwrap();
        assert_eq!(calls.get(), p.iterations);
        assert_eq!(rep.movable_vertices, region.iter().filter(|&&r| r).count());
        for (v, (x, y)) in m.positions.iter().zip(&a.positions).enumerate() {
            assert_eq!(
                x == y,
                !region[v] || x == y,
                "vertex {v} outside the region moved"
            );
            if !region[v] {
                assert_eq!(x, y);
            }
        }
        assert!(rep.max_displacement > 0.0);
        // Same result on one thread and on several, bit for bit.
        let on = |threads: usize| {
            let mut b = m.clone();
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    anisotropic(
                        &mut b,
                        &adj,
                        &AnisotropicParams::default(),
                        &Control::default(),
                    )
                })
                .unwrap();
            b.positions
        };
        assert_eq!(on(1), on(3));
    }
}
