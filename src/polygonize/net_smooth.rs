//! Projection of the quad net onto f = 0 and tangential relaxation on the surface (seed 004
//! section 3: "normal projection, then smoothing"; the relaxation is the area-weighted centroid
//! rule of seed 003 eq. 9 / seed 000 eq. 13, restricted to the tangent plane).
//!
//! One relaxation sweep (Jacobi, so parallel and order-independent):
//! 1. target t_i of node i = sum_q A_q c_q / sum_q A_q over its quads q (c_q the quad's centroid,
//!    A_q its area |d1 x d2| / 2), both taken in the *unrolled* neighbourhood of node i: each
//!    corner q of the quads around i replaced by x_i + log_i(q), the discrete log map of
//!    [`super::log_map`] (the chord turned into i's tangent plane by half the turning of the
//!    normals, at arc length). Beside a crease rounded below the patch size (the rim of the
//!    Stanford bunny's flat base) chords that climb the far side project onto the tangent
//!    plane as short vectors in nearly one direction, and a centroid of the chords' shadows
//!    leaves the patch corner there a sliver (measured: 11.6 degrees between the patch's
//!    corner tangents, a fold OpenCASCADE's point projection fell into); unrolled, the far
//!    nodes sit at their distance along the surface and the corner opens (above 15 degrees).
//!    (A parallelogram rule, t = p_next + p_prev - p_opposite averaged over the quads, was
//!    tried and lowered the minimum angle on every test shape.)
//! 2. x_i <- x_i + lambda P_i (t_i - x_i), with P_i = I - n_i n_i^T the tangent-plane projector;
//! 3. x_i <- the root of f on the line x_i + s n_i nearest s = 0 (n_i the normal before the
//!    move), i.e. back onto the surface across the tangent plane.
//!
//! The first projection of the voxel net's nodes also works on lines, along the net's own normal
//! at each node (the sum of its quads' normals), not along the gradient: on a plate thinner than
//! a voxel the nodes of the net's side faces lie inside the plate, where the gradient points to
//! the flat faces; along the net normal they reach the rim, and the side quads wrap it.
//!
//! A node whose move would flip or degenerate one of its quads keeps its old position. Sweeps stop
//! when the minimum corner angle has not improved for `patience` sweeps; the best net seen (fewest
//! flipped + degenerate quads, then the largest minimum angle, then the largest mean) is kept.

use super::log_map::log_map;
use super::net_quality::{node_residuals, quad_normals, quad_shape, quality_with, NetQuality};
use super::newton::{project, solve_on_line, solve_on_line_facing, NewtonOptions};
use super::quad_net::QuadNet;
use crate::implicit::Implicit;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Options of [`project_and_smooth`].
#[derive(Debug, Clone, Copy)]
pub struct SmoothOptions {
    /// Length scale for tolerances (the bounding-box diagonal): nodes end within 1e-12 of it
    /// from f = 0 (first-order distance).
    pub scale: f64,
    /// Nominal edge length (the voxel size h): caps Newton steps.
    pub h: f64,
    /// Relaxation step lambda in (0, 1].
    pub step: f64,
    pub max_iterations: usize,
    pub patience: usize,
}

impl SmoothOptions {
    /// Positive `h` and `scale`, a step in (0, 1].
    fn validate(&self) -> Result<()> {
        if self.h > 0.0 && self.scale > 0.0 && self.step > 0.0 && self.step <= 1.0 {
            Ok(())
        } else {
            Err(Error::InvalidOption(
                "smoothing needs positive h and scale and a step in (0, 1]".into(),
            ))
        }
    }

    pub fn new(scale: f64, h: f64) -> Self {
        SmoothOptions {
            scale,
            h,
            step: 0.8,
            max_iterations: 200,
            // Measured on the bunny: every grid placement's best net came within the first
            // few sweeps of the last improvement; 6 sweeps without one give the same nets as
            // 15 did, in half the sweeps (docs/BENCHMARKS.md, session 9).
            patience: 6,
        }
    }
}

