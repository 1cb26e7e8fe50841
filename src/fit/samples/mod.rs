//! Per-patch sample grids on the implicit (seed 004 section 3, Fig. 5(c)): for every quad of the
//! smoothed net, an (S + 1) x (T + 1) grid of points on f = 0 with the boundary tangents that
//! the bicubic interpolation of eq. 9-14 needs.
//!
//! **Patch frame.** Quad [a, b, c, d] (counter-clockwise seen from outside) becomes the patch
//! with corners (u, v) = (0, 0), (1, 0), (1, 1), (0, 1) at a, b, c, d, so S_u x S_v points
//! outward. Its sides: v = 0 runs a -> b, u = 1 runs b -> c, v = 1 runs d -> c, u = 0 runs
//! a -> d ([`PatchSamples::sides`], each with its net edge and whether the patch walks it
//! against the edge's canonical lower -> higher direction).
//!
//! **Counts.** S (u) and T (v) are per ribbon ([`super::ribbons`]): opposite sides of a quad and
//! both quads of an edge share one count. Start at `min_intervals`; build every patch; for each
//! quad estimate the deviation of its row splines (u) and column splines (v) from f = 0 at the
//! interval midpoints ([`super::spline_check`]; these splines are the patch's iso-curves through
//! the sample rows) and at the cell centres (an estimate); where it exceeds the tolerance, raise the
//! ribbon's count to 1.2 S (dev / tol)^(1/2) (see [`CONVERGENCE_ORDER`]: on scan implicits the
//! estimate falls like the square of the spacing at these counts, not yet like the fourth power
//! cubic interpolation reaches asymptotically), rebuild the patches touching changed ribbons,
//! and repeat; a
//! quad whose deviation fell by less than r^2 once its count rose by r >= 2 (r^4 is expected)
//! is "stalled" and stops driving
//! refinement (otherwise one unresolvable patch would push its whole ribbon to the cap). A
//! ribbon takes the largest count any of its quads needs, so one curved spot densifies its whole
//! strip: the price of a tensor-product network without T-junctions. The first round may be
//! given ([`sample_patches_from`]: `fit` passes the trial sampling that ranked the grid
//! placements), so refinement starts from it instead of from `min_intervals`.
//!
//! **Parameters.** Uniform, k / S, snapped to multiples of 2^-40 (exactly symmetric under
//! t -> 1 - t, and the grid the nurbs module's `Params` uses), identical for every patch of a
//! ribbon and on both sides of every edge. The edge samples sit at equal chord stations
//! ([`super::edge_curve`]), so they are nearly equally spaced and eq. 9's square-root chord
//! parameters would be nearly uniform anyway; uniform values are what two neighbours can
//! compute identically without seeing each other's interior.
//!
//! **Boundary.** Row v = 0 is the sample list of the edge a-b (reversed if a > b), and so on:
//! points and along-side derivatives come from the shared [`EdgeSamples`], bit-identical for
//! both neighbours. Along-side derivatives are d/dt of the edge curve, t the edge parameter on
//! [0, 1], which is the patch parameter along that side: they are derivatives of the patch with
//! respect to its own parameter, as eq. 11's end conditions require.
//!
//! **Interior.** Each interior row j is the section curve from its left boundary sample to its
//! right one, sampled at S intervals with the edge machinery ([`super::edge_curve`]: a family of
//! lines of the section plane, tracing as fallback), the plane chosen with the normal of the
//! transfinite (Coons) patch of the four boundary rows at the row's middle. (Independent Coons
//! points projected onto f = 0 were tried first: on patches wrapping the rim of a part thinner
//! than a patch, like the bunny's ears, neighbouring points landed on different sides and the
//! grid folded as it was refined.) If a row cannot be found, its points are the Coons points
//! moved onto f = 0 along the Coons normal. In an open fit, rows that stray from the data are
//! replaced row by row ([`NearData`]), and a patch whose rows together cover over three times
//! the area of its Coons patch with cells away from the data (rows running round an ear or a
//! horn beside the patch, past the data's rim) takes the Coons rows instead
//! (`patch::unballoon`).
//!
//! **Cross-boundary derivatives.** d/du at the ends of interior rows is the row curve's own
//! tangent (exact for that curve, in the implicit's tangent plane); at the corners it is the
//! along-side derivative of the adjacent side. d/dv on the rows v = 0 and v = 1 is the
//! one-sided difference (third order when T >= 3) of each column of samples, projected onto
//! the implicit's tangent plane at the boundary sample (normal from the edge data). On all four
//! sides, an interior one that reaches back across its side (a patch wrapping a thin rim) is
//! reflected into the patch ([`point_into_patch`]). The two patches of an edge have different
//! cross derivatives (each points into its own patch, with its own length), but both lie in
//! the same tangent plane with the along-edge derivative, so the network is tangent-continuous
//! (G1) at every boundary sample. Between samples the normal jump depends on the
//! interpolation and is measured downstream (cad_check normal_jump_deg); at net vertices of
//! valence != 4 one bicubic per quad cannot be G1 in general (Peters & Fan), so no twist
//! compatibility is attempted here.

