use super::patch::{point_into_patch, SideKind};
use super::*;
use crate::mesh::Aabb;
use crate::polygonize::net_smooth::{project_and_smooth, SmoothOptions};
use crate::polygonize::test_shapes::*;
use crate::polygonize::voxel_net::{build_voxel_net, VoxelNetOptions};

fn net_on<I: Implicit>(f: &I, seeds: &[Point3<f64>], b: &Aabb, h: f64) -> QuadNet {
    let mut v = build_voxel_net(f, seeds, b, &VoxelNetOptions::new(h)).unwrap();
    project_and_smooth(&mut v.net, f, &SmoothOptions::new(b.diagonal(), h)).unwrap();
    v.net
}

/// A torus (radii 1 and 0.35), its box and its smoothed net at voxel size 0.15.
fn torus_net() -> (Torus, Aabb, QuadNet) {
    let t = Torus {
        big: 1.0,
        small: 0.35,
    };
    let b = aabb([-1.35, -1.35, -0.35], [1.35, 1.35, 0.35]);
    let net = net_on(&t, &seeds_on(&t, Point3::origin(), 1.4, 40), &b, 0.15);
    (t, b, net)
}

/// The data that fixes a side's boundary curve, in the edge's canonical direction:
/// points, parameters, derivative at the lower node, derivative at the higher node.
type Boundary = (Vec<Point3<f64>>, Vec<f64>, Vector3<f64>, Vector3<f64>);

fn boundary(p: &PatchSamples, k: usize) -> Boundary {
    let (s, t) = (p.s(), p.t());
    let (pts, params, d0, d1): (Vec<_>, _, _, _) = match k {
        0 => (
            (0..=s).map(|i| p.points[i][0]).collect(),
            p.params_u.clone(),
            p.tan_u0[0],
            p.tan_u1[0],
        ),
        1 => (
            p.points[s].clone(),
            p.params_v.clone(),
            p.tan_v0[s],
            p.tan_v1[s],
        ),
        2 => (
            (0..=s).map(|i| p.points[i][t]).collect(),
            p.params_u.clone(),
            p.tan_u0[t],
            p.tan_u1[t],
        ),
        _ => (
            p.points[0].clone(),
            p.params_v.clone(),
            p.tan_v0[0],
            p.tan_v1[0],
        ),
    };
    if p.sides[k].reversed {
        let rev_params = params.iter().rev().map(|x| 1.0 - x).collect();
        (pts.into_iter().rev().collect(), rev_params, -d1, -d0)
    } else {
        (pts, params, d0, d1)
    }
}

/// Watertightness, samples on f = 0, G1 at the boundary samples, outward orientation.
fn check_network<I: Implicit>(name: &str, f: &I, net: &QuadNet, ps: &PatchSampling, scale: f64) {
    assert_eq!(ps.patches.len(), net.quads.len());
    // 1. Both quads of every edge see bit-identical boundary data, equal to the edge's.
    for (e, eq) in net.edge_quads.iter().enumerate() {
        let mut seen = Vec::new();
        for &q in eq {
            let p = &ps.patches[q as usize];
            let k = p.sides.iter().position(|s| s.edge == e as u32).unwrap();
            seen.push(boundary(p, k));
        }
        assert_eq!(
            seen[0], seen[1],
            "{name}: edge {e} differs between its quads"
        );
        let ed = &ps.edges[e];
        assert_eq!(seen[0].0, ed.points);
        assert_eq!(seen[0].2, ed.tangents[0]);
        assert_eq!(seen[0].3, *ed.tangents.last().unwrap());
    }
    // 2. Every sample on f = 0.
    let mut worst = 0.0f64;
    for p in &ps.patches {
        for row in &p.points {
            for x in row {
                let (v, g) = f.value_and_gradient(x);
                worst = worst.max(v.abs() / g.norm());
            }
        }
    }
    assert!(
        worst <= 1e-9 * scale,
        "{name}: sample off the surface by {worst:e}"
    );
    // 3. At boundary samples, S_u and S_v lie in the tangent plane and S_u x S_v is the
    // outward normal.
    let mut max_tilt = 0.0f64;
    for p in &ps.patches {
        let (s, t) = (p.s(), p.t());
        for k in 0..4 {
            let ed = &ps.edges[p.sides[k].edge as usize];
            let n_side = if k % 2 == 0 { s } else { t };
            for m in 0..=n_side {
                let idx = if p.sides[k].reversed { n_side - m } else { m };
                let sign = if p.sides[k].reversed { -1.0 } else { 1.0 };
                let along = ed.tangents[idx] * sign;
                let normal = ed.normals[idx];
                let cross = match k {
                    0 => p.tan_v0[m],
                    1 => p.tan_u1[m],
                    2 => p.tan_v1[m],
                    _ => p.tan_u0[m],
                };
                let (su, sv) = if k % 2 == 0 {
                    (along, cross)
                } else {
                    (cross, along)
                };
                let nrm = su.cross(&sv);
                assert!(
                    nrm.dot(&normal) > 0.0,
                    "{name}: patch {} side {k} sample {m} folds",
                    p.quad
                );
                assert!(
                    cross.dot(&normal).abs() <= 1e-12 * cross.norm(),
                    "{name}: cross tangent off the plane"
                );
                max_tilt = max_tilt.max(nrm.normalize().cross(&normal).norm());
            }
        }
    }
    assert!(
        max_tilt < 1e-9,
        "{name}: patch normal tilts {max_tilt:e} from the implicit's"
    );
    eprintln!(
        "{name}: {} patches, {} ribbons, intervals {:?}, {} rounds, max deviation {:.2e}, {} over tolerance, {} grid points",
        ps.patches.len(),
        ps.report.ribbons,
        ps.report.interval_histogram,
        ps.report.rounds,
        ps.report.max_deviation,
        ps.report.over_tolerance,
        ps.report.grid_points
    );
}