/// Quality before and after smoothing.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SmoothReport {
    /// Right after the projection of the voxel corners.
    pub projected: NetQuality,
    /// After the relaxation.
    pub smoothed: NetQuality,
    pub iterations: usize,
}

fn score(q: &NetQuality) -> (usize, f64, f64) {
    (q.flipped + q.degenerate, q.min_angle_deg, q.mean_angle_deg)
}

fn better(a: &NetQuality, b: &NetQuality) -> bool {
    let (sa, sb) = (score(a), score(b));
    sa.0 < sb.0
        || (sa.0 == sb.0 && (sa.1 > sb.1 + 1e-9 || (sa.1 >= sb.1 - 1e-9 && sa.2 > sb.2 + 1e-9)))
}

/// Projects every node onto f = 0 and relaxes the net on the surface.
pub fn project_and_smooth<I: Implicit + ?Sized>(
    net: &mut QuadNet,
    f: &I,
    opt: &SmoothOptions,
) -> Result<SmoothReport> {
    opt.validate()?;
    let newton = NewtonOptions::new(opt.scale, 0.5 * opt.h);
    let net_normals = net_normals(net);
    let (nodes, normals) =
        project_on_lines(f, &net.nodes, &net_normals, 1.5 * opt.h, &newton, None)?;
    net.nodes = nodes;
    let state = State::new(net, f, normals, opt);
    relax_on_surface(net, f, opt, state, None)
}

/// What the relaxation must respect besides the surface: nodes that must not move and nodes
/// whose moves must stay on a curve of the surface (a crease) or on one side of it.
pub trait NodeConstraint: Sync {
    /// Whether node `i` keeps its place.
    fn pinned(&self, i: usize) -> bool;
    /// Where node `i`, relaxed from `old` to `new` (both on the surface), goes instead: `new`
    /// when it is free there, a point of its curve near `new`, `old` when neither will do.
    fn constrain(&self, i: usize, old: &Point3<f64>, new: &Point3<f64>) -> Point3<f64>;
}

/// Relaxes a net whose nodes already lie on f = 0, as [`project_and_smooth`] does after its
/// projection, with `constraint` on the nodes' moves (the boundary of an open net stays
/// pinned as well).
pub fn relax_constrained<I: Implicit + ?Sized>(
    net: &mut QuadNet,
    f: &I,
    opt: &SmoothOptions,
    constraint: &dyn NodeConstraint,
) -> Result<SmoothReport> {
    opt.validate()?;
    let normals = super::net_quality::node_normals(f, &net.nodes);
    let state = State::new(net, f, normals, opt);
    relax_on_surface(net, f, opt, state, Some(constraint))
}