mod near;
mod patch;
#[cfg(test)]
mod tests;

pub use near::NearData;

use super::edge_curve::{sample_edge, sample_projected_chord, EdgeMethod, EdgeSamples};
use super::ribbons::{ribbons, Ribbons};
use crate::implicit::Implicit;
use crate::polygonize::QuadNet;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use near::keep_near;
use patch::{build_patch, measure};
use rayon::prelude::*;

/// Options of [`sample_patches`].
#[derive(Debug, Clone, Copy)]
pub struct SampleOptions<'a> {
    /// Largest allowed distance of the row/column splines from f = 0 (`--tolerance`; the CLI
    /// default is 1e-4 of the bounding-box diagonal).
    pub tolerance: f64,
    /// Model size (bounding-box diagonal): root-finding tolerances are 1e-12 of it.
    pub scale: f64,
    /// Fewest and most intervals per side (defaults 2 and 16; the cap bounds the cost where
    /// the tolerance cannot be met, e.g. an implicit wobbling at its own fit tolerance; the
    /// fit lowers it to 12 for patches small enough to get STEP aprons,
    /// [`crate::fit::pipeline::APRON_MAX_INTERVALS`]).
    pub min_intervals: usize,
    pub max_intervals: usize,
    /// Refinement rounds.
    pub max_rounds: usize,
    /// Largest turning of the surface normal between consecutive samples of an edge, degrees
    /// (default 20): sides whose normals turn faster are refined, for continuity rather than
    /// position.
    pub max_turn_deg: f64,
    /// Measure every patch's deviation (default true): the refinement's input, and half the
    /// cost of a sampling at four intervals. Without it (trial patches that are only looked
    /// at as patches) there is one round and the patches are left unmeasured
    /// ([`PatchSamples::measured`]); [`sample_patches_from`] measures them when it starts from
    /// them.
    pub measure: bool,
    /// Keep samples near the data ([`NearData`]; open fits). None (default): samples follow
    /// the implicit wherever it goes (closed fits, where the implicit closes the openings).
    pub near: Option<NearData<'a>>,
}

impl SampleOptions<'_> {
    pub fn new(tolerance: f64, scale: f64) -> Self {
        SampleOptions {
            tolerance,
            scale,
            min_intervals: 2,
            max_intervals: 16,
            max_rounds: 6,
            max_turn_deg: 20.0,
            measure: true,
            near: None,
        }
    }
}

/// One side of a patch: its net edge, and whether the patch's parameter runs from the edge's
/// higher node to its lower node (then the patch sees the edge's arrays reversed and its
/// tangents negated).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct PatchSide {
    pub edge: u32,
    pub reversed: bool,
}

