//! How much of the data an open net covers, and the patch size that covers it (`--close open`).
//!
//! The voxel net follows the implicit's zero set only where the inside and outside voxels
//! around it are consistent. On a partial scan that fails for data thinner than a few voxels
//! that hang beyond the scanned body: the lower halves of a horizontal shaft's shoulders seen
//! from above are one-sided crescents one or two voxels wide, past which the implicit only
//! extrapolates. The closed net wraps such parts as blobs, the cut to the data keeps none of
//! them, and their points are left uncovered (stepped shaft at 1,500 patches: input deviation
//! p99 8.6e-2 of the diagonal). With smaller voxels they are followed (3,000 patches: 2.5e-4).
//!
//! **Coverage.** An input point x is *missed* when the net's quads (each split into two
//! triangles) all lie farther than r = [`MISS_DISTANCE`] h from it. The quads searched are those
//! around the [`NODES_SEARCHED`] nodes nearest to x: a point the net covers lies within a voxel
//! of the nodes of its quad. Where the net follows the surface its projected nodes lie on
//! f = 0 and a quad departs from the surface by its sagitta, h^2 / (8 R) for a radius of
//! curvature R, an eighth of a voxel where R = h; so the missed points are those of parts the
//! net does not reach. The missed share is measured on at most [`SAMPLE`] points, evenly spread
//! through the input order.
//!
//! **Far area.** A net that folds through a part it cannot resolve (a hole a few voxels wide
//! where it cuts a crease) covers the points but spans the gap: the quick trial patches that
//! rank the grid placements then have area farther than 1 % of the diagonal from the data
//! ([`crate::fit::net::TrialScore::far_share`], the report's `support_far` on those patches).
//!
//! **Refinement** ([`crate::fit::net::fit_open_net`]). When `fit` chose the patch count itself
//! (no `--patches` or `--patch-size`) and the open net misses more than [`MISS_SHARE`] of the
//! points or its trial patches have more than [`FAR_SHARE`] of their area far from the data,
//! the net is built again with twice the patches (voxels 1/sqrt 2 the size), at most
//! [`MAX_DOUBLINGS`] times and only with [`MIN_POINTS_PER_PATCH`] points per patch; the first
//! net that passes is kept, or else the one that misses the fewest points. With a size given,
//! the report says what is wrong and which `--patches` would make a finer net.

use super::pieces::PiecesReport;
use crate::metrics::deviation::closest_point_on_triangle;
use crate::polygonize::QuadNet;
use crate::spatial::KdTree;
use nalgebra::Point3;
use rayon::prelude::*;

/// Distance from the net, in voxels, beyond which an input point is missed.
pub const MISS_DISTANCE: f64 = 0.5;
/// Nearest nodes whose quads are searched for the distance.
pub const NODES_SEARCHED: usize = 4;
/// Largest missed share kept without refining (the deviation bar is on the 99th percentile).
pub const MISS_SHARE: f64 = 0.005;
/// Largest share of the trial patches' area farther than 1 % of the diagonal from the data kept
/// without refining (the bar on the final patches is 0.2 %).
pub const FAR_SHARE: f64 = 0.002;
/// Largest 99th percentile of the input points' distances from the trial patches, in
/// voxels h, kept without pieces. A net that reaches every part but follows a thin one as a
/// blob (a car's mirror) misses few points by [`MISS_DISTANCE`] yet leaves them a fifth of a
/// voxel off the patches; where the net follows the data the 99th percentile is about 0.01 h
/// (0.05 h at most on the partial-scan corpus of docs/BENCHMARKS.md, 0.15 h on the beetle).
pub const FAR_POINTS_P99: f64 = 0.1;
/// Times the patch count may be doubled.
pub const MAX_DOUBLINGS: usize = 2;
/// Fewest input points per patch for a refinement: a finer net on sparse data spends long
/// in the voxel net's thin-part repairs and gains nothing (cow's 1,872 upper vertices at
/// 3,000 patches: 10 minutes, then no net).
pub const MIN_POINTS_PER_PATCH: usize = 16;
/// Points measured at most.
pub const SAMPLE: usize = 50_000;