/// The relaxation sweeps of [`project_and_smooth`] from nodes on the surface with unit
/// normals `state`; the best net seen is kept.
fn relax_on_surface<I: Implicit + ?Sized>(
    net: &mut QuadNet,
    f: &I,
    opt: &SmoothOptions,
    mut state: State,
    constraint: Option<&dyn NodeConstraint>,
) -> Result<SmoothReport> {
    let newton = NewtonOptions::new(opt.scale, 0.5 * opt.h);
    let quality = |net: &QuadNet, st: &State| quality_with(net, &st.quad_n, &[0.0]);
    let projected = quality(net, &state);
    let mut best = (projected, net.nodes.clone());
    let mut since = 0;
    let mut iterations = 0;
    let mut pinned = net.boundary_nodes();
    if let Some(c) = constraint {
        for (i, p) in pinned.iter_mut().enumerate() {
            *p |= c.pinned(i);
        }
    }
    for _ in 0..opt.max_iterations {
        iterations += 1;
        let moved = relax_step(net, &state.node_n, &pinned, opt.step);
        // A node that cannot be put back on the surface keeps its place.
        let (mut proj, mut normals) = project_on_lines(
            f,
            &moved,
            &state.node_n,
            0.5 * opt.h,
            &newton,
            Some((&net.nodes, &state.node_n)),
        )?;
        if let Some(c) = constraint {
            let fixed: Vec<(usize, Point3<f64>)> = (0..proj.len())
                .into_par_iter()
                .filter(|&i| !pinned[i])
                .filter_map(|i| {
                    let q = c.constrain(i, &net.nodes[i], &proj[i]);
                    (q != proj[i]).then_some((i, q))
                })
                .collect();
            for (i, q) in fixed {
                proj[i] = q;
                normals[i] = f.gradient(&q).try_normalize(0.0).unwrap_or(state.node_n[i]);
            }
        }
        state = keep_unfolded(net, proj, normals, &state, f, opt);
        let q = quality(net, &state);
        if better(&q, &best.0) {
            let improved_min =
                q.min_angle_deg > best.0.min_angle_deg + 1e-3 || score(&q).0 < score(&best.0).0;
            best = (q, net.nodes.clone());
            since = if improved_min { 0 } else { since + 1 };
        } else {
            since += 1;
        }
        if since >= opt.patience {
            break;
        }
    }
    net.nodes = best.1;
    // Residuals of the kept nodes (the iterations do not need them).
    let residuals = node_residuals(f, &net.nodes);
    let fix = |mut q: NetQuality| {
        q.max_residual = residuals.iter().fold(0.0, |a: f64, &b| a.max(b));
        q
    };
    Ok(SmoothReport {
        projected: fix(projected),
        smoothed: fix(best.0),
        iterations,
    })
}

/// Unit normals at the nodes and at the quad centres.
struct State {
    node_n: Vec<Vector3<f64>>,
    quad_n: Vec<Vector3<f64>>,
}

impl State {
    fn new<I: Implicit + ?Sized>(
        net: &QuadNet,
        f: &I,
        node_n: Vec<Vector3<f64>>,
        opt: &SmoothOptions,
    ) -> State {
        let quad_n = quad_normals(f, net, &node_n, opt.scale, opt.h);
        State { node_n, quad_n }
    }
}

/// Area-weighted normals of the net at its nodes (sum of the diagonal cross products of the
/// incident quads), unit.
fn net_normals(net: &QuadNet) -> Vec<Vector3<f64>> {
    (0..net.nodes.len())
        .into_par_iter()
        .map(|i| {
            let mut n = Vector3::zeros();
            for &q in net.node_quads(i) {
                let p = net.quads[q as usize].map(|k| net.nodes[k as usize]);
                n += (p[2] - p[0]).cross(&(p[3] - p[1]));
            }
            n.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
        })
        .collect()
}

/// Node positions with their unit normals.
type PointsAndNormals<'a> = (&'a [Point3<f64>], &'a [Vector3<f64>]);
/// Projected positions and the unit normals there.
type Projected = (Vec<Point3<f64>>, Vec<Vector3<f64>>);

/// Each point moved onto f = 0 along its line x + s n (the root nearest s = 0 where f grows
/// along n, so a node stays on the sheet its outward normal n faces: on a plate thinner than a
/// voxel both sheets lie within reach; |s| <= s_max);
/// Newton along the gradient where the line misses the surface. Returns the points and the unit
/// normals there. Where both fail: the `fallback` point and normal when given, else an error.
fn project_on_lines<I: Implicit + ?Sized>(
    f: &I,
    points: &[Point3<f64>],
    dirs: &[Vector3<f64>],
    s_max: f64,
    opt: &NewtonOptions,
    fallback: Option<PointsAndNormals<'_>>,
) -> Result<Projected> {
    let out: Vec<(Point3<f64>, Vector3<f64>)> = (0..points.len())
        .into_par_iter()
        .map(|i| {
            let (p, n) = (points[i], dirs[i]);
            let solved = match (n.norm_squared() > 0.0)
                .then(|| solve_on_line_facing(f, p, n, s_max, opt.tol).ok())
                .flatten()
            {
                Some((s, g)) => Ok((p + n * s, g)),
                None => project(f, p, opt)
                    .or_else(|e| nearest_on_lattice_lines(f, p, s_max, opt.tol).ok_or(e)),
            };
            match (solved, fallback) {
                (Ok((q, g)), _) => Ok((q, g.try_normalize(0.0).unwrap_or_else(Vector3::zeros))),
                (Err(_), Some((pts, nrm))) => Ok((pts[i], nrm[i])),
                (Err(e), None) => Err(e),
            }
        })
        .collect::<Result<_>>()?;
    Ok(out.into_iter().unzip())
}

