//! The rim of an open net, at the edge of the data and smooth (`--close open`).
//!
//! [`super::trim`] cuts the voxel net before projection, with a loose test (a node within a
//! voxel of a point), so its boundary is a voxel staircase that may run up to a voxel past the
//! data's edge, where the implicit only extrapolates. [`fit_rim`] then, on the projected net:
//!
//! 1. **Recut.** Every node now lies on f = 0; a quad is kept when its four nodes have an input
//!    point within min(2 r_e, 0.35 h), r_e the edge radius below, but at least 1.25 point
//!    spacings (cleaned as in [`super::trim`]). The staircase now lies inside the data.
//! 2. **Strip.** From every boundary node b_i (loops walked with the net on their left, seen
//!    from outside) a path on the surface runs outward, along o_i = the mean of the adjacent
//!    boundary edges' outward directions e x N in the tangent plane, in steps of h / 16, each
//!    step projected back onto f = 0, while an input point lies within r_e = max(1.5 s, h / 16)
//!    of it (s the points' spacing): its end c_i is its last point on the data, at least
//!    [`MIN_STRIP`] h and at most [`MAX_STRIP`] h from b_i. The ends are smoothed along their
//!    loop (three sweeps of c_i <- (c_{i-1} + 2 c_i + c_{i+1}) / 4, projected onto f = 0; a
//!    move that would leave the data is not made: smoothing cuts a concave bay's chord across
//!    the unscanned side, measured 0.26 -> 1.1 % of the front half of the bunny's area past 1 %
//!    of the diagonal), and
//!    every boundary edge b_i b_{i+1} gets the quad [b_{i+1}, b_i, c_i, c_{i+1}] (its outward
//!    normal (b_i - b_{i+1}) x (c_{i+1} - b_{i+1}) is along N). The staircase becomes interior
//!    (a convex step's node gets two quads of about 135 degrees, a concave one two of about
//!    45) and the boundary is the smoothed curve of the data's edge.
//! 3. The net is projected and relaxed again with the new boundary pinned, so the staircase's
//!    nodes spread out between the data's edge and the interior.

use super::trim::trim_to_data;
use super::TrimReport;
use crate::implicit::Implicit;
use crate::polygonize::net_smooth::{project_and_smooth, SmoothOptions, SmoothReport};
use crate::polygonize::newton::{project, NewtonOptions};
use crate::polygonize::QuadNet;
use crate::spatial::KdTree;
use crate::Result;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// A projected node is on the data when an input point lies within this many edge radii r_e
/// (so the staircase lies inside the data and the strip reaches out to their edge), at most
/// [`RECUT_RADIUS`] voxels, but at least [`RECUT_SPACINGS`] point spacings: where the points
/// are sparser than the patches (spot's 1,947 upper vertices as a cloud, 1,500 patches) a
/// third of a voxel is less than the gaps between the points and dropped 85 % of the net;
/// without the cap in voxels, the front half of the bunny (a point every third of a voxel)
/// kept a staircase 2 % of the diagonal past its edge.
pub const RECUT_EDGES: f64 = 2.0;
pub const RECUT_RADIUS: f64 = 0.35;
pub const RECUT_SPACINGS: f64 = 1.25;
/// Shortest and longest strip, in voxels.
pub const MIN_STRIP: f64 = 0.25;
pub const MAX_STRIP: f64 = 1.5;
/// The data's edge radius r_e, in point spacings: a surface point farther than r_e from every
/// input point is past the edge.
pub const EDGE_SPACINGS: f64 = 1.5;
/// Steps per voxel of the walk to the data's edge.
const STEPS_PER_VOXEL: f64 = 16.0;
/// Smoothing sweeps along each boundary loop.
const LOOP_SWEEPS: usize = 3;

/// What [`fit_rim`] did (the report's `close.rim`).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RimReport {
    /// The recut of the projected net.
    pub recut: TrimReport,
    /// Quads of the strip to the data's edge (one per boundary edge).
    pub strip_quads: usize,
    /// Distance walked from the staircase to the data's edge (or to the end of the walk), in
    /// voxels: mean and max.
    pub walk_mean: f64,
    pub walk_max: f64,
    /// Strip ends clamped to MIN_STRIP (data's edge nearer) or MAX_STRIP (no edge within it).
    pub clamped_short: usize,
    pub clamped_long: usize,
    /// The data's edge radius r_e used (model units).
    pub edge_radius: f64,
}

