//! Parts of the data the open net misses, fitted by finer nets of their own (`--close open`).
//!
//! The voxel net has one voxel size h. Where the data are a one-sided part thinner than a
//! few voxels (a cow's leg seen from the side: a half-tube about 1.5 h across; an ear; a
//! tail), the net at h wraps the part's implicit as a blob or not at all, the cut to the data
//! keeps nothing of it, and its points are left uncovered ([`super::coverage`]); halving h
//! everywhere would quadruple the patches of the whole model for a few per cent of its area.
//! The same holds where the net reaches a thin part but follows it as a blob (a car's
//! mirror: few points half a voxel from the quads, 1 % a sixth of a voxel off the trial
//! patches); [`crate::fit::net::fit_open_net`] calls [`fit_pieces`] in both cases, which fits
//! those parts alone, each with a finer voxel net:
//!
//! 1. **Missed points.** The input points farther than [`PIECE_DISTANCE`] h from the net's
//!    quads.
//! 2. **Clusters.** Missed points closer than [`LINK`] h are linked (single linkage, a union
//!    of the pairs found by a radius search); clusters with fewer than [`MIN_PIECE_POINTS`]
//!    points are left (they do not move the deviation's 99th percentile; the report counts
//!    them).
//! 3. **A piece per cluster.** For h_k = h / k, k = 2, 3, 4, 6 ([`REFINEMENTS`]), the voxel net
//!    of f = 0 in the cluster's box (seeded by its points) is cut to the quads the cluster's
//!    points support ([`super::trim`]), projected and smoothed, and carried to the edge of
//!    the cluster's data ([`super::rim`]), exactly as the main net is against all the data.
//!    The first h_k whose piece leaves at most [`PIECE_MISS`] of the cluster's points farther
//!    than `PIECE_DISTANCE` h_k from it is kept, else the piece that misses the fewest, if it
//!    misses at most [`MAX_PIECE_MISS`] of them.
//!
//! The pieces join the net as components of their own: the cluster's points are those the
//! main net does not reach, so a piece begins where the main net's rim ends, with a seam about
//! half a voxel wide that is not sewn (the shell is open anyway; the report gives the pieces).

use super::coverage::missed_points;
use super::{fit_rim, net_support, trim_to_data};
use crate::implicit::Implicit;
use crate::mesh::Aabb;
use crate::polygonize::net_quality::folded_quads;
use crate::polygonize::net_smooth::{project_and_smooth, SmoothOptions};
use crate::polygonize::voxel_net::{build_voxel_net, VoxelNetOptions};
use crate::polygonize::QuadNet;
use crate::spatial::KdTree;
use crate::Result;
use nalgebra::Point3;
use rayon::prelude::*;

/// Distance from the net, in voxels, beyond which a point is missed here: half of the
/// coverage's [`super::coverage::MISS_DISTANCE`], since a point a third of a voxel from the quads is covered
/// but not followed (the net wraps a thin tail as a blob that far from its points).
pub const PIECE_DISTANCE: f64 = 0.25;
/// Missed points closer than this many voxels h belong to one cluster.
pub const LINK: f64 = 0.5;
/// Fewest points of a cluster that gets a piece.
pub const MIN_PIECE_POINTS: usize = 12;
/// Voxel refinements tried for a piece: h / k.
pub const REFINEMENTS: [f64; 4] = [2.0, 3.0, 4.0, 6.0];
/// Largest share of its cluster's points a piece may miss and be kept at once.
pub const PIECE_MISS: f64 = 0.05;
/// Largest share of its cluster's points a piece may miss and be kept at all: a piece that
/// cannot follow most of its points spans them badly (a 23-point crescent of the stepped
/// shaft at `--patches 1500` got a 9-patch piece missing 61 % of them, folded 180 degrees).
pub const MAX_PIECE_MISS: f64 = 0.5;
/// Clusters fitted at most (the largest).
pub const MAX_PIECES: usize = 64;
/// Voxels evaluated at most for one piece.
const MAX_PIECE_VOXELS: usize = 2_000_000;

/// One piece fitted (the report's `close.coverage.pieces.pieces`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PieceReport {
    /// Points of the cluster.
    pub points: usize,
    /// Centre of the cluster's box.
    pub center: [f64; 3],
    /// Voxel edge of the piece's net.
    pub h: f64,
    pub patches: usize,
    /// Share of the cluster's points the piece still misses.
    pub missed_share: f64,
    /// Flipped or degenerate quads of the piece's net after smoothing (cut out).
    pub folded_quads: usize,
}

/// What [`fit_pieces`] found and did (the report's `close.coverage.pieces`).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct PiecesReport {
    /// Input points the main net misses.
    pub missed_points: usize,
    /// Clusters of them, and those too small for a piece (with their points).
    pub clusters: usize,
    pub small_clusters: usize,
    pub small_cluster_points: usize,
    /// The pieces added.
    pub pieces: Vec<PieceReport>,
    /// Clusters for which no piece could be made (no net, or it missed more than
    /// [`MAX_PIECE_MISS`] of their points).
    pub failed: usize,
    /// Input points no net reaches after the pieces were added.
    pub still_missed_points: usize,
}