/// Last resort for a node that neither its line nor Newton along the gradient brings onto
/// f = 0 (Newton stalls at a local minimum of |f| between two thin parts, e.g. a leg and a
/// horn a voxel apart): the nearest root on the 13 lattice lines through `p` (axes, face and
/// body diagonals), each searched within `s_max`.
fn nearest_on_lattice_lines<I: Implicit + ?Sized>(
    f: &I,
    p: Point3<f64>,
    s_max: f64,
    tol: f64,
) -> Option<(Point3<f64>, Vector3<f64>)> {
    let mut best: Option<(f64, Point3<f64>, Vector3<f64>)> = None;
    for m in 0..27 {
        let d = Vector3::new(
            (m % 3) as f64 - 1.0,
            (m / 3 % 3) as f64 - 1.0,
            (m / 9) as f64 - 1.0,
        );
        // One of each pair of opposite directions: the line search covers both signs.
        if m <= 13 {
            continue;
        }
        let w = d.normalize();
        if let Ok((s, g)) = solve_on_line(f, p, w, s_max, tol) {
            if best.as_ref().is_none_or(|b| s.abs() < b.0) {
                best = Some((s.abs(), p + w * s, g));
            }
        }
    }
    best.map(|(_, q, g)| (q, g))
}

/// Tangential move of every node toward its relaxation target: the area-weighted centroid of
/// its quads in the unrolled neighbourhood ([`super::log_map`]), so that a node beside a
/// crease sees the nodes beyond it at their distance along the surface, in the direction the
/// surface takes, not at their chords' short shadows on its tangent plane. `pinned` nodes (the
/// boundary of an open net, whose centroid lies inside the net) stay.
fn relax_step(
    net: &QuadNet,
    normals: &[Vector3<f64>],
    pinned: &[bool],
    step: f64,
) -> Vec<Point3<f64>> {
    (0..net.nodes.len())
        .into_par_iter()
        .map(|i| {
            let p = net.nodes[i];
            if pinned[i] {
                return p;
            }
            let n = normals[i];
            let unroll = |k: u32| {
                let q = net.nodes[k as usize];
                log_map(&p, &n, &q, &normals[k as usize]).unwrap_or_else(|| {
                    let d = q - p;
                    d - n * n.dot(&d)
                })
            };
            let mut cen = Vector3::zeros();
            let mut area = 0.0;
            let quads = net.node_quads(i);
            for &q in quads {
                let quad = net.quads[q as usize];
                let c = net.corner_of(q as usize, i as u32).unwrap_or(0);
                let (t1, t2, t3) = (
                    unroll(quad[(c + 1) % 4]),
                    unroll(quad[(c + 2) % 4]),
                    unroll(quad[(c + 3) % 4]),
                );
                let a = 0.5 * t2.cross(&(t3 - t1)).norm();
                cen += (t1 + t2 + t3) * (0.25 * a);
                area += a;
            }
            if area <= 0.0 || quads.is_empty() {
                return p;
            }
            let d = cen / area;
            p + (d - n * n.dot(&d)) * step
        })
        .collect()
}