/// The interpolation data of one patch (one quad of the net).
#[derive(Debug, Clone, PartialEq)]
pub struct PatchSamples {
    /// Quad index in the net.
    pub quad: usize,
    /// Net nodes at (u, v) = (0, 0), (1, 0), (1, 1), (0, 1).
    pub corners: [u32; 4],
    /// Sides v = 0 (a -> b), u = 1 (b -> c), v = 1 (d -> c), u = 0 (a -> d), each in the
    /// direction of increasing patch parameter.
    pub sides: [PatchSide; 4],
    /// points[i][j] at (params_u[i], params_v[j]), S + 1 by T + 1, all on f = 0.
    pub points: Vec<Vec<Point3<f64>>>,
    /// The implicit's unit normal at each point (as the root finders left it; zero where the
    /// gradient vanishes), for the fold measure (`quality::folds`).
    pub normals: Vec<Vec<Vector3<f64>>>,
    pub params_u: Vec<f64>,
    pub params_v: Vec<f64>,
    /// d/du on the column u = 0 and u = 1 (T + 1 each).
    pub tan_u0: Vec<Vector3<f64>>,
    pub tan_u1: Vec<Vector3<f64>>,
    /// d/dv on the row v = 0 and v = 1 (S + 1 each).
    pub tan_v0: Vec<Vector3<f64>>,
    pub tan_v1: Vec<Vector3<f64>>,
    /// Largest distance from f = 0 of the row splines (u) and column splines (v) at their
    /// interval midpoints: exact for the tensor-product interpolant of eq. 9-14, whose
    /// iso-curves through the sample rows and columns are these splines.
    pub deviation_u: f64,
    pub deviation_v: f64,
    /// Estimated largest distance from f = 0 at the cell centres (see `build_patch`).
    pub deviation_cell: f64,
    /// Interior samples that could not be moved onto f = 0 and were left at their Coons point
    /// (0 unless the implicit misbehaves there).
    pub unprojected: usize,
    /// Largest |f| / |grad f| over the samples (about 1e-12 of the model size; larger where
    /// the implicit jumps across zero and a sample sits on the jump), from the root finders'
    /// last evaluations ([`EdgeSamples::residuals`]).
    pub max_residual: f64,
    /// Whether the interior rows are the Coons rows (projected onto f = 0, or as they are and
    /// counted in `unprojected`) because the section rows ballooned off the data (open fits
    /// only; see `patch::unballoon`).
    pub coons_rows: bool,
    /// Whether the three deviations were measured (else they are 0; see
    /// [`SampleOptions::measure`]).
    pub measured: bool,
}

impl PatchSamples {
    /// The largest of the three deviation estimates.
    pub fn deviation(&self) -> f64 {
        self.deviation_u
            .max(self.deviation_v)
            .max(self.deviation_cell)
    }
}

impl PatchSamples {
    /// S, the number of intervals in u.
    pub fn s(&self) -> usize {
        self.params_u.len() - 1
    }
    /// T, the number of intervals in v.
    pub fn t(&self) -> usize {
        self.params_v.len() - 1
    }
}

/// How the sampling went.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SampleReport {
    pub rounds: usize,
    pub ribbons: usize,
    /// Largest estimated deviation over all patches, and the median and 95th percentile of the
    /// per-patch deviations.
    pub max_deviation: f64,
    pub p50_deviation: f64,
    pub p95_deviation: f64,
    /// Patches whose estimated deviation exceeds the tolerance (at `max_intervals`).
    pub over_tolerance: usize,
    /// Total grid points over all patches, and distinct ones on edges.
    pub grid_points: usize,
    /// Histogram of ribbon interval counts: (count, ribbons).
    pub interval_histogram: Vec<(usize, usize)>,
    /// Edges sampled on lines of their section plane / by tracing / by the projected-chord
    /// last resort.
    pub edges_on_lines: usize,
    pub edges_traced: usize,
    pub edges_projected_chord: usize,
    /// Interior samples left off the surface (see [`PatchSamples::unprojected`]).
    pub unprojected_samples: usize,
    /// Open fits: patches whose section rows covered more than three times the area of the
    /// Coons patch of their sides, partly off the data (rows running round a part beside the
    /// patch), and were made again from the Coons patch.
    pub coons_row_patches: usize,
    /// Largest |f| / |grad f| over all samples, and the patches with a sample farther than
    /// 1e-9 of the model size from f = 0 (implicit defects: f jumping across zero).
    pub max_sample_residual: f64,
    pub patches_off_surface: usize,
    /// Patches whose deviation fell by less than r^2 once their sample count rose by r >= 2:
    /// they stopped driving refinement (patches wrapping a part thinner than themselves, implicit defects).
    pub stalled: usize,
    /// The cap on intervals per side ([`SampleOptions::max_intervals`]).
    pub max_intervals: usize,
}

