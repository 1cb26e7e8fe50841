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
//! moved onto f = 0 along the Coons normal.
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

use super::edge_curve::{residual, sample_edge, sample_section, EdgeMethod, EdgeSamples};
use super::ribbons::{ribbons, Ribbons};
use super::spline_check::spline_midpoints;
use crate::implicit::Implicit;
use crate::polygonize::newton::{project, solve_on_line, NewtonOptions};
use crate::polygonize::QuadNet;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Options of [`sample_patches`].
#[derive(Debug, Clone, Copy)]
pub struct SampleOptions {
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
}

impl SampleOptions {
    pub fn new(tolerance: f64, scale: f64) -> Self {
        SampleOptions {
            tolerance,
            scale,
            min_intervals: 2,
            max_intervals: 16,
            max_rounds: 6,
            max_turn_deg: 20.0,
            measure: true,
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
            sample_edge(
                f,
                net.nodes[lo as usize],
                net.nodes[hi as usize],
                hint,
                n,
                tol,
            )
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

/// One side's samples in the patch direction: points, along-side derivatives, normals, and
/// the section plane's in-plane normal.
struct Side {
    p: Vec<Point3<f64>>,
    d: Vec<Vector3<f64>>,
    n: Vec<Vector3<f64>>,
    w: Vector3<f64>,
}

fn side(e: &EdgeSamples, reversed: bool) -> Side {
    if reversed {
        Side {
            p: e.points.iter().rev().copied().collect(),
            d: e.tangents.iter().rev().map(|t| -t).collect(),
            n: e.normals.iter().rev().copied().collect(),
            w: e.plane_w,
        }
    } else {
        Side {
            p: e.points.clone(),
            d: e.tangents.clone(),
            n: e.normals.clone(),
            w: e.plane_w,
        }
    }
}

/// Which parameter a side runs along: `V` sides (v = 0, v = 1) run along u, `U` sides along v.
#[derive(Clone, Copy)]
enum SideKind {
    U,
    V,
}

/// The unit vector of the tangent plane (normal `n`) perpendicular to a side whose derivative
/// along itself is `along`, pointing the way the patch parameter across the side increases:
/// N x C' on a v side, C' x N on a u side, so that S_u x S_v points along N.
fn across(kind: SideKind, along: &Vector3<f64>, n: &Vector3<f64>) -> Option<Vector3<f64>> {
    match kind {
        SideKind::V => n.cross(along),
        SideKind::U => along.cross(n),
    }
    .try_normalize(1e-300)
}

/// Reflects the interior cross derivatives of one side that point backwards across it,
/// D -> D - 2 (D . e) e with e from [`across`]. A one-sided difference of the sample columns
/// reaches back across the side where the patch wraps the rim of a part thinner than the
/// sample spacing (the bunny's ear tip); left as it is, the patch's normal there is flipped
/// and the two neighbours' normals differ by 180 degrees at that sample. Reflection keeps the
/// derivative's length and its component along the side. Default bunny: the largest normal
/// jump (our measure) 180 -> 92 degrees, edge samples over 5 degrees 40 -> 36; the cow 314 ->
/// 236, the Utah teapot 571 -> 432.
fn point_into_patch(
    d: &mut [Vector3<f64>],
    along: &[Vector3<f64>],
    normals: &[Vector3<f64>],
    kind: SideKind,
) {
    let n = d.len().min(along.len()).min(normals.len());
    for k in 1..n.saturating_sub(1) {
        if let Some(e) = across(kind, &along[k], &normals[k]) {
            let b = d[k].dot(&e);
            if b < 0.0 {
                d[k] -= e * (2.0 * b);
            }
        }
    }
}

fn tangent_part(x: Vector3<f64>, n: &Vector3<f64>) -> Vector3<f64> {
    x - n * n.dot(&x)
}

/// The q-quantile of sorted values (nearest rank; 0 for none).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Derivative at p[0] of the polynomial through p[0], p[1], ... at uniform steps `h`, of
/// degree min(n, 3) (n the number of intervals available): one-sided differences of order up
/// to three.
fn one_sided_derivative(p: [Vector3<f64>; 4], n: usize, h: f64) -> Vector3<f64> {
    match n {
        0 => Vector3::zeros(),
        1 => (p[1] - p[0]) / h,
        2 => ((p[1] - p[0]) * 4.0 - (p[2] - p[0])) / (2.0 * h),
        _ => ((p[1] - p[0]) * 18.0 - (p[2] - p[0]) * 9.0 + (p[3] - p[0]) * 2.0) / (6.0 * h),
    }
}

/// An interior row: points, normals, d/du at both ends, samples left off the surface, the
/// largest |f| / |grad f| of its points.
type Row = (
    Vec<Point3<f64>>,
    Vec<Vector3<f64>>,
    Vector3<f64>,
    Vector3<f64>,
    usize,
    f64,
);

/// The transfinite (Coons) patch of four boundary sample rows, for interior hints and the
/// fallback: P = (1-v) B(u) + v T(u) + (1-u) L(v) + u R(v) - bilinear(corners).
struct Coons<'a> {
    bot: &'a Side,
    top: &'a Side,
    left: &'a Side,
    right: &'a Side,
    corners: [Point3<f64>; 4],
}

impl Coons<'_> {
    /// Point at sample (i, j), parameters (u, v).
    fn point(&self, i: usize, j: usize, u: f64, v: f64) -> Point3<f64> {
        let [ca, cb, cc, cd] = self.corners.map(|p| p.coords);
        Point3::from(
            self.bot.p[i].coords * (1.0 - v)
                + self.top.p[i].coords * v
                + self.left.p[j].coords * (1.0 - u)
                + self.right.p[j].coords * u
                - (ca * ((1.0 - u) * (1.0 - v))
                    + cb * (u * (1.0 - v))
                    + cc * (u * v)
                    + cd * ((1.0 - u) * v)),
        )
    }
    /// Unit normal P_u x P_v at sample (i, j) (outward); the blend of the boundary normals where
    /// that degenerates.
    fn normal(&self, i: usize, j: usize, u: f64, v: f64) -> Vector3<f64> {
        let [ca, cb, cc, cd] = self.corners;
        let (b, t, l, r) = (self.bot, self.top, self.left, self.right);
        let su = b.d[i] * (1.0 - v) + t.d[i] * v + (r.p[j] - l.p[j])
            - ((cb - ca) * (1.0 - v) + (cc - cd) * v);
        let sv = l.d[j] * (1.0 - u) + r.d[j] * u + (t.p[i] - b.p[i])
            - ((cd - ca) * (1.0 - u) + (cc - cb) * u);
        let s = b.n.len() - 1;
        let blend = b.n[i] * (1.0 - v) + t.n[i] * v + l.n[j] * (1.0 - u) + r.n[j] * u
            - (b.n[0] * ((1.0 - u) * (1.0 - v))
                + b.n[s] * (u * (1.0 - v))
                + t.n[s] * (u * v)
                + t.n[0] * ((1.0 - u) * v));
        su.cross(&sv)
            .try_normalize(1e-12 * su.norm() * sv.norm())
            .or_else(|| blend.try_normalize(1e-12))
            .unwrap_or_else(Vector3::zeros)
    }

    /// Largest distance an interior sample may lie from its Coons point: twice the longer
    /// diagonal of the quad. A section curve that leaves this band has run onto another
    /// sheet (in a concave crease narrower than a patch the section plane also cuts the
    /// surface across the crease: on the bunny's base two rows ran 3-4 patch widths down to
    /// the bottom and the patch grew a spike). Half a diagonal removed those spikes too but
    /// rejected honest rows on the cow's thin legs, where the Coons surface is far from the
    /// surface (mean deviation 4.1e-4 -> 8.2e-4); twice the diagonal keeps them (4.4e-4).
    fn reach(&self) -> f64 {
        let [ca, cb, cc, cd] = self.corners;
        2.0 * (cc - ca).norm().max((cd - cb).norm())
    }

    /// Whether every sample of row j lies within [`Coons::reach`] of its Coons point.
    fn row_near(&self, row: &[Point3<f64>], j: usize, pu: &[f64], v: f64) -> bool {
        let r2 = self.reach().powi(2);
        row.iter()
            .zip(pu)
            .enumerate()
            .all(|(i, (p, &u))| (p - self.point(i, j, u, v)).norm_squared() <= r2)
    }

    /// Row j from Coons points moved onto f = 0 along the Coons normal (kept where that fails),
    /// with the row's end derivatives from the Coons derivative; also the count of points left
    /// off the surface.
    fn row_fallback<I: Implicit + ?Sized>(
        &self,
        f: &I,
        j: usize,
        pu: &[f64],
        v: f64,
        tol: f64,
        scale: f64,
    ) -> Row {
        let s = pu.len() - 1;
        let [ca, cb, cc, cd] = self.corners;
        let reach = 0.5 * self.reach();
        let newton = NewtonOptions::new(scale, reach);
        let mut missed = 0;
        let row: Vec<Point3<f64>> = (0..=s)
            .map(|i| {
                if i == 0 {
                    return self.left.p[j];
                }
                if i == s {
                    return self.right.p[j];
                }
                let x = self.point(i, j, pu[i], v);
                let n = self.normal(i, j, pu[i], v);
                if n.norm_squared() > 0.0 {
                    if let Ok((sv, _)) = solve_on_line(f, x, n, reach, tol) {
                        return x + n * sv;
                    }
                }
                match project(f, x, &newton) {
                    Ok((p, _)) => p,
                    Err(_) => {
                        missed += 1;
                        x
                    }
                }
            })
            .collect();
        let common = (self.right.p[j] - self.left.p[j]) - ((cb - ca) * (1.0 - v) + (cc - cd) * v);
        let d0 = self.bot.d[0] * (1.0 - v) + self.top.d[0] * v + common;
        let d1 = self.bot.d[s] * (1.0 - v) + self.top.d[s] * v + common;
        let mut worst = 0.0f64;
        let normals = row
            .iter()
            .map(|p| {
                let (v, g) = f.value_and_gradient(p);
                worst = worst.max(residual(v, &g));
                g.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
            })
            .collect();
        (row, normals, d0, d1, missed, worst)
    }
}

/// Builds the samples of quad `q` from the edge data.
fn build_patch<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    edges: &[Option<EdgeSamples>],
    q: usize,
    opt: &SampleOptions,
) -> Result<PatchSamples> {
    let [a, b, c, d] = net.quads[q];
    let qe = net.quad_edges[q];
    // Patch sides: (net edge, patch walks from -> to).
    let sides = [
        PatchSide {
            edge: qe[0],
            reversed: a > b,
        },
        PatchSide {
            edge: qe[1],
            reversed: b > c,
        },
        PatchSide {
            edge: qe[2],
            reversed: d > c,
        },
        PatchSide {
            edge: qe[3],
            reversed: a > d,
        },
    ];
    let get = |s: &PatchSide| -> Result<Side> {
        edges[s.edge as usize]
            .as_ref()
            .map(|e| side(e, s.reversed))
            .ok_or_else(|| Error::Numerical(format!("edge {} has no samples", s.edge)))
    };
    let (bot, right, top, left) = (
        get(&sides[0])?,
        get(&sides[1])?,
        get(&sides[2])?,
        get(&sides[3])?,
    );
    let (s, t) = (bot.p.len() - 1, left.p.len() - 1);
    if top.p.len() != s + 1 || right.p.len() != t + 1 {
        return Err(Error::Numerical(format!(
            "quad {q}: opposite sides have different sample counts"
        )));
    }
    let (pu, pv) = (uniform_params(s), uniform_params(t));
    let (ca, cb, cc, cd) = (bot.p[0], bot.p[s], top.p[s], top.p[0]);
    let tol = 1e-12 * opt.scale;
    let mut points = vec![vec![Point3::origin(); t + 1]; s + 1];
    for (i, col) in points.iter_mut().enumerate() {
        col[0] = bot.p[i];
        col[t] = top.p[i];
    }
    points[0].copy_from_slice(&left.p);
    points[s].copy_from_slice(&right.p);
    let mut normals = vec![vec![Vector3::zeros(); t + 1]; s + 1];
    for (i, col) in normals.iter_mut().enumerate() {
        col[0] = bot.n[i];
        col[t] = top.n[i];
    }
    normals[0].copy_from_slice(&left.n);
    normals[s].copy_from_slice(&right.n);
    // d/du at the ends of every row: the boundary edges' tangents at the corners, the row
    // curves' own tangents in between.
    let mut tan_u0 = vec![Vector3::zeros(); t + 1];
    let mut tan_u1 = vec![Vector3::zeros(); t + 1];
    (tan_u0[0], tan_u1[0], tan_u0[t], tan_u1[t]) = (bot.d[0], bot.d[s], top.d[0], top.d[s]);
    // Interior rows: the section curve from the row's left sample to its right one (the edge
    // machinery: lines, tracing), hinted by the Coons surface's normal at the row's middle.
    // Where even that fails: Coons points moved onto f = 0 along the Coons normal.
    let coons = Coons {
        bot: &bot,
        top: &top,
        left: &left,
        right: &right,
        corners: [ca, cb, cc, cd],
    };
    let rows: Vec<Row> = (1..t)
        .map(|j| {
            // The plane normal blends the bottom and top edges' (rows 0 and T would be those
            // edges exactly); where they disagree (a patch wrapping a rim along v), the Coons
            // normal at the row's middle makes up the missing length.
            let hint = coons.normal(s / 2, j, 0.5, pv[j]);
            let blend = bot.w * (1.0 - pv[j]) + top.w * pv[j];
            let w = blend + hint * (1.0 - blend.norm()).max(0.0);
            match sample_section(f, left.p[j], right.p[j], w, s, tol) {
                Ok(row) if coons.row_near(&row.points, j, &pu, pv[j]) => {
                    let worst = row.residuals.iter().fold(0.0, |a: f64, &b| a.max(b));
                    (
                        row.points,
                        row.normals,
                        row.tangents[0],
                        row.tangents[s],
                        0,
                        worst,
                    )
                }
                _ => coons.row_fallback(f, j, &pu, pv[j], tol, opt.scale),
            }
        })
        .collect();
    let mut unprojected = 0;
    // Largest |f| / |grad f| of the samples, as the root finders left them: the four edges',
    // then the rows'.
    let mut max_residual = sides
        .iter()
        .filter_map(|sd| edges[sd.edge as usize].as_ref())
        .flat_map(|e| e.residuals.iter().copied())
        .fold(0.0, f64::max);
    for (j, (row, row_normals, d0, d1, missed, worst)) in (1..t).zip(rows) {
        max_residual = max_residual.max(worst);
        for i in 1..s {
            points[i][j] = row[i];
            normals[i][j] = row_normals[i];
        }
        tan_u0[j] = tangent_part(d0, &left.n[j]);
        tan_u1[j] = tangent_part(d1, &right.n[j]);
        unprojected += missed;
    }
    // d/dv on the rows v = 0 and v = 1: the side edges' tangents at the corners; in between,
    // the one-sided difference of each column, in the tangent plane.
    let dv = pv[1] - pv[0];
    let one_sided = |p: [Point3<f64>; 4]| {
        one_sided_derivative([p[0].coords, p[1].coords, p[2].coords, p[3].coords], t, dv)
    };
    let mut tan_v0 = Vec::with_capacity(s + 1);
    let mut tan_v1 = Vec::with_capacity(s + 1);
    for (i, col) in points.iter().enumerate() {
        let (v0, v1) = if i == 0 {
            (left.d[0], left.d[t])
        } else if i == s {
            (right.d[0], right.d[t])
        } else {
            let at = |k: usize| col[k.min(t)];
            let from_top = |k: usize| col[t - k.min(t)];
            (
                tangent_part(one_sided([at(0), at(1), at(2), at(3)]), &bot.n[i]),
                -tangent_part(
                    one_sided([from_top(0), from_top(1), from_top(2), from_top(3)]),
                    &top.n[i],
                ),
            )
        };
        tan_v0.push(v0);
        tan_v1.push(v1);
    }
    // A cross derivative reaching back across its side (a one-sided difference over the rim
    // of a part thinner than the sample spacing) is reflected into the patch.
    point_into_patch(&mut tan_v0, &bot.d, &bot.n, SideKind::V);
    point_into_patch(&mut tan_v1, &top.d, &top.n, SideKind::V);
    point_into_patch(&mut tan_u0, &left.d, &left.n, SideKind::U);
    point_into_patch(&mut tan_u1, &right.d, &right.n, SideKind::U);
    let mut p = PatchSamples {
        quad: q,
        corners: [a, b, c, d],
        sides,
        points,
        normals,
        params_u: pu,
        params_v: pv,
        tan_u0,
        tan_u1,
        tan_v0,
        tan_v1,
        deviation_u: 0.0,
        deviation_v: 0.0,
        deviation_cell: 0.0,
        unprojected,
        max_residual,
        measured: false,
    };
    if opt.measure {
        measure(f, &mut p);
    }
    Ok(p)
}