/// Starting from an unmeasured trial sampling gives exactly what sampling from scratch
/// with the trial's count as minimum gives; a start of another net is ignored.
#[test]
fn a_given_first_round_is_the_first_round() {
    let (t, b, net) = torus_net();
    // Tighter than four intervals per side meet (about 1e-7 of the diagonal), so that
    // refinement goes on from the start.
    let tol = 2e-8 * b.diagonal();
    let mut trial_opt = SampleOptions::new(tol, b.diagonal());
    (trial_opt.min_intervals, trial_opt.max_intervals) = (4, 4);
    trial_opt.measure = false;
    let trial = sample_patches(&net, &t, &trial_opt).unwrap();
    assert_eq!(trial.report.rounds, 1);
    assert!(trial
        .patches
        .iter()
        .all(|p| !p.measured && p.deviation() == 0.0));
    let opt = SampleOptions::new(tol, b.diagonal());
    let from = sample_patches_from(&net, &t, &opt, Some(trial.clone())).unwrap();
    let mut scratch_opt = opt;
    scratch_opt.min_intervals = 4;
    let scratch = sample_patches(&net, &t, &scratch_opt).unwrap();
    assert!(from.report.rounds > 1, "{:?}", from.report);
    assert!(from.patches.iter().all(|p| p.measured));
    assert_eq!(from.patches, scratch.patches);
    assert_eq!(from.report, scratch.report);
    // A start sampled on another net (the same torus at another voxel size).
    let other = net_on(&t, &seeds_on(&t, Point3::origin(), 1.4, 40), &b, 0.2);
    let wrong = sample_patches(&other, &t, &trial_opt).unwrap();
    let ignored = sample_patches_from(&net, &t, &opt, Some(wrong)).unwrap();
    assert_eq!(
        ignored.patches,
        sample_patches(&net, &t, &opt).unwrap().patches
    );
}

#[test]
fn sphere_and_torus_patches_are_watertight_and_meet_the_tolerance() {
    let s = Sphere {
        c: Point3::new(0.02, -0.01, 0.03),
        r: 1.0,
    };
    let b = aabb([-1.0; 3], [1.0; 3]);
    let net = net_on(&s, &seeds_on(&s, s.c, 1.2, 10), &b, 0.25);
    let tol = 1e-4 * b.diagonal();
    let ps = sample_patches(&net, &s, &SampleOptions::new(tol, b.diagonal())).unwrap();
    check_network("sphere", &s, &net, &ps, b.diagonal());
    assert_eq!(ps.report.over_tolerance, 0);
    assert!(ps.report.max_deviation <= tol);
    // Same input, same output.
    let again = sample_patches(&net, &s, &SampleOptions::new(tol, b.diagonal())).unwrap();
    assert_eq!(again.patches, ps.patches);

    let (t, b, net) = torus_net();
    let tol = 1e-4 * b.diagonal();
    let ps = sample_patches(&net, &t, &SampleOptions::new(tol, b.diagonal())).unwrap();
    check_network("torus", &t, &net, &ps, b.diagonal());
    assert_eq!(ps.report.over_tolerance, 0);
    // A tolerance below what the coarse grids reach needs more samples, and gets met.
    let tight = 0.25 * ps.report.max_deviation;
    let fine = sample_patches(&net, &t, &SampleOptions::new(tight, b.diagonal())).unwrap();
    check_network("torus, tight", &t, &net, &fine, b.diagonal());
    assert!(fine.report.grid_points > ps.report.grid_points);
    assert!(fine.report.max_deviation <= tight);
}