/// All patches with the shared edge data they were built from.
#[derive(Debug, Clone)]
pub struct PatchSampling {
    pub patches: Vec<PatchSamples>,
    /// Per net edge, in its canonical direction.
    pub edges: Vec<EdgeSamples>,
    pub ribbons: Ribbons,
    /// Intervals per ribbon.
    pub intervals: Vec<usize>,
    pub report: SampleReport,
}

/// Uniform parameters k / n snapped to multiples of 2^-40 (symmetric: t_{n-k} = 1 - t_k exactly).
pub fn uniform_params(n: usize) -> Vec<f64> {
    const SNAP: f64 = (1u64 << 40) as f64;
    (0..=n)
        .map(|k| {
            if k == n {
                1.0
            } else {
                ((k as f64 / n as f64) * SNAP).round() / SNAP
            }
        })
        .collect()
}

/// Order of convergence the refinement assumes: a side whose deviation estimate is `dev` at
/// S intervals gets S (dev / tol)^(1 / CONVERGENCE_ORDER). Cubic interpolation converges with
/// order 4 asymptotically, but on the bunny's implicit the per-quad estimates fell with a
/// median order of 1.1 (from 2 to about 5 intervals), 1.7 (to about 10) and 2.1 (to 12)
/// between rounds: the implicit's curvature varies at the scale of the samples. Predicting
/// with 4 needed five rounds, most of them rebuilding every patch; with 2, three (the first
/// given), for 9 % more grid points and 1 s less on the bunny (docs/BENCHMARKS.md, session 9).
/// The prediction carries a [`MARGIN`].
pub const CONVERGENCE_ORDER: f64 = 2.0;

/// Factor on the predicted count: the order is a median, and without a margin a third of the
/// patches missed the tolerance by a little and took their ribbons through one more round
/// (bunny: 1.2 gives 2 % more grid points and 0.2 s less sampling than 1.0).
pub const MARGIN: f64 = 1.2;

/// Samples every quad of `net` (nodes on f = 0, e.g. after `net_smooth`). Errors: invalid
/// options, and edge or interior points where the implicit cannot be solved.
pub fn sample_patches<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    opt: &SampleOptions,
) -> Result<PatchSampling> {
    sample_patches_from(net, f, opt, None)
}