/// Recut, strip and relax (module doc) the projected open `net` of voxel edge `h`.
/// `spacing` is the input points' spacing. Errors: the recut leaves nothing, or the net
/// cannot be projected again.
pub fn fit_rim<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    data: &KdTree,
    h: f64,
    spacing: f64,
    smooth: &SmoothOptions,
) -> Result<(QuadNet, SmoothReport, RimReport)> {
    let edge_radius = (EDGE_SPACINGS * spacing).max(h / STEPS_PER_VOXEL);
    let recut_radius = (RECUT_EDGES * edge_radius)
        .min(RECUT_RADIUS * h)
        .max(RECUT_SPACINGS * spacing);
    let keep = super::decide::quads_near_data(net, data, recut_radius);
    let (cut, recut) = trim_to_data(net, &keep)?;
    let (nodes, quads, walk) = strip(&cut, f, data, h, edge_radius);
    let mut out = QuadNet::new_open(nodes, quads)?;
    let smoothing = project_and_smooth(&mut out, f, smooth)?;
    let report = RimReport {
        recut,
        strip_quads: out.quads.len() - cut.quads.len(),
        edge_radius,
        ..walk
    };
    Ok((out, smoothing, report))
}

/// Where a walk to the data's edge ended.
#[derive(Debug, Clone, Copy, PartialEq)]
enum End {
    /// At the data's edge, this far from the start.
    Edge(f64),
    /// The edge was nearer than MIN_STRIP h (at this distance): the end is MIN_STRIP h out.
    Short(f64),
    /// No edge within MAX_STRIP h (or the surface ended): the end is where the walk stopped.
    Long(f64),
}

/// The walk from `b` along the surface in direction `dir` while the data last: the end point
/// (clamped to [MIN_STRIP, MAX_STRIP] h) and how it ended.
fn walk_to_edge<I: Implicit + ?Sized>(
    f: &I,
    data: &KdTree,
    b: Point3<f64>,
    dir: Vector3<f64>,
    h: f64,
    edge_radius: f64,
    newton: &NewtonOptions,
) -> (Point3<f64>, End) {
    let step = h / STEPS_PER_VOXEL;
    let (mut x, mut d) = (b, dir);
    let mut walked = 0.0;
    let mut end: Option<(Point3<f64>, f64)> = None;
    let mut min_point = b;
    while walked < MAX_STRIP * h {
        let last = (x, walked);
        let Ok((y, g)) = project(f, x + d * step, newton) else {
            break;
        };
        let n = g.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
        let moved = y - x;
        walked += moved.norm();
        // Keep walking in the tangent plane, in the direction just taken.
        d = (moved - n * n.dot(&moved)).try_normalize(0.0).unwrap_or(d);
        x = y;
        if walked <= MIN_STRIP * h {
            min_point = x;
        }
        if end.is_none() && data.nearest(&x).1 > edge_radius {
            // The last point of the walk still on the data.
            end = Some(last);
            if walked >= MIN_STRIP * h {
                break;
            }
        }
    }
    match end {
        Some((p, w)) if w >= MIN_STRIP * h => (p, End::Edge(w)),
        Some((_, w)) => (min_point, End::Short(w)),
        None => (x, End::Long(walked)),
    }
}

type Strip = (Vec<Point3<f64>>, Vec<[u32; 4]>, RimReport);