/// One net measured (the report's `close.coverage.rounds`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CoverageRound {
    /// Patches asked for and made.
    pub patches_requested: usize,
    pub patches: usize,
    /// Voxel edge.
    pub h: f64,
    /// Share of the measured input points farther than [`MISS_DISTANCE`] h from the net.
    pub missed_share: f64,
    /// Share of the trial patches' area farther than 1 % of the diagonal from the data (the
    /// report's `support_far` measured on the quick patches that rank the grid placements;
    /// `None` when they could not be built).
    pub far_share: Option<f64>,
}

/// What the coverage check found and did (the report's `close.coverage`).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct CoverageReport {
    /// Every net built, in order; the kept one is `kept`.
    pub rounds: Vec<CoverageRound>,
    pub kept: usize,
    /// Whether the kept net passes both bars: at most [`MISS_SHARE`] of the points missed and
    /// at most [`FAR_SHARE`] of its trial patches' area far from the data.
    pub covered: bool,
    /// What happened, in words (empty when the first net passed).
    pub note: String,
    /// Finer nets for the parts the kept net still misses ([`super::pieces`]), when it misses
    /// more than [`MISS_SHARE`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pieces: Option<PiecesReport>,
}

/// Distance from `x` to the quads (two triangles each) around the [`NODES_SEARCHED`] nodes of
/// `net` nearest to it (`nodes` indexes them).
fn distance_to_net(net: &QuadNet, nodes: &KdTree, x: &Point3<f64>) -> f64 {
    let mut best = f64::INFINITY;
    for (v, _) in nodes.knn(x, NODES_SEARCHED) {
        for &q in net.node_quads(v) {
            let c = net.quads[q as usize].map(|i| net.nodes[i as usize]);
            for [a, b, d] in [[c[0], c[1], c[2]], [c[0], c[2], c[3]]] {
                best = best.min((closest_point_on_triangle(x, &a, &b, &d) - x).norm());
            }
        }
    }
    best
}

/// Share of `points` (at most [`SAMPLE`] of them) farther than [`MISS_DISTANCE`] `h` from the
/// quads of `net`. 0 for an empty point set; 1 for a net without nodes.
pub fn missed_share(net: &QuadNet, points: &[Point3<f64>], h: f64) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let sample = measured_sample(points);
    missed_points(net, &sample, MISS_DISTANCE * h).len() as f64 / sample.len() as f64
}

/// At most [`SAMPLE`] of `points`, evenly spread through their order: those the coverage
/// figures are measured on.
pub fn measured_sample(points: &[Point3<f64>]) -> Vec<Point3<f64>> {
    let step = points.len().div_ceil(SAMPLE).max(1);
    points.iter().step_by(step).copied().collect()
}

/// Indices of `points` farther than `r` from the quads of `net` (all of them for a net
/// without nodes).
pub fn missed_points(net: &QuadNet, points: &[Point3<f64>], r: f64) -> Vec<usize> {
    let Ok(nodes) = KdTree::build(&net.nodes) else {
        return (0..points.len()).collect();
    };
    (0..points.len())
        .into_par_iter()
        .filter(|&i| distance_to_net(net, &nodes, &points[i]) > r)
        .collect()
}

/// Whether a net that misses `missed` of the points, and whose trial patches have `far` of
/// their area farther than 1 % of the diagonal from the data, should be built again, finer.
pub fn needs_refinement(missed: f64, far: Option<f64>) -> bool {
    missed > MISS_SHARE || far.is_some_and(|s| s > FAR_SHARE)
}

fn pct(s: f64) -> String {
    format!("{:.2} %", 100.0 * s)
}

/// What is wrong with a round, in words (empty when nothing is).
fn faults(r: &CoverageRound) -> String {
    let mut out = Vec::new();
    if r.missed_share > MISS_SHARE {
        out.push(format!(
            "misses {} of the points (parts of the data thinner than a patch: one-sided fins, \
             thin flanges)",
            pct(r.missed_share)
        ));
    }
    if let Some(far) = r.far_share.filter(|&s| s > FAR_SHARE) {
        out.push(format!(
            "puts {} of its area farther than 1 % of the diagonal from the data (it folds \
             through a part it cannot resolve, such as a hole a few patches wide)",
            pct(far)
        ));
    }
    out.join(" and ")
}