/// Single-linkage clusters of `pts` at distance `link`: lists of indices into `pts`, largest
/// first (ties by first index, so the order is deterministic).
fn clusters(pts: &[Point3<f64>], link: f64) -> Vec<Vec<usize>> {
    let Ok(tree) = KdTree::build(pts) else {
        return Vec::new();
    };
    // Union-find with path halving.
    let mut parent: Vec<usize> = (0..pts.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let near: Vec<Vec<usize>> = pts.par_iter().map(|p| tree.within(p, link)).collect();
    for (i, js) in near.iter().enumerate() {
        for &j in js {
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut by_root: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for i in 0..pts.len() {
        let r = root(&mut parent, i);
        by_root.entry(r).or_default().push(i);
    }
    let mut out: Vec<Vec<usize>> = by_root.into_values().collect();
    out.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
    out
}

/// The finer open net of the implicit `f` over the points `cluster` (indexed by `data`,
/// boxed by `bounds`; voxel edge `hk`): cut to them, projected, smoothed and carried to their
/// edge; with the share of them it misses and the folded quads cut from it.
fn piece_net<I: Implicit + ?Sized>(
    f: &I,
    cluster: &[Point3<f64>],
    data: &KdTree,
    bounds: &Aabb,
    hk: f64,
    spacing: f64,
    scale: f64,
) -> Result<(QuadNet, f64, usize)> {
    let mut opt = VoxelNetOptions::new(hk);
    opt.max_voxels = MAX_PIECE_VOXELS;
    let voxel = build_voxel_net(f, cluster, bounds, &opt)?;
    let (support, _) = net_support(&voxel.net, data, hk);
    let (mut net, _) = trim_to_data(&voxel.net, &support)?;
    let smooth = SmoothOptions::new(scale, hk);
    project_and_smooth(&mut net, f, &smooth)?;
    let (net, _, _) = fit_rim(&net, f, data, hk, spacing, &smooth)?;
    // Folded quads (where the piece's net crosses a part still too thin for it) are cut out.
    let folded = folded_quads(&net, f, scale, hk);
    let folds = folded.iter().filter(|&&b| b).count();
    let net = if folds > 0 {
        let keep: Vec<bool> = folded.iter().map(|&b| !b).collect();
        trim_to_data(&net, &keep)?.0
    } else {
        net
    };
    let missed =
        missed_points(&net, cluster, PIECE_DISTANCE * hk).len() as f64 / cluster.len() as f64;
    Ok((net, missed, folds))
}

/// Appends the quads of `piece` to the node and quad lists of a net.
fn append(nodes: &mut Vec<Point3<f64>>, quads: &mut Vec<[u32; 4]>, piece: &QuadNet) {
    let base = nodes.len() as u32;
    nodes.extend_from_slice(&piece.nodes);
    quads.extend(piece.quads.iter().map(|q| q.map(|k| k + base)));
}

/// The open `net` (voxel edge `h`) with finer pieces for the clusters of `points` it misses
/// (module doc); `spacing` is the points' spacing, `scale` the model's diagonal. The net is
/// returned unchanged (with the report) when there is nothing to add. Errors: the merged net
/// is not a valid open quad net (the pieces are separate components, so this would be a bug).
pub fn fit_pieces<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    points: &[Point3<f64>],
    h: f64,
    spacing: f64,
    scale: f64,
) -> Result<(QuadNet, PiecesReport)> {
    let missed = missed_points(net, points, PIECE_DISTANCE * h);
    let mut rep = PiecesReport {
        missed_points: missed.len(),
        ..Default::default()
    };
    let missed_pts: Vec<Point3<f64>> = missed.iter().map(|&i| points[i]).collect();
    let groups = clusters(&missed_pts, LINK * h);
    rep.clusters = groups.len();
    let (big, small): (Vec<_>, Vec<_>) = groups
        .into_iter()
        .partition(|g| g.len() >= MIN_PIECE_POINTS);
    rep.small_clusters = small.len();
    rep.small_cluster_points = small.iter().map(Vec::len).sum();
    let fitted: Vec<Option<(QuadNet, PieceReport)>> = big
        .par_iter()
        .take(MAX_PIECES)
        .map(|g| {
            let cluster: Vec<Point3<f64>> = g.iter().map(|&i| missed_pts[i]).collect();
            let data = KdTree::build(&cluster).ok()?;
            let b = Aabb::of(&cluster)?;
            let mut best: Option<(QuadNet, f64, f64, usize)> = None;
            for k in REFINEMENTS {
                let hk = h / k;
                let Ok((piece, miss, folds)) =
                    piece_net(f, &cluster, &data, &b, hk, spacing, scale)
                else {
                    continue;
                };
                if best.as_ref().is_none_or(|b| miss < b.1) {
                    best = Some((piece, miss, hk, folds));
                }
                if miss <= PIECE_MISS {
                    break;
                }
            }
            let (piece, miss, hk, folds) = best.filter(|b| b.1 <= MAX_PIECE_MISS)?;
            let c = nalgebra::center(&b.min, &b.max);
            let report = PieceReport {
                points: cluster.len(),
                center: [c.x, c.y, c.z],
                h: hk,
                patches: piece.quads.len(),
                missed_share: miss,
                folded_quads: folds,
            };
            Some((piece, report))
        })
        .collect();
    rep.failed = big.len() - fitted.iter().flatten().count();
    if fitted.iter().all(Option::is_none) {
        rep.still_missed_points = missed.len();
        return Ok((net.clone(), rep));
    }
    let (mut nodes, mut quads) = (net.nodes.clone(), net.quads.clone());
    for (piece, report) in fitted.into_iter().flatten() {
        append(&mut nodes, &mut quads, &piece);
        rep.pieces.push(report);
    }
    let merged = QuadNet::new_open(nodes, quads)?;
    rep.still_missed_points = missed_points(&merged, &missed_pts, PIECE_DISTANCE * h).len();
    Ok((merged, rep))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::test_shapes::{Capsule, Sphere, Union};
    use crate::polygonize::voxel_net::build_voxel_net;

    #[test]
    fn clusters_are_linked_within_the_distance_and_largest_first() {
        let mut pts: Vec<Point3<f64>> = (0..5)
            .map(|i| Point3::new(i as f64 * 0.1, 0.0, 0.0))
            .collect();
        pts.extend((0..8).map(|i| Point3::new(5.0, i as f64 * 0.1, 0.0)));
        pts.push(Point3::new(-3.0, 0.0, 0.0));
        let c = clusters(&pts, 0.15);
        assert_eq!(c.len(), 3);
        assert_eq!(c[0], (5..13).collect::<Vec<_>>());
        assert_eq!(c[1], (0..5).collect::<Vec<_>>());
        assert_eq!(c[2], vec![13]);
        // A gap wider than the link splits the row.
        assert_eq!(clusters(&pts[..5], 0.05).len(), 5);
        assert!(clusters(&[], 1.0).is_empty());
    }

    /// The front halves (z > 0) of a ball and of a leg 0.24 thick hanging below it, a tenth of
    /// a voxel apart: the ball's net leaves the leg; a piece covers it.
    #[test]
    fn a_thin_one_sided_leg_the_net_misses_gets_a_piece() {
        let ball = Sphere {
            c: Point3::origin(),
            r: 1.0,
        };
        let leg = Capsule {
            a: Point3::new(0.0, -0.9, 0.0),
            b: Point3::new(0.0, -2.2, 0.0),
            r: 0.12,
        };
        let f = Union(ball, leg);
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let n = 4000;
        let mut body: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let rho = (1.0 - z * z).sqrt();
                let t = golden * i as f64;
                Point3::new(rho * t.cos(), rho * t.sin(), z)
            })
            .filter(|p| p.z > 0.0 && p.y > -0.95)
            .collect();
        let mut limb = Vec::new();
        for i in 0..60 {
            for j in 0..12 {
                let y = -1.05 - 1.1 * i as f64 / 59.0;
                let a = std::f64::consts::PI * (j as f64 + 0.5) / 12.0;
                limb.push(Point3::new(0.12 * a.cos(), y, 0.12 * a.sin()));
            }
        }
        let h = 0.25;
        let bounds = crate::polygonize::test_shapes::aabb([-1.2, -2.5, -1.2], [1.2, 1.2, 1.2]);
        let voxel = build_voxel_net(&f, &body, &bounds, &VoxelNetOptions::new(h)).unwrap();
        let data = KdTree::build(&body).unwrap();
        let (support, _) = net_support(&voxel.net, &data, h);
        let (mut net, _) = trim_to_data(&voxel.net, &support).unwrap();
        project_and_smooth(&mut net, &f, &SmoothOptions::new(3.0, h)).unwrap();
        let limb_missed = missed_points(&net, &limb, PIECE_DISTANCE * h).len();
        assert!(limb_missed > limb.len() / 2, "{limb_missed}");
        body.extend_from_slice(&limb);
        let (merged, rep) = fit_pieces(&net, &f, &body, h, 0.03, 3.0).unwrap();
        assert!(!rep.pieces.is_empty(), "{rep:?}");
        assert!(
            rep.pieces[0].h < h && rep.pieces[0].center[1] < -1.0,
            "{rep:?}"
        );
        assert!(merged.quads.len() > net.quads.len() && merged.is_open());
        let still = missed_points(&merged, &limb, PIECE_DISTANCE * h).len();
        assert!(
            still * 10 < limb.len(),
            "{still} of {} leg points still missed: {rep:?}",
            limb.len()
        );
        assert_eq!(
            rep.still_missed_points,
            missed_points(&merged, &body, PIECE_DISTANCE * h).len()
        );
        // Nothing missed: the net comes back as it was.
        let (same, none) = fit_pieces(&merged, &f, &limb, h, 0.03, 3.0).unwrap();
        assert_eq!(same.quads.len(), merged.quads.len());
        assert!(none.pieces.is_empty());
    }
}
