//! Property tests (proptest) of the geometry kernels, on random but well-posed inputs; few cases
//! each so the file runs in seconds:
//! - cubic curve interpolation (seed 004 eq. 9-11) passes through its points and end tangents;
//! - patch interpolation (`BSplineSurface::interpolate_grid`, seed 004 eq. 12-14) reproduces
//!   its grid points at the parameter values;
//! - Newton projection onto an implicit lands on f = 0 or reports failure;
//! - hole filling leaves a manifold mesh with fewer boundary loops;
//! - every smoothing method keeps every coordinate finite, even with noise and degenerate faces.

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use scansurf::implicit::project::{project, ProjectOptions};
use scansurf::implicit::Implicit;
use scansurf::mesh::{Mesh, Topology};
use scansurf::nurbs::{BSplineCurve, BSplineSurface, Params, PatchGrid, Twist};

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

fn coord() -> impl Strategy<Value = f64> {
    -10.0..10.0f64
}

fn point() -> impl Strategy<Value = Point3<f64>> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

fn vector() -> impl Strategy<Value = Vector3<f64>> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

/// Strictly increasing parameters from 0 to 1 with gaps of at least 1/(8n).
fn params(n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(1.0..8.0f64, n - 1).prop_map(|gaps| {
        let total: f64 = gaps.iter().sum();
        let mut t = vec![0.0];
        let mut acc = 0.0;
        for g in &gaps {
            acc += g / total;
            t.push(acc);
        }
        *t.last_mut().unwrap() = 1.0;
        t
    })
}

proptest! {
    #![proptest_config(config(48))]

    #[test]
    fn curve_interpolation_reproduces_points_and_tangents(
        (pts, t) in (2usize..9).prop_flat_map(|n| (prop::collection::vec(point(), n), params(n))),
        t0 in vector(),
        t1 in vector(),
    ) {
        let p = Params::new(&t).unwrap();
        let c = BSplineCurve::interpolate_with_end_tangents(&pts, &p, t0, t1).unwrap();
        for (q, &ti) in pts.iter().zip(&t) {
            let e = (c.evaluate(ti) - q).norm();
            prop_assert!(e < 1e-8 * (1.0 + q.coords.norm()), "error {} at t = {}", e, ti);
            prop_assert!(c.evaluate(ti).iter().all(|v| v.is_finite()));
        }
        prop_assert!((c.derivative(0.0, 1) - t0).norm() < 1e-7 * (1.0 + t0.norm()));
        prop_assert!((c.derivative(1.0, 1) - t1).norm() < 1e-7 * (1.0 + t1.norm()));
    }
}

proptest! {
    #![proptest_config(config(24))]

    #[test]
    fn grid_interpolation_reproduces_points(
        (s, t, u, v, heights) in (2usize..6, 2usize..6).prop_flat_map(|(s, t)| (
            Just(s), Just(t), params(s), params(t),
            prop::collection::vec(-1.0..1.0f64, s * t),
        )),
        zero_twist in any::<bool>(),
    ) {
        // A height field over a warped grid, with tangents from its differences.
        let points: Vec<Vec<Point3<f64>>> = (0..s)
            .map(|k| (0..t).map(|j| Point3::new(3.0 * u[k], 2.0 * v[j] + 0.3 * u[k], heights[k * t + j])).collect())
            .collect();
        let du = |j: usize, k0: usize, k1: usize| (points[k1][j] - points[k0][j]) / (u[k1] - u[k0]);
        let dv = |k: usize, j0: usize, j1: usize| (points[k][j1] - points[k][j0]) / (v[j1] - v[j0]);
        let grid = PatchGrid {
            du_u0: (0..t).map(|j| du(j, 0, 1)).collect(),
            du_u1: (0..t).map(|j| du(j, s - 2, s - 1)).collect(),
            dv_v0: (0..s).map(|k| dv(k, 0, 1)).collect(),
            dv_v1: (0..s).map(|k| dv(k, t - 2, t - 1)).collect(),
            twist: if zero_twist { Twist::Zero } else { Twist::Estimate },
            points: points.clone(),
        };
        let surf = BSplineSurface::interpolate_grid(&grid, &Params::new(&u).unwrap(), &Params::new(&v).unwrap()).unwrap();
        for k in 0..s {
            for j in 0..t {
                let e = (surf.evaluate(u[k], v[j]) - points[k][j]).norm();
                prop_assert!(e < 1e-8, "error {} at ({}, {})", e, k, j);
            }
        }
    }
}

/// A sphere of radius `r` as a signed distance.
struct Sphere {
    r: f64,
}

impl Implicit for Sphere {
    fn value(&self, p: &Point3<f64>) -> f64 {
        p.coords.norm() - self.r
    }
    fn gradient(&self, p: &Point3<f64>) -> Vector3<f64> {
        let n = p.coords.norm();
        if n > 0.0 {
            p.coords / n
        } else {
            Vector3::zeros()
        }
    }
}

/// A torus (major radius 2, minor `r`) as an algebraic, not distance-like, implicit: Newton
/// converges from near it and may fail from far away.
struct Torus {
    r: f64,
}

impl Implicit for Torus {
    fn value(&self, p: &Point3<f64>) -> f64 {
        let q = p.coords.norm_squared() + 4.0 - self.r * self.r;
        q * q - 16.0 * (p.x * p.x + p.y * p.y)
    }
    fn gradient(&self, p: &Point3<f64>) -> Vector3<f64> {
        let q = p.coords.norm_squared() + 4.0 - self.r * self.r;
        Vector3::new(
            4.0 * q * p.x - 32.0 * p.x,
            4.0 * q * p.y - 32.0 * p.y,
            4.0 * q * p.z,
        )
    }
}