/// [`sample_patches`] with its first round given: `start`, a sampling of the same `net` (by
/// [`sample_patches`] with any options; `fit` passes the trial patches that ranked the grid
/// placements), counts as round 1 and refinement goes on from its counts. A `start` of
/// another net, or with counts outside `opt`'s range, is ignored (sampled from scratch).
pub fn sample_patches_from<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    opt: &SampleOptions,
    start: Option<PatchSampling>,
) -> Result<PatchSampling> {
    if !(opt.tolerance > 0.0 && opt.scale > 0.0)
        || opt.min_intervals < 1
        || opt.max_intervals < opt.min_intervals
        || opt.max_rounds < 1
    {
        return Err(Error::InvalidOption(format!(
            "sampling needs a positive tolerance and scale and 1 <= min <= max intervals, got {opt:?}"
        )));
    }
    let rib = ribbons(net);
    let start = start.filter(|s| {
        s.ribbons == rib
            && s.patches.len() == net.quads.len()
            && s.edges.len() == net.edges.len()
            && s.intervals.len() == rib.count
            && s.intervals
                .iter()
                .all(|n| (opt.min_intervals..=opt.max_intervals).contains(n))
    });
    let (mut intervals, mut edges, mut patches, mut changed): (Vec<usize>, Vec<_>, Vec<_>, _) =
        match start {
            Some(mut s) => {
                if opt.measure {
                    s.patches
                        .par_iter_mut()
                        .filter(|p| !p.measured)
                        .for_each(|p| measure(f, p));
                }
                (
                    s.intervals,
                    s.edges.into_iter().map(Some).collect(),
                    s.patches.into_iter().map(Some).collect(),
                    vec![false; rib.count],
                )
            }
            None => (
                vec![opt.min_intervals; rib.count],
                vec![None; net.edges.len()],
                vec![None; net.quads.len()],
                vec![true; rib.count],
            ),
        };
    let mut rounds = 0;
    // Per quad and direction: the (count, deviation) of the first build, and whether the quad
    // stopped improving (it then no longer drives refinement).
    let mut first: Vec<[(usize, f64); 2]> = vec![[(0, f64::INFINITY); 2]; net.quads.len()];
    let mut stalled = vec![[false; 2]; net.quads.len()];
    loop {
        if changed.contains(&true) {
            rebuild(
                net,
                f,
                &rib,
                &intervals,
                &changed,
                &mut edges,
                &mut patches,
                opt,
            )?;
        }
        rounds += 1;
        if rounds >= opt.max_rounds || !opt.measure {
            break;
        }
        // Raise the counts of ribbons whose quads miss the tolerance.
        let mut need = intervals.clone();
        for (q, p) in patches.iter().enumerate() {
            let Some(p) = p else { continue };
            // A cell-centre miss raises both directions.
            let du = p.deviation_u.max(p.deviation_cell);
            let dv = p.deviation_v.max(p.deviation_cell);
            for (dir, dev, n) in [(0, du, p.s()), (1, dv, p.t())] {
                // Raised by r >= 2 since the first build: cubic interpolation should have cut
                // the deviation by r^4; less than r^2 means the patch does not converge (a
                // feature below the sample spacing, a jump of the implicit).
                let (n0, d0) = first[q][dir];
                if n0 == 0 {
                    first[q][dir] = (n, dev);
                } else if n >= 2 * n0 {
                    let r = n as f64 / n0 as f64;
                    if dev > d0 / (r * r) {
                        stalled[q][dir] = true;
                    }
                }
                if dev > opt.tolerance && !stalled[q][dir] {
                    let r = rib.of_quad[q][dir] as usize;
                    let want =
                        (n as f64 * (dev / opt.tolerance).powf(1.0 / CONVERGENCE_ORDER) * MARGIN)
                            .ceil() as usize;
                    need[r] = need[r].max(want.max(n + 1).min(opt.max_intervals));
                }
            }
        }
        // Normals turning fast between samples (a rounded crease, a thin rim): the normal jump
        // between two patches grows with the turning per interval, so a ribbon whose edges
        // turn by more than `max_turn_deg` per interval is refined in proportion.
        for (e, es) in edges.iter().enumerate() {
            let Some(es) = es else { continue };
            let turn = es
                .normals
                .windows(2)
                .map(|w| w[0].angle(&w[1]).to_degrees())
                .fold(0.0, f64::max);
            if turn > opt.max_turn_deg {
                let r = rib.of_edge[e] as usize;
                let n = es.intervals();
                let want = (n as f64 * turn / opt.max_turn_deg).ceil() as usize;
                need[r] = need[r].max(want.max(n + 1).min(opt.max_intervals));
            }
        }
        changed = need.iter().zip(&intervals).map(|(a, b)| a != b).collect();
        intervals = need;
        if !changed.contains(&true) {
            break;
        }
    }
    let stalled = stalled.iter().filter(|s| s[0] || s[1]).count();
    finish(rib, intervals, edges, patches, opt, rounds, stalled)
}