/// Measures a patch's samples: the deviation from f = 0 of its row splines (u) and column
/// splines (v) at their interval midpoints, and the estimate at the cell centres.
fn measure<I: Implicit + ?Sized>(f: &I, p: &mut PatchSamples) {
    let (s, t) = (p.s(), p.t());
    let (points, pu, pv) = (&p.points, &p.params_u, &p.params_v);
    let (tan_u0, tan_u1, tan_v0, tan_v1) = (&p.tan_u0, &p.tan_u1, &p.tan_v0, &p.tan_v1);
    // Tolerance estimate along rows (u), columns (v) and at cell centres.
    let dist = |p: &Vector3<f64>| {
        let (val, g) = f.value_and_gradient(&Point3::from(*p));
        residual(val, &g)
    };
    let max_dist = |v: &[Vector3<f64>]| v.iter().map(dist).fold(0.0, f64::max);
    let row_mids: Vec<Vec<Vector3<f64>>> = (0..=t)
        .map(|j| {
            let row: Vec<Vector3<f64>> = (0..=s).map(|i| points[i][j].coords).collect();
            spline_midpoints(&row, pu, &tan_u0[j], &tan_u1[j])
        })
        .collect();
    let deviation_u = row_mids.iter().map(|r| max_dist(r)).fold(0.0, f64::max);
    let deviation_v = (0..=s)
        .map(|i| {
            let col: Vec<Vector3<f64>> = points[i].iter().map(|p| p.coords).collect();
            max_dist(&spline_midpoints(&col, pv, &tan_v0[i], &tan_v1[i]))
        })
        .fold(0.0, f64::max);
    // Cell centres: the v-spline through the row midpoints of each column of cells, with end
    // derivatives interpolated along u from tan_v0 / tan_v1 (end slopes of that interpolation,
    // the twists, from one-sided differences of order up to three). The tensor-product patch's value there depends
    // on how the interpolation treats twists, so this is an estimate.
    let du = pu[1] - pu[0];
    let twist = |d: &[Vector3<f64>], from_end: bool| {
        let at = |k: usize| {
            if from_end {
                d[s - k.min(s)]
            } else {
                d[k.min(s)]
            }
        };
        let sign = if from_end { -1.0 } else { 1.0 };
        sign * one_sided_derivative([at(0), at(1), at(2), at(3)], s, du)
    };
    let v0_mid = spline_midpoints(tan_v0, pu, &twist(tan_v0, false), &twist(tan_v0, true));
    let v1_mid = spline_midpoints(tan_v1, pu, &twist(tan_v1, false), &twist(tan_v1, true));
    let deviation_cell = (0..s)
        .map(|i| {
            let col: Vec<Vector3<f64>> = row_mids.iter().map(|r| r[i]).collect();
            max_dist(&spline_midpoints(&col, pv, &v0_mid[i], &v1_mid[i]))
        })
        .fold(0.0, f64::max);
    p.deviation_u = deviation_u;
    p.deviation_v = deviation_v;
    p.deviation_cell = deviation_cell;
    p.measured = true;
}

#[cfg(test)]
mod tests {
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
    fn check_network<I: Implicit>(
        name: &str,
        f: &I,
        net: &QuadNet,
        ps: &PatchSampling,
        scale: f64,
    ) {
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
}