impl CoverageReport {
    /// Records the pieces fitted for the kept net's missed parts (of `n` input points): the
    /// note says what they did, and the net is covered when the points still missed are at
    /// most [`MISS_SHARE`] and the kept round's far share passes.
    pub fn add_pieces(&mut self, pieces: PiecesReport, n: usize) {
        let Some(kept) = self.rounds.get(self.kept) else {
            return;
        };
        let still = pieces.still_missed_points as f64 / n.max(1) as f64;
        if !pieces.pieces.is_empty() {
            self.covered = !needs_refinement(still, kept.far_share);
            let patches: usize = pieces.pieces.iter().map(|p| p.patches).sum();
            let add = format!(
                "{} finer piece{} ({patches} patches) fit the parts it misses, {} of the points \
                 still missed",
                pieces.pieces.len(),
                if pieces.pieces.len() == 1 { "" } else { "s" },
                pct(still)
            );
            self.note = if self.note.is_empty() {
                add
            } else {
                format!("{}; {add}", self.note)
            };
        }
        self.pieces = Some(pieces);
    }

    /// Sets `covered` and `note` from the rounds made and the one kept; `remedy` says what
    /// would make a finer net or why none was made (may be empty), `failed` why a refinement
    /// round could not be built.
    pub fn conclude(&mut self, remedy: &str, failed: Option<&crate::Error>) {
        let Some(kept) = self.rounds.get(self.kept) else {
            return;
        };
        self.covered = !needs_refinement(kept.missed_share, kept.far_share);
        let first = &self.rounds[0];
        let failed = failed.map_or_else(String::new, |e| format!(" (a finer net failed: {e})"));
        let remedy = if remedy.is_empty() {
            String::new()
        } else {
            format!("; {remedy}")
        };
        self.note = match (self.rounds.len(), self.covered) {
            (1, true) => String::new(),
            (1, false) => format!(
                "the net of {} patches {}{remedy}{failed}",
                kept.patches,
                faults(kept)
            ),
            (_, true) => format!(
                "the net of {} patches {}; made again with {} patches",
                first.patches,
                faults(first),
                kept.patches
            ),
            (_, false) => format!(
                "the net of {} patches {}, even after refining{remedy}{failed}",
                kept.patches,
                faults(kept)
            ),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square net of 10 x 10 quads in z = 0.
    fn square() -> QuadNet {
        let n = 11;
        let nodes = (0..n * n)
            .map(|i| Point3::new((i % n) as f64 / 10.0, (i / n) as f64 / 10.0, 0.0))
            .collect();
        let mut quads = Vec::new();
        for j in 0..10u32 {
            for i in 0..10u32 {
                let a = j * 11 + i;
                quads.push([a, a + 1, a + 12, a + 11]);
            }
        }
        QuadNet::new_open(nodes, quads).unwrap()
    }

    #[test]
    fn points_on_the_net_are_covered_and_a_fin_is_missed() {
        let net = square();
        let h = 0.1;
        // Points all over the square, also at the quads' centres: none missed.
        let on: Vec<Point3<f64>> = (0..400)
            .map(|i| Point3::new((i % 20) as f64 / 19.0, (i / 20) as f64 / 19.0, 0.01))
            .collect();
        assert_eq!(missed_share(&net, &on, h), 0.0);
        // A fin hanging 0.5 below the square's edge, a quarter of the points: missed.
        let mut all = on.clone();
        all.extend(
            (0..100).map(|i| Point3::new(i as f64 / 99.0, 1.0, -0.2 - 0.3 * (i % 7) as f64 / 6.0)),
        );
        let s = missed_share(&net, &all, h);
        assert!((s - 0.2).abs() < 0.01, "{s}");
        assert!(needs_refinement(s, None) && !needs_refinement(0.0, Some(0.001)));
        assert!(needs_refinement(0.0, Some(0.01)));
        assert_eq!(missed_share(&net, &[], h), 0.0);
    }
}