/// Re-samples the edges of the changed ribbons and the quads touching them.
#[allow(clippy::too_many_arguments)]
fn rebuild<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    rib: &Ribbons,
    intervals: &[usize],
    changed: &[bool],
    edges: &mut [Option<EdgeSamples>],
    patches: &mut [Option<PatchSamples>],
    opt: &SampleOptions,
) -> Result<()> {
    let tol = 1e-12 * opt.scale;
    let todo: Vec<usize> = (0..net.edges.len())
        .filter(|&e| changed[rib.of_edge[e] as usize])
        .collect();
    let fresh: Vec<EdgeSamples> = todo
        .par_iter()
        .map(|&e| {
            let [lo, hi] = net.edges[e];
            let n = intervals[rib.of_edge[e] as usize];
            let hint = net.quads_of_edge(e).fold(Vector3::zeros(), |acc, q| {
                let p = net.quads[q as usize].map(|k| net.nodes[k as usize]);
                acc + (p[2] - p[0]).cross(&(p[3] - p[1])).normalize()
            });
            let (a, b) = (net.nodes[lo as usize], net.nodes[hi as usize]);
            let es = sample_edge(f, a, b, hint, n, tol)?;
            Ok(keep_near(
                opt.near,
                es,
                |e| &e.points,
                || sample_projected_chord(f, a, b, n, tol).ok(),
            ))
        })
        .collect::<Result<_>>()?;
    for (e, s) in todo.into_iter().zip(fresh) {
        edges[e] = Some(s);
    }
    let todo: Vec<usize> = (0..net.quads.len())
        .filter(|&q| rib.of_quad[q].iter().any(|&r| changed[r as usize]))
        .collect();
    let fresh: Vec<PatchSamples> = todo
        .par_iter()
        .map(|&q| build_patch(net, f, edges, q, opt))
        .collect::<Result<_>>()?;
    for (q, p) in todo.into_iter().zip(fresh) {
        patches[q] = Some(p);
    }
    Ok(())
}

fn finish(
    rib: Ribbons,
    intervals: Vec<usize>,
    edges: Vec<Option<EdgeSamples>>,
    patches: Vec<Option<PatchSamples>>,
    opt: &SampleOptions,
    rounds: usize,
    stalled: usize,
) -> Result<PatchSampling> {
    let edges: Vec<EdgeSamples> = edges
        .into_iter()
        .collect::<Option<_>>()
        .ok_or_else(|| Error::Numerical("an edge was left without samples".into()))?;
    let patches: Vec<PatchSamples> = patches
        .into_iter()
        .collect::<Option<_>>()
        .ok_or_else(|| Error::Numerical("a quad was left without samples".into()))?;
    let dev = |p: &PatchSamples| p.deviation();
    let mut devs: Vec<f64> = patches.iter().map(dev).collect();
    devs.sort_by(f64::total_cmp);
    let mut hist = std::collections::BTreeMap::new();
    for &n in &intervals {
        *hist.entry(n).or_insert(0usize) += 1;
    }
    let report = SampleReport {
        rounds,
        ribbons: rib.count,
        max_deviation: patches.iter().map(dev).fold(0.0, f64::max),
        p50_deviation: quantile(&devs, 0.5),
        p95_deviation: quantile(&devs, 0.95),
        over_tolerance: patches.iter().filter(|p| dev(p) > opt.tolerance).count(),
        grid_points: patches.iter().map(|p| (p.s() + 1) * (p.t() + 1)).sum(),
        interval_histogram: hist.into_iter().collect(),
        edges_on_lines: edges
            .iter()
            .filter(|e| e.method == EdgeMethod::Lines)
            .count(),
        edges_traced: edges
            .iter()
            .filter(|e| e.method == EdgeMethod::Traced)
            .count(),
        edges_projected_chord: edges
            .iter()
            .filter(|e| e.method == EdgeMethod::ProjectedChord)
            .count(),
        unprojected_samples: patches.iter().map(|p| p.unprojected).sum(),
        coons_row_patches: patches.iter().filter(|p| p.coons_rows).count(),
        max_sample_residual: patches.iter().map(|p| p.max_residual).fold(0.0, f64::max),
        patches_off_surface: patches
            .iter()
            .filter(|p| p.max_residual > 1e-9 * opt.scale)
            .count(),
        stalled,
        max_intervals: opt.max_intervals,
    };
    Ok(PatchSampling {
        patches,
        edges,
        ribbons: rib,
        intervals,
        report,
    })
}

/// The q-quantile of sorted values (nearest rank; 0 for none).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}