#[test]
fn hard_shapes_give_watertight_samples() {
    let h = 0.1;
    let b = aabb([-1.2; 3], [1.2; 3]);
    let tol = 1e-4 * b.diagonal();
    let opt = SampleOptions::new(tol, b.diagonal());
    let dir = Vector3::new(1.0, 1.0, 0.3).normalize();
    let a = Sphere {
        c: Point3::origin() - dir * 0.5125,
        r: 0.5,
    };
    let bb = Sphere {
        c: Point3::origin() + dir * 0.5125,
        r: 0.5,
    };
    let mut seeds = seeds_on(&a, a.c, 0.7, 10);
    seeds.extend(seeds_on(&bb, bb.c, 0.7, 10));
    let u = Union(a, bb);
    let net = net_on(&u, &seeds, &b, h);
    check_network(
        "two spheres",
        &u,
        &net,
        &sample_patches(&net, &u, &opt).unwrap(),
        b.diagonal(),
    );
    let c = SoftCube { a: 0.6, k: 0.04 };
    let net = net_on(&c, &seeds_on(&c, Point3::origin(), 0.8, 30), &b, h);
    check_network(
        "soft cube",
        &c,
        &net,
        &sample_patches(&net, &c, &opt).unwrap(),
        b.diagonal(),
    );
    let d = Vector3::new(1.0, 0.2, 0.1).normalize();
    let db = SmoothUnion {
        a: Union(
            Sphere {
                c: Point3::origin() - d * 0.6,
                r: 0.35,
            },
            Sphere {
                c: Point3::origin() + d * 0.6,
                r: 0.35,
            },
        ),
        b: Capsule {
            a: Point3::origin() - d * 0.6,
            b: Point3::origin() + d * 0.6,
            r: 0.06,
        },
        k: 0.05,
    };
    let net = net_on(&db, &seeds_on(&db, Point3::origin(), 1.0, 60), &b, h);
    check_network(
        "dumbbell",
        &db,
        &net,
        &sample_patches(&net, &db, &opt).unwrap(),
        b.diagonal(),
    );
    let slab = RoundedBox {
        b: Vector3::new(0.6, 0.45, 0.0),
        r: 0.03,
    };
    let net = net_on(&slab, &seeds_on(&slab, Point3::origin(), 0.7, 60), &b, h);
    check_network(
        "thin slab",
        &slab,
        &net,
        &sample_patches(&net, &slab, &opt).unwrap(),
        b.diagonal(),
    );
    let blob = Blob {
        r: 0.8,
        amp: 0.04,
        w: 20.0,
    };
    let net = net_on(&blob, &seeds_on(&blob, Point3::origin(), 0.9, 60), &b, h);
    check_network(
        "blob",
        &blob,
        &net,
        &sample_patches(&net, &blob, &opt).unwrap(),
        b.diagonal(),
    );
}

#[test]
fn cross_derivatives_reaching_back_are_reflected_into_the_patch() {
    // A v = 0 side along +x on the plane z = 0 (normal +z): the patch lies at +y.
    let along = vec![Vector3::x(); 4];
    let normals = vec![Vector3::z(); 4];
    let mut d = vec![
        Vector3::new(0.3, 0.2, 0.0),  // corner: never touched
        Vector3::new(0.5, 1.0, 0.0),  // into the patch: kept
        Vector3::new(0.4, -2.0, 0.0), // back across the side: reflected
        Vector3::new(0.1, -0.7, 0.0), // corner: never touched
    ];
    let before = d.clone();
    point_into_patch(&mut d, &along, &normals, SideKind::V);
    assert_eq!(d[0], before[0]);
    assert_eq!(d[1], before[1]);
    assert_eq!(d[2], Vector3::new(0.4, 2.0, 0.0));
    assert_eq!(d[3], before[3]);
    // The same side seen as a u side (running along +x, the patch lies at -y, since
    // S_u x S_v must point along +z): the sign convention flips.
    let mut d = before.clone();
    point_into_patch(&mut d, &along, &normals, SideKind::U);
    assert_eq!(d[1], Vector3::new(0.5, -1.0, 0.0));
    assert_eq!(d[2], before[2]);
}

#[test]
fn params_are_reversal_symmetric_and_options_checked() {
    for n in 1..40 {
        let p = uniform_params(n);
        assert_eq!(p[0], 0.0);
        assert_eq!(p[n], 1.0);
        for k in 0..=n {
            assert_eq!(p[n - k], 1.0 - p[k]);
        }
    }
    let s = Sphere {
        c: Point3::origin(),
        r: 1.0,
    };
    let (nodes, quads) = crate::polygonize::quad_net::tests::cube();
    let nodes = nodes
        .iter()
        .map(|p| Point3::from((p.coords - Vector3::repeat(0.5)).normalize()))
        .collect();
    let net = QuadNet::new(nodes, quads).unwrap();
    assert!(sample_patches(&net, &s, &SampleOptions::new(0.0, 1.0)).is_err());
    assert!(sample_patches(&net, &s, &SampleOptions::new(f64::NAN, 1.0)).is_err());
    let ps = sample_patches(&net, &s, &SampleOptions::new(1e-5, 2.0)).unwrap();
    check_network("cube on sphere", &s, &net, &ps, 2.0);
}