/// Moves the nodes to `new`, except those whose move folds (flips or degenerates) a quad that
/// was fine before: they keep their old positions and normals.
fn keep_unfolded<I: Implicit + ?Sized>(
    net: &mut QuadNet,
    new: Vec<Point3<f64>>,
    new_n: Vec<Vector3<f64>>,
    old: &State,
    f: &I,
    opt: &SmoothOptions,
) -> State {
    let bad = |nodes: &[Point3<f64>], normals: &[Vector3<f64>], q: &[u32; 4], qi: usize| {
        let s = quad_shape(&q.map(|i| nodes[i as usize]), &normals[qi]);
        s.flipped || s.degenerate
    };
    let was_bad: Vec<bool> = net
        .quads
        .par_iter()
        .enumerate()
        .map(|(qi, q)| bad(&net.nodes, &old.quad_n, q, qi))
        .collect();
    let old_nodes = std::mem::replace(&mut net.nodes, new);
    let mut state = State::new(net, f, new_n, opt);
    for _ in 0..8 {
        let revert: Vec<usize> = net
            .quads
            .par_iter()
            .enumerate()
            .filter(|(qi, q)| !was_bad[*qi] && bad(&net.nodes, &state.quad_n, q, *qi))
            .map(|(qi, _)| qi)
            .collect();
        if revert.is_empty() {
            break;
        }
        let mut node_n = state.node_n;
        for qi in revert {
            for &i in &net.quads[qi] {
                net.nodes[i as usize] = old_nodes[i as usize];
                node_n[i as usize] = old.node_n[i as usize];
            }
        }
        state = State::new(net, f, node_n, opt);
    }
    state
}

#[cfg(test)]
mod tests {
    use super::super::test_shapes::*;
    use super::super::voxel_net::{build_voxel_net, VoxelNetOptions};
    use super::*;
    use crate::mesh::Aabb;

    fn smoothed<I: Implicit>(
        f: &I,
        seeds: &[Point3<f64>],
        b: &Aabb,
        h: f64,
    ) -> (QuadNet, SmoothReport) {
        let mut v = build_voxel_net(f, seeds, b, &VoxelNetOptions::new(h)).unwrap();
        let rep = project_and_smooth(&mut v.net, f, &SmoothOptions::new(b.diagonal(), h)).unwrap();
        (v.net, rep)
    }

    fn check<I: Implicit>(name: &str, f: &I, net: &QuadNet, rep: &SmoothReport, scale: f64) {
        eprintln!(
            "{name}: {} quads, projected min/mean {:.1}/{:.1} flipped {} degenerate {}; \
             smoothed ({} it) min/mean {:.1}/{:.1} mean |a-90| {:.1} flipped {} degenerate {} residual {:.1e}",
            net.quads.len(),
            rep.projected.min_angle_deg,
            rep.projected.mean_angle_deg,
            rep.projected.flipped,
            rep.projected.degenerate,
            rep.iterations,
            rep.smoothed.min_angle_deg,
            rep.smoothed.mean_angle_deg,
            rep.smoothed.mean_deviation_deg,
            rep.smoothed.flipped,
            rep.smoothed.degenerate,
            rep.smoothed.max_residual,
        );
        assert_eq!(rep.smoothed.flipped, 0, "{name}");
        assert_eq!(rep.smoothed.degenerate, 0, "{name}");
        for p in &net.nodes {
            let (v, g) = f.value_and_gradient(p);
            assert!(
                v.abs() / g.norm() <= 1e-9 * scale,
                "{name}: node off the surface"
            );
        }
    }

    #[test]
    fn sphere_and_torus_smooth_to_good_quads() {
        let s = Sphere {
            c: Point3::new(0.02, 0.01, -0.03),
            r: 1.0,
        };
        let b = aabb([-1.0; 3], [1.0; 3]);
        let (net, rep) = smoothed(&s, &seeds_on(&s, s.c, 1.2, 10), &b, 0.12);
        check("sphere", &s, &net, &rep, b.diagonal());
        assert!(rep.smoothed.min_angle_deg > 45.0);
        let t = Torus {
            big: 1.0,
            small: 0.35,
        };
        let b = aabb([-1.35, -1.35, -0.35], [1.35, 1.35, 0.35]);
        let (net, rep) = smoothed(&t, &seeds_on(&t, Point3::origin(), 1.4, 40), &b, 0.1);
        check("torus", &t, &net, &rep, b.diagonal());
        assert_eq!(net.euler_characteristic(), 0);
        assert!(rep.smoothed.min_angle_deg > 45.0);
    }