/// The strip of quads from every boundary loop of `net` to the data's edge (module doc, 2).
fn strip<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    data: &KdTree,
    h: f64,
    edge_radius: f64,
) -> Strip {
    let newton = NewtonOptions::new(h * 1e3, 0.5 * h);
    let mut nodes = net.nodes.clone();
    let mut quads = net.quads.clone();
    let mut rep = RimReport::default();
    let mut walks = Vec::new();
    for lp in net.boundary_loops() {
        let m = lp.len();
        if m < 3 {
            continue;
        }
        let p = |i: usize| net.nodes[lp[i % m] as usize];
        let ends: Vec<(Point3<f64>, End)> = (0..m)
            .into_par_iter()
            .map(|i| {
                let b = p(i);
                let nrm = f.gradient(&b).try_normalize(0.0).unwrap_or_else(Vector3::z);
                let out = |e: Vector3<f64>| e.cross(&nrm).try_normalize(0.0);
                let dir = match (out(b - p(i + m - 1)), out(p(i + 1) - b)) {
                    (Some(a), Some(c)) => (a + c).try_normalize(0.0).unwrap_or(a),
                    (Some(a), None) | (None, Some(a)) => a,
                    (None, None) => return (b, End::Short(0.0)),
                };
                walk_to_edge(f, data, b, dir, h, edge_radius, &newton)
            })
            .collect();
        let mut c: Vec<Point3<f64>> = ends.iter().map(|e| e.0).collect();
        for &(_, e) in &ends {
            walks.push(match e {
                End::Edge(w) => w,
                End::Short(w) => {
                    rep.clamped_short += 1;
                    w
                }
                End::Long(w) => {
                    rep.clamped_long += 1;
                    w
                }
            });
        }
        for _ in 0..LOOP_SWEEPS {
            c = (0..m)
                .into_par_iter()
                .map(|i| {
                    let avg =
                        (c[(i + m - 1) % m].coords + 2.0 * c[i].coords + c[(i + 1) % m].coords)
                            / 4.0;
                    // Only along or into the data: a move that takes an end farther from
                    // the data than the edge radius and than it was is not made.
                    match project(f, Point3::from(avg), &newton) {
                        Ok((q, _))
                            if data.nearest(&q).1 <= edge_radius.max(data.nearest(&c[i]).1) =>
                        {
                            q
                        }
                        _ => c[i],
                    }
                })
                .collect();
        }
        let base = nodes.len() as u32;
        nodes.extend(c);
        for i in 0..m {
            let j = (i + 1) % m;
            quads.push([lp[j], lp[i], base + i as u32, base + j as u32]);
        }
    }
    if !walks.is_empty() {
        rep.walk_mean = walks.iter().sum::<f64>() / walks.len() as f64 / h;
        rep.walk_max = walks.iter().fold(0.0f64, |a, &b| a.max(b)) / h;
    }
    (nodes, quads, rep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::openings::{net_support, trim_to_data};
    use crate::polygonize::test_shapes::*;
    use crate::polygonize::voxel_net::{build_voxel_net, VoxelNetOptions};

    /// The upper half of a sphere sampled densely: the rim ends on the equator, where the data
    /// stop, smoothly (no staircase), with no folded quad.
    #[test]
    fn hemisphere_rim_lies_on_the_data_edge() {
        let s = Sphere {
            c: Point3::new(0.013, -0.021, 0.0),
            r: 1.0,
        };
        let all = seeds_on(&s, s.c, 1.2, 40_000);
        let data: Vec<Point3<f64>> = all.iter().copied().filter(|p| p.z > 0.0).collect();
        let tree = KdTree::build(&data).unwrap();
        let b = crate::mesh::Aabb {
            min: Point3::new(-1.2, -1.2, -1.2),
            max: Point3::new(1.2, 1.2, 1.2),
        };
        let h = 0.15;
        let v = build_voxel_net(&s, &data, &b, &VoxelNetOptions::new(h)).unwrap();
        let (support, share) = net_support(&v.net, &tree, h);
        assert!(share > 0.3 && share < 0.7, "{share}");
        let (mut net, _) = trim_to_data(&v.net, &support).unwrap();
        let opts = SmoothOptions::new(b.diagonal(), h);
        project_and_smooth(&mut net, &s, &opts).unwrap();
        let spacing = crate::reconstruct::mean_spacing(&data, &tree);
        let (out, smooth, rep) = fit_rim(&net, &s, &tree, h, spacing, &opts).unwrap();
        assert!(out.is_open());
        assert_eq!(out.boundary_loops().len(), 1);
        assert_eq!(
            smooth.smoothed.flipped + smooth.smoothed.degenerate,
            0,
            "{smooth:?}"
        );
        assert!(rep.strip_quads > 20, "{rep:?}");
        // The boundary runs along the equator: within the edge radius plus a walk step below
        // the data's last row, never above a quarter voxel (the staircase was up to a voxel).
        let lp = &out.boundary_loops()[0];
        let z: Vec<f64> = lp.iter().map(|&i| out.nodes[i as usize].z).collect();
        let (lo, hi) = z
            .iter()
            .fold((f64::MAX, f64::MIN), |a, &x| (a.0.min(x), a.1.max(x)));
        assert!(lo > -0.05 && hi < 0.25 * h, "boundary z in [{lo}, {hi}]");
        // Smooth: consecutive boundary edges turn by little in the tangent plane.
        let m = lp.len();
        let p = |i: usize| out.nodes[lp[i % m] as usize];
        let turns: Vec<f64> = (0..m)
            .map(|i| {
                let (a, c) = (
                    (p(i + 1) - p(i)).normalize(),
                    (p(i + 2) - p(i + 1)).normalize(),
                );
                a.dot(&c).clamp(-1.0, 1.0).acos().to_degrees()
            })
            .collect();
        let worst = turns.iter().copied().fold(0.0f64, f64::max);
        assert!(
            worst < 45.0,
            "boundary turns by {worst} degrees: {turns:?}, {rep:?}"
        );
        // Every node is on the sphere.
        assert!(out
            .nodes
            .iter()
            .all(|q| ((q - s.c).norm() - 1.0).abs() < 1e-9));
    }
}