proptest! {
    #![proptest_config(config(64))]

    #[test]
    fn projection_lands_on_the_surface_or_fails(x in point(), r in 0.2..0.9f64) {
        let opts = ProjectOptions::for_diagonal(10.0);
        let sphere = Sphere { r: 3.0 };
        let torus = Torus { r };
        let surfaces: [&dyn Implicit; 2] = [&sphere, &torus];
        for f in surfaces {
            match project(f, &x, &opts) {
                Ok((p, _)) => {
                    prop_assert!(p.iter().all(|c| c.is_finite()));
                    prop_assert!(f.value(&p).abs() <= opts.tolerance, "f = {}", f.value(&p));
                }
                Err(e) => prop_assert!(matches!(e, scansurf::Error::Numerical(_)), "{e}"),
            }
        }
        // From a point near the sphere, the projection must succeed.
        let near = Point3::from(x.coords.try_normalize(1e-9).unwrap_or(Vector3::x()) * 3.05);
        let (p, _) = project(&sphere, &near, &opts).unwrap();
        prop_assert!((p.coords.norm() - 3.0).abs() <= opts.tolerance);
    }
}

/// A closed, consistently oriented UV sphere with `n` rings.
fn uv_sphere(n: u32) -> Mesh {
    let m = 2 * n;
    let mut positions = vec![Point3::new(0.0, 0.0, 1.0)];
    for i in 1..n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..m {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
            positions.push(Point3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
    }
    positions.push(Point3::new(0.0, 0.0, -1.0));
    let south = positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * m + (j % m);
    let mut faces = Vec::new();
    for j in 0..m {
        faces.push([0, ring(1, j), ring(1, j + 1)]);
        faces.push([south, ring(n - 1, j + 1), ring(n - 1, j)]);
    }
    for i in 1..n - 1 {
        for j in 0..m {
            faces.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
            faces.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
        }
    }
    Mesh {
        positions,
        normals: None,
        faces,
    }
}

fn is_manifold(t: &Topology) -> bool {
    t.non_manifold_edges.is_empty() && t.non_manifold_vertices.is_empty()
}

proptest! {
    #![proptest_config(config(12))]

    #[test]
    fn hole_filling_keeps_manifoldness(
        removed in prop::collection::btree_set(0usize..240, 1..6),
        planar in any::<bool>(),
    ) {
        let mut mesh = uv_sphere(10);
        let keep: Vec<[u32; 3]> = mesh
            .faces
            .iter()
            .enumerate()
            .filter(|(i, _)| !removed.contains(&(i % mesh.faces.len())))
            .map(|(_, f)| *f)
            .collect();
        mesh.faces = keep;
        let before = Topology::build(&mesh);
        // Removing faces can pinch a vertex; such inputs are outside the property.
        prop_assume!(is_manifold(&before));
        prop_assert!(!before.loops.is_empty());
        let opts = scansurf::holes::FillOptions {
            method: if planar { scansurf::holes::FillMethod::Planar } else { scansurf::holes::FillMethod::Rbf },
            parallel: false,
            ..Default::default()
        };
        let (filled, _) = scansurf::holes::fill_holes(&mesh, &opts).unwrap();
        let after = Topology::build(&filled);
        prop_assert!(is_manifold(&after), "non-manifold after filling {:?}", removed);
        prop_assert!(after.loops.len() < before.loops.len());
        prop_assert_eq!(after.misoriented_edges, 0);
        prop_assert!(filled.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
        // Every original face is kept.
        prop_assert_eq!(&filled.faces[..mesh.faces.len()], &mesh.faces[..]);
    }
}

proptest! {
    #![proptest_config(config(16))]

    #[test]
    fn smoothing_never_produces_nan(
        noise in prop::collection::vec(-0.3..0.3f64, 3 * 162),
        collapse in prop::collection::vec(0usize..162, 0..6),
        method in prop::sample::select(vec!["anisotropic", "arc", "centroid"]),
        iterations in 1usize..8,
    ) {
        let mut mesh = uv_sphere(9);
        for (i, p) in mesh.positions.iter_mut().enumerate() {
            *p += Vector3::new(noise[3 * i], noise[3 * i + 1], noise[3 * i + 2]);
        }
        // Degenerate faces: some vertices moved onto a neighbour.
        for &v in &collapse {
            let f = mesh.faces.iter().find(|f| f.contains(&(v as u32))).copied();
            if let Some(f) = f {
                let other = f.iter().copied().find(|&w| w as usize != v).unwrap();
                mesh.positions[v] = mesh.positions[other as usize];
            }
        }
        let adj = scansurf::smooth::Adjacency::build(&mesh).unwrap();
        let m = scansurf::smooth::Method::by_name(method).unwrap().with_iterations(iterations);
        let r = scansurf::smooth::run(&mut mesh, &adj, &m, None, &scansurf::smooth::Control::default());
        match r {
            Ok(_) => prop_assert!(
                mesh.positions.iter().all(|p| p.iter().all(|c| c.is_finite())),
                "{} produced a non-finite coordinate", method
            ),
            Err(e) => prop_assert!(!matches!(e, scansurf::Error::Io { .. }), "{e}"),
        }
    }
}