    /// Smallest angle at a quad corner in the unrolled neighbourhood of its node
    /// ([`super::super::log_map::unrolled_angle`]): the angle between the patch's corner
    /// tangents, whatever the chords do in space.
    fn min_unrolled_angle<I: Implicit>(f: &I, net: &QuadNet) -> f64 {
        let n = |i: u32| f.gradient(&net.nodes[i as usize]).normalize();
        let mut worst = f64::INFINITY;
        for q in &net.quads {
            for k in 0..4 {
                let (a, b, c) = (q[k], q[(k + 1) % 4], q[(k + 3) % 4]);
                let na = n(a);
                let (nb, nc) = (n(b), n(c));
                let p = |i: u32| &net.nodes[i as usize];
                if let Some(ang) =
                    super::super::log_map::unrolled_angle((p(a), &na), (p(b), &nb), (p(c), &nc))
                {
                    worst = worst.min(ang);
                }
            }
        }
        worst
    }

    /// Boxes whose edges are rounded well below the voxel size: nets wrap the creases, and
    /// relaxing in the unrolled neighbourhoods keeps every patch corner open.
    #[test]
    fn nets_over_tight_creases_keep_open_corners() {
        let b = aabb([-1.0; 3], [1.0; 3]);
        for (name, r) in [("r = 0.2 h", 0.02), ("r = 0.5 h", 0.05)] {
            let f = RoundedBox {
                b: Vector3::new(0.55, 0.4, 0.33),
                r,
            };
            let (net, rep) = smoothed(&f, &seeds_on(&f, Point3::origin(), 0.8, 60), &b, 0.1);
            check(name, &f, &net, &rep, b.diagonal());
            let a = min_unrolled_angle(&f, &net);
            // Measured 73.6 and 64.3 degrees; the centroid of the chords' shadows on the
            // tangent planes (the rule before the unrolling) gave 78.3 and 44.7.
            assert!(a > 55.0, "{name}: smallest unrolled corner angle {a:.1}");
        }
    }

    #[test]
    fn hard_shapes_smooth_without_folds() {
        let h = 0.1;
        // Two spheres a quarter voxel apart.
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
        let b = aabb([-1.2; 3], [1.2; 3]);
        let (net, rep) = smoothed(&u, &seeds, &b, h);
        check("two spheres", &u, &net, &rep, b.diagonal());
        // Dumbbell with a neck of radius 0.06 (0.6 h).
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
        let (net, rep) = smoothed(&db, &seeds_on(&db, Point3::origin(), 1.0, 60), &b, h);
        check("dumbbell", &db, &net, &rep, b.diagonal());
        // Rounded cube as a smooth max of its planes.
        let c = SoftCube { a: 0.6, k: 0.04 };
        let (net, rep) = smoothed(&c, &seeds_on(&c, Point3::origin(), 0.8, 30), &b, h);
        check("soft cube", &c, &net, &rep, b.diagonal());
        // Thin plate 0.06 thick.
        let slab = RoundedBox {
            b: Vector3::new(0.6, 0.45, 0.0),
            r: 0.03,
        };
        let (net, rep) = smoothed(&slab, &seeds_on(&slab, Point3::origin(), 0.7, 60), &b, h);
        check("thin slab", &slab, &net, &rep, b.diagonal());
        // Bumpy blob, bumps about 1.5 h wide.
        let blob = Blob {
            r: 0.8,
            amp: 0.04,
            w: 20.0,
        };
        let (net, rep) = smoothed(&blob, &seeds_on(&blob, Point3::origin(), 0.9, 60), &b, h);
        check("blob", &blob, &net, &rep, b.diagonal());
    }
}
