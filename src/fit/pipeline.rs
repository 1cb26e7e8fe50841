//! The whole `fit` pipeline (seed 004, Fig. 2): oriented points -> partition-of-unity implicit
//! (eq. 1-3) -> voxel quad net, projected and smoothed on the implicit -> per-quad sample grids
//! with shared edge data -> one bicubic patch per quad by interpolation with clamped end
//! tangents (eq. 9-14) -> a sewn patch network, measured: deviation of the input points from the
//! patches by point inversion, normal jump across shared edges, quad quality, timings.

use super::crease_net::CreaseNet;
use super::cross_tangents::{align_cross_derivatives, corner_twists, BoundarySplines};
use super::net::{fit_net, fit_open_net, NetReport, PatchSize, TrialScore};
use super::samples::{
    sample_patches, sample_patches_from, NearData, PatchSampling, SampleOptions, SampleReport,
};
use super::vertex_twists::{corners_of, solve_vertex_twists, Corner};
use crate::implicit::pou::{FitOptions as ImplicitOptions, FitStats, PouImplicit};
use crate::implicit::Implicit;
use crate::mesh::{Aabb, Mesh};
use crate::normals::{oriented_points, NormalSource};
use crate::nurbs::{BSplineSurface, Params, PatchGrid, PatchInput, PatchNetwork, Twist};
use crate::polygonize::QuadNet;
use crate::quality::{
    deviation_from_patches, folds, normal_jumps, surface_support_at, ContinuityReport, FoldReport,
    PatchDeviation, SampleGrid, SupportReport,
};
use crate::spatial::KdTree;
use crate::{Error, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Options of [`fit`], with the CLI's defaults.
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Patch count or patch edge (default about 1,500 patches).
    pub size: PatchSize,
    /// Largest distance of the patches from the implicit, as a fraction of the bounding-box
    /// diagonal (default 1e-4).
    pub tolerance: f64,
    /// The implicit's own fitting options.
    pub implicit: ImplicitOptions,
    /// Neighbours for normal estimation and repair (default 12).
    pub normal_neighbours: usize,
    /// Samples per shared edge for the normal-jump measurement (default 5, as cad_check).
    pub jump_samples: usize,
    /// The unit the STEP file will declare when its writer may extend small patches' surfaces
    /// ([`crate::export::apron`]); `None` when it will not. Patches that small get at most
    /// [`APRON_MAX_INTERVALS`] sample intervals per side instead of 16, so that with the two
    /// apron spans OpenCASCADE still samples them on its uniform grid.
    pub apron_unit: Option<crate::export::LengthUnit>,
    /// Find the input's sharp features and report them (`features` in the report;
    /// [`crate::features`]); `None` (default) skips the detection. The later stages do not use
    /// them yet.
    pub features: Option<crate::features::DetectOptions>,
    /// What to do with the openings of the data (`--close`, default `auto`;
    /// [`crate::openings`]).
    pub close: crate::openings::Close,
    /// Build the crease-aligned net too (`--sharp`, default `off` while it is being built,
    /// issue 36): the input is segmented into smooth regions, a second implicit fitted with one
    /// function per region in the cells a crease crosses ([`crate::implicit::sharp`]), its net
    /// built in the frame of the part's plane faces and its nodes put on the creases and
    /// corners ([`crate::polygonize::crease_nodes`]); the report and `--net` show it. The
    /// patches are still those of the smooth implicit's net. `Auto` decides as `reconstruct`
    /// does ([`crate::features::sharp_choice`]).
    pub sharp: crate::features::SharpMode,
    /// How `--sharp` builds its crease-aligned net (`--crease-net`, default `remesh`;
    /// [`super::crease_net`]).
    pub crease_net: super::crease_net::CreaseNetRoute,
    /// Whether the user gave the patch count or size (`--patches`, `--patch-size`). When not,
    /// an open fit whose net misses parts of the data thinner than a patch is made again with
    /// more patches ([`crate::openings::coverage`]); when given, the report only says so.
    pub size_given: bool,
}

/// Most sample intervals per patch side when the STEP writer extends the patches' surfaces:
/// 12 + 2 apron spans = 14 knot spans, the most for which OpenCASCADE's point projection
/// samples a cubic B-spline on its uniform 44-line grid (more spans give 3 lines per span,
/// too close together on a patch that small).
pub const APRON_MAX_INTERVALS: usize = 12;

/// Radius, in voxels, of the data fitted around a crease node for the sides it is put between
/// (`--sharp`; [`crate::features::data_sides`]): a node is up to a voxel from its crease.
const DATA_SIDES_RADIUS: f64 = 1.5;

/// Sample intervals per side of the trial patches that rank the grid placements.
const TRIAL_INTERVALS: usize = 4;

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            size: PatchSize::Count(super::net::DEFAULT_PATCHES),
            tolerance: 1e-4,
            implicit: ImplicitOptions::default(),
            normal_neighbours: 12,
            jump_samples: 5,
            apron_unit: Some(crate::export::LengthUnit::Millimetre),
            features: None,
            close: crate::openings::Close::Auto,
            sharp: crate::features::SharpMode::Off,
            crease_net: super::crease_net::CreaseNetRoute::Remesh,
            size_given: false,
        }
    }
}

/// Seconds per stage.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FitTimings {
    pub normals: f64,
    /// Sharp features (`--features`) and the segmentation of `--sharp`; 0 without.
    pub features: f64,
    pub implicit: f64,
    pub net: f64,
    /// The crease-aligned net of `--sharp` (its implicit, net and nodes put on the creases; 0
    /// without).
    pub creases: f64,
    pub sampling: f64,
    pub patches: f64,
    pub deviation: f64,
    /// Normal jumps and folds.
    pub continuity: f64,
    pub total: f64,
}

/// What `fit` made and how good it is: the JSON of `--report`.
#[derive(Debug, Clone, Serialize)]
pub struct FitReport {
    pub input_points: usize,
    pub normal_source: NormalSource,
    pub normals_flipped: usize,
    pub normals_estimated: usize,
    pub bbox_diagonal: f64,
    /// What `--close` chose and why.
    pub close: crate::openings::ClosureReport,
    /// Tolerance asked for, absolute (model units).
    pub tolerance: f64,
    pub implicit: FitStats,
    pub net: NetReport,
    pub sampling: SampleReport,
    pub patches: usize,
    pub control_points: usize,
    /// Control points per patch: min, max.
    pub control_points_per_patch: [usize; 2],
    pub shared_edges: usize,
    pub free_edges: usize,
    pub closed: bool,
    /// Deviation of the input points from the patch surfaces (point inversion).
    pub deviation: PatchDeviation,
    /// Normal jump across shared patch edges, in degrees.
    pub continuity: ContinuityReport,
    /// Patches whose normal turns away from the implicit's ([`crate::quality::folds`]).
    pub folds: FoldReport,
    /// Patch area farther than half a voxel (h / 2) from every point the implicit was fitted
    /// to: surface the data does not back (openings closed by extrapolation).
    pub support: SupportReport,
    /// The same at 1 % of the bounding-box diagonal: surface clearly away from the data
    /// (with `--close open` the bar is under 0.2 % of the area).
    pub support_far: SupportReport,
    /// How far the patches' control points leave the input's bounding box: a patch whose
    /// interpolation went wrong ([`crate::quality::control_net`]).
    pub control_net: crate::quality::control_net::ControlNetReport,
    /// The local hole filling run before the fit (`--fill-holes rbf|planar|flat`), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hole_fill: Option<crate::holes::FillReport>,
    /// How the STEP file represents the patches (set by the writer's caller): faces on
    /// surfaces extended by an apron for OpenCASCADE's point projection
    /// ([`crate::export::apron`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<crate::export::apron::ApronSummary>,
    /// The input's sharp features (`fit --features`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub features: Option<crate::features::detect::FeatureSummary>,
    /// Whether the sharp edges were kept, and why (`None` with `--sharp off`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sharp: Option<crate::features::SharpChoice>,
    /// The frame of the part's plane faces the crease-aligned net was built in (`--sharp` when
    /// kept, and the faces are not along the world axes; [`crate::features::grid_frame`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid_frame: Option<crate::features::grid_frame::GridFrame>,
    /// The crease-aligned net (`--sharp` when kept): what `--net` writes then.
    #[serde(skip)]
    pub crease_net: Option<QuadNet>,
    /// The crease-aligned net's nodes put on the creases and corners (`--sharp` when kept,
    /// `--crease-net voxel`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crease_nodes: Option<crate::polygonize::crease_nodes::CreaseNodesReport>,
    /// The crease-aligned net remeshed from the sharp implicit's mesh (`--sharp` when kept,
    /// `--crease-net remesh`): its sizes, creases, corners and quality.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crease_remesh: Option<crate::polygonize::remesh_net::RemeshNetReport>,
    /// The patches labelled by the smooth regions of `features` (`fit --features`), or the
    /// quads of the crease-aligned net by the regions its nodes were put between (`--sharp`,
    /// when kept).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub net_regions: Option<crate::features::net_regions::NetRegions>,
    pub timings: FitTimings,
}

/// Fits a patch network to a point cloud or mesh. `progress(stage, fraction)` is called as
/// stages start. The deviation is that of the input's (referenced) points.
pub fn fit(
    input: &Mesh,
    opts: &FitOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<(PatchNetwork, FitReport)> {
    let (pts, _) = input.referenced_points();
    fit_measured(input, &pts, opts, progress)
}

/// [`fit`] with the deviation measured at `measured` instead of the input's points: the scan
/// points when `input` is a scan with holes filled by added triangles, whose new vertices are
/// not measurements.
pub fn fit_measured(
    input: &Mesh,
    measured: &[nalgebra::Point3<f64>],
    opts: &FitOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<(PatchNetwork, FitReport)> {
    if !(opts.tolerance > 0.0 && opts.tolerance.is_finite()) {
        return Err(Error::InvalidOption(format!(
            "tolerance must be a positive fraction of the diagonal, got {}",
            opts.tolerance
        )));
    }
    let t_all = Instant::now();
    let mut timings = FitTimings::default();

    progress("normals", 0.0);
    let t = Instant::now();
    let op = oriented_points(input, opts.normal_neighbours)?;
    timings.normals = t.elapsed().as_secs_f64();

    // `--close`: decided here, from the oriented points, before the expensive stages.
    let enclosure = crate::openings::enclosure::escape_share(&op.points, &op.normals);
    let mut closure = crate::openings::choose(opts.close, enclosure);
    let open = closure.chosen == crate::openings::Close::Open;

    let features = match &opts.features {
        Some(fo) => {
            progress("features", 0.03);
            let t = Instant::now();
            let found = crate::features::detect::detect_oriented(input, Some(&op), fo)?;
            timings.features = t.elapsed().as_secs_f64();
            Some(found)
        }
        None => None,
    };

    // `--sharp`: the smooth regions, and whether their creases are kept.
    let (segmentation, sharp) = if opts.sharp == crate::features::SharpMode::Off {
        (None, None)
    } else {
        progress("features", 0.04);
        let t = Instant::now();
        let seg =
            crate::features::segment(input, &op, &crate::features::FeatureOptions::default())?;
        let choice = crate::features::sharp_choice::choose(opts.sharp, &seg.stats);
        timings.features += t.elapsed().as_secs_f64();
        (choice.sharp.then_some(seg), Some(choice))
    };

    progress("implicit", 0.05);
    let t = Instant::now();
    let fit_implicit = |open: bool| {
        let mut implicit_opts = opts.implicit.clone();
        implicit_opts.bridge_openings &= !open;
        PouImplicit::fit(&op.points, &op.normals, &implicit_opts)
    };
    let f = fit_implicit(open)?;
    timings.implicit = t.elapsed().as_secs_f64();
    let diag = f.diagonal();
    let bounds = Aabb::of(&op.points).ok_or_else(|| Error::Degenerate("no points".into()))?;

    progress("quad net", 0.3);
    let t = Instant::now();
    // The input points' tree: the net stage cuts an open net to them, the support is
    // measured against them.
    let data = KdTree::build(&op.points)?;
    let tol = opts.tolerance * diag;
    // The points the trial patches of an open net are measured against.
    let measured_sample = crate::openings::coverage::measured_sample(&op.points);
    let world = NetInputs {
        points: &op.points,
        data: &data,
        bounds,
        measured_sample: &measured_sample,
    };
    // `--sharp`: a part whose plane faces are not along the world axes gets its net built in
    // their frame ([`crate::features::grid_frame`]), so that its creases run along the grid.
    let grid_frame = segmentation
        .as_ref()
        .filter(|_| opts.crease_net == super::crease_net::CreaseNetRoute::Voxel)
        .and_then(crate::features::grid_frame::grid_frame);
    let framed = grid_frame
        .as_ref()
        .map(|g| FramedInputs::new(g.rotation(), &op.points));
    let framed = framed.transpose()?;
    let build_net = |f: &PouImplicit, close: crate::openings::Close| {
        net_stage(f, close, &world, opts, tol, diag)
    };
    let build_crease_net = |f: &PouImplicit, close: crate::openings::Close| match &framed {
        Some(fi) => {
            let g = crate::implicit::framed::Framed { f, r: fi.r };
            let (mut net, report, _, coverage) =
                net_stage(&g, close, &fi.inputs(), opts, tol, diag)?;
            let back = fi.r.inverse();
            for p in &mut net.nodes {
                *p = back * *p;
            }
            // The trial sampling lies in the frame; the sampling starts afresh.
            Ok((net, report, None, coverage))
        }
        None => net_stage(f, close, &world, opts, tol, diag),
    };
    let first = build_net(&f, closure.chosen);
    // `auto` closed a surface the data do not back, or could not build the closed net: fitted
    // again, open. When that fails too, the closed result (with its warning) or its error
    // stands.
    let because =
        crate::openings::decide::closed_shortfall(first.as_ref().map(|b| b.1.unsupported_share));
    let mut reopened = closure.clone();
    // The open implicit's time, counted under `implicit`, not `net`.
    let mut refit_secs = 0.0;
    let (f, (net, net_report, trial_sampling, coverage)) = match because {
        Some(because) if reopened.reopen(&because) => {
            progress("implicit", 0.05);
            let t_reopen = Instant::now();
            let open_fit = fit_implicit(true).and_then(|f| {
                refit_secs = t_reopen.elapsed().as_secs_f64();
                timings.implicit += refit_secs;
                progress("quad net", 0.3);
                let built = build_net(&f, reopened.chosen)?;
                Ok((f, built))
            });
            match (open_fit, first) {
                (Ok(done), _) => {
                    closure = reopened;
                    done
                }
                (Err(e), Ok(built)) => {
                    closure.reason = format!(
                        "{}; {because}, but fitting only the scanned surface failed ({e}), so \
                         the closed surface is kept",
                        closure.reason
                    );
                    (f, built)
                }
                (Err(_), Err(e)) => return Err(e),
            }
        }
        _ => (f, first?),
    };
    closure.coverage = coverage;
    timings.net = t.elapsed().as_secs_f64() - refit_secs;
    closure.unsupported_share = net_report.unsupported_share;
    closure.support_radius = crate::openings::SUPPORT_RADIUS * net_report.h;
    closure.trim = net_report.trim.clone();
    closure.rim = net_report.rim.clone();

    // `--sharp`: the crease-aligned net, on the sharp implicit (one function per region in the
    // cells a crease crosses), its nodes put on the creases and corners. The patches are still
    // built on the net above: joined with tangent continuity across a crease, patches on the
    // crease net fold (issue 37 makes them meet with G0 there).
    let crease_net = match &segmentation {
        Some(seg) => {
            progress("creases", 0.45);
            let t = Instant::now();
            let mut implicit_opts = opts.implicit.clone();
            implicit_opts.bridge_openings &= closure.chosen != crate::openings::Close::Open;
            // As in `reconstruct`: a mesh's points with their own region's normals.
            let (labels, normals, sides) = seg.labels_normals_and_sides(&op.points, &op.normals);
            let fs = PouImplicit::fit_with_sides(
                &op.points,
                &normals,
                &labels,
                sides.as_deref(),
                &implicit_opts,
            )?;
            let field = crate::features::sharp_field::SharpField { seg, f: &fs };
            let built = match opts.crease_net {
                super::crease_net::CreaseNetRoute::Remesh => {
                    let open = closure.chosen == crate::openings::Close::Open;
                    let r = super::crease_net::remeshed(&super::crease_net::RemeshInputs {
                        f: &fs,
                        implicit: &implicit_opts,
                        field: &field,
                        data: &op.points[..op.original],
                        tree: &data,
                        open_support: open
                            .then_some(crate::openings::SUPPORT_RADIUS * net_report.h),
                        quads: net_report.patches,
                    })?;
                    CreaseNet::Remeshed(r)
                }
                super::crease_net::CreaseNetRoute::Voxel => {
                    let (mut cnet, creport, _, _) = build_crease_net(&fs, closure.chosen)?;
                    let data_sides = crate::features::data_sides::DataSides {
                        seg,
                        radius: DATA_SIDES_RADIUS * creport.h,
                    };
                    let smooth = crate::polygonize::net_smooth::SmoothOptions::new(diag, creport.h);
                    let placed = crate::polygonize::crease_nodes::place_on_creases(
                        &mut cnet,
                        &fs,
                        &field,
                        Some(&data_sides),
                        &smooth,
                        &crate::polygonize::crease_nodes::CreaseNodeOptions::default(),
                    )?;
                    CreaseNet::Placed(placed, cnet, seg.regions.len())
                }
            };
            timings.creases = t.elapsed().as_secs_f64();
            Some(built)
        }
        None => None,
    };

    progress("sampling", 0.5);
    let t = Instant::now();
    let mut sample_opts = SampleOptions::new(tol, diag);
    sample_opts.near =
        (closure.chosen == crate::openings::Close::Open).then(|| NearData::for_net(&data, &net));
    if opts
        .apron_unit
        .is_some_and(|u| crate::export::apron::patch_needs_apron(net_report.h, u))
    {
        sample_opts.max_intervals = APRON_MAX_INTERVALS;
    }
    let sampling = sample_patches_from(&net, &f, &sample_opts, trial_sampling)?;
    timings.sampling = t.elapsed().as_secs_f64();
    let grids: Vec<&Vec<Vec<nalgebra::Point3<f64>>>> =
        sampling.patches.iter().map(|p| &p.points).collect();
    let [support, support_far] =
        surface_support_at(&grids, &data, [0.5 * net_report.h, 0.01 * diag]);

    progress("patches", 0.7);
    let t = Instant::now();
    let network = patch_network(&f, &net, &sampling)?;
    timings.patches = t.elapsed().as_secs_f64();

    progress("deviation", 0.85);
    let t = Instant::now();
    let deviation = deviation_from_patches(&network, measured, diag);
    timings.deviation = t.elapsed().as_secs_f64();

    progress("continuity", 0.95);
    let t = Instant::now();
    let continuity = normal_jumps(&network, opts.jump_samples);
    let sample_grids: Vec<SampleGrid<'_>> = sampling
        .patches
        .iter()
        .map(|p| SampleGrid {
            points: &p.points,
            normals: &p.normals,
            params_u: &p.params_u,
            params_v: &p.params_v,
        })
        .collect();
    let folds = folds(&network, &sample_grids);
    timings.continuity = t.elapsed().as_secs_f64();
    timings.total = t_all.elapsed().as_secs_f64();

    let counts: Vec<usize> = network
        .faces
        .iter()
        .map(|f| {
            let (a, b) = f.surface.ctrl_dims();
            a * b
        })
        .collect();
    let uses = network.edge_use_counts();
    let report = FitReport {
        input_points: measured.len(),
        normal_source: op.source,
        normals_flipped: op.flipped,
        normals_estimated: op.estimated,
        bbox_diagonal: diag,
        close: closure,
        tolerance: tol,
        implicit: f.stats().clone(),
        net: net_report,
        sampling: sampling.report.clone(),
        patches: network.faces.len(),
        control_points: counts.iter().sum(),
        control_points_per_patch: [
            counts.iter().copied().min().unwrap_or(0),
            counts.iter().copied().max().unwrap_or(0),
        ],
        shared_edges: uses.iter().filter(|&&u| u == 2).count(),
        free_edges: uses.iter().filter(|&&u| u == 1).count(),
        closed: network.closed,
        deviation,
        continuity,
        folds,
        support,
        support_far,
        control_net: crate::quality::control_net::control_net(&network, &bounds),
        hole_fill: None,
        step: None,
        net_regions: match &crease_net {
            Some(c) => {
                let (net, labels, regions) = c.labelled();
                Some(crate::features::net_regions::from_labels(
                    &net.quads,
                    labels.to_vec(),
                    regions,
                ))
            }
            None => features
                .as_ref()
                .map(|found| crate::features::net_regions::label_network(&network, found)),
        },
        sharp,
        grid_frame,
        crease_nodes: crease_net.as_ref().and_then(|c| match c {
            CreaseNet::Placed(p, _, _) => Some(p.report.clone()),
            CreaseNet::Remeshed(_) => None,
        }),
        crease_remesh: crease_net.as_ref().and_then(|c| match c {
            CreaseNet::Remeshed(r) => Some(r.report.clone()),
            CreaseNet::Placed(..) => None,
        }),
        crease_net: crease_net.map(CreaseNet::into_net),
        features: features.map(|found| found.summary()),
        timings,
    };
    Ok((network, report))
}

/// What the net stage works on, in one frame: the points (seeds of the voxel net), their tree,
/// their box, and the sample the trial patches of an open net are measured against.
struct NetInputs<'a> {
    points: &'a [nalgebra::Point3<f64>],
    data: &'a KdTree,
    bounds: Aabb,
    measured_sample: &'a [nalgebra::Point3<f64>],
}

/// The net stage's inputs turned into a part's frame (`--sharp`).
struct FramedInputs {
    /// World to frame.
    r: nalgebra::Rotation3<f64>,
    points: Vec<nalgebra::Point3<f64>>,
    data: KdTree,
    bounds: Aabb,
    measured_sample: Vec<nalgebra::Point3<f64>>,
}

impl FramedInputs {
    fn new(r: nalgebra::Rotation3<f64>, points: &[nalgebra::Point3<f64>]) -> Result<Self> {
        let points: Vec<_> = points.iter().map(|p| r * p).collect();
        let data = KdTree::build(&points)?;
        let bounds = Aabb::of(&points).ok_or_else(|| Error::Degenerate("no points".into()))?;
        let measured_sample = crate::openings::coverage::measured_sample(&points);
        Ok(FramedInputs {
            r,
            points,
            data,
            bounds,
            measured_sample,
        })
    }

    fn inputs(&self) -> NetInputs<'_> {
        NetInputs {
            points: &self.points,
            data: &self.data,
            bounds: self.bounds,
            measured_sample: &self.measured_sample,
        }
    }
}

/// The net, its report, the kept placement's trial sampling and (open fits) the coverage.
type NetStage = (
    QuadNet,
    NetReport,
    Option<PatchSampling>,
    Option<crate::openings::coverage::CoverageReport>,
);

/// The quad net stage on `f` ([`fit_net`], or [`fit_open_net`] when `close` is open), each grid
/// placement's net tried as patches: [`TRIAL_INTERVALS`] samples per side, no refinement, its
/// jumps over 5 degrees counted. The kept placement's trial sampling is the first round of the
/// real sampling.
fn net_stage<I: Implicit + Sync + ?Sized>(
    f: &I,
    close: crate::openings::Close,
    inp: &NetInputs<'_>,
    opts: &FitOptions,
    tol: f64,
    diag: f64,
) -> Result<NetStage> {
    let open = close == crate::openings::Close::Open;
    let trial = |net: &QuadNet| -> Option<(TrialScore, PatchSampling)> {
        let mut o = SampleOptions::new(tol, diag);
        o.near = open.then(|| NearData::for_net(inp.data, net));
        (o.min_intervals, o.max_intervals, o.max_rounds) = (TRIAL_INTERVALS, TRIAL_INTERVALS, 1);
        // Only the kept placement's patches are measured, when the sampling starts from them.
        o.measure = false;
        let sampling = sample_patches(net, f, &o).ok()?;
        let network = patch_network(f, net, &sampling).ok()?;
        let c = normal_jumps(&network, opts.jump_samples);
        let grids: Vec<_> = sampling.patches.iter().map(|p| &p.points).collect();
        let [far] = surface_support_at(&grids, inp.data, [0.01 * diag]);
        let points_p99 = open.then(|| {
            deviation_from_patches(&network, inp.measured_sample, diag)
                .stats
                .absolute
                .p99
        });
        let score = TrialScore {
            samples_over_5_deg: c.samples_over_5_deg,
            far_share: far.unsupported_fraction,
            points_p99,
        };
        Some((score, sampling))
    };
    if open {
        let (net, report, kept, coverage) = fit_open_net(
            f,
            inp.points,
            inp.data,
            &inp.bounds,
            opts.size,
            opts.size_given,
            &trial,
        )?;
        Ok((net, report, kept, Some(coverage)))
    } else {
        let (net, report, kept) = fit_net(
            f,
            inp.points,
            inp.data,
            &inp.bounds,
            opts.size,
            close,
            &trial,
        )?;
        Ok((net, report, kept, None))
    }
}

/// One bicubic patch per quad of `net` from its samples (seed 004 eq. 9-14): cross
/// derivatives aligned with the boundary splines, corner twists from the implicit
/// ([`super::cross_tangents`]), the grid interpolated; the patches sewn along the net's edges.
pub fn patch_network<I: Implicit + Sync + ?Sized>(
    f: &I,
    net: &QuadNet,
    sampling: &PatchSampling,
) -> Result<PatchNetwork> {
    type Prepared = (
        PatchGrid,
        Params,
        Params,
        [Corner; 4],
        [nalgebra::Vector3<f64>; 4],
    );
    let prepared: Vec<Prepared> = sampling
        .patches
        .par_iter()
        .map(|s| {
            let mut s = s.clone();
            let (pu, pv) = (Params::new(&s.params_u)?, Params::new(&s.params_v)?);
            let splines = BoundarySplines::of(&s, &pu, &pv)?;
            align_cross_derivatives(&mut s, &sampling.edges, &splines)?;
            let grid = PatchGrid {
                points: s.points,
                du_u0: s.tan_u0,
                du_u1: s.tan_u1,
                dv_v0: s.tan_v0,
                dv_v1: s.tan_v1,
                twist: Twist::Estimate,
            };
            let twists = corner_twists(f, &grid, &pu, &pv, &splines)?;
            let [v0, u1, v1, u0] = &splines.sides;
            let (ua, ub) = (pu.as_slice()[0], pu.as_slice()[pu.as_slice().len() - 1]);
            let (va, vb) = (pv.as_slice()[0], pv.as_slice()[pv.as_slice().len() - 1]);
            let suu = [
                v0.derivative(ua, 2),
                v0.derivative(ub, 2),
                v1.derivative(ua, 2),
                v1.derivative(ub, 2),
            ];
            let svv = [
                u0.derivative(va, 2),
                u1.derivative(va, 2),
                u0.derivative(vb, 2),
                u1.derivative(vb, 2),
            ];
            let corners = corners_of(&grid, suu, svv);
            Ok((grid, pu, pv, corners, twists))
        })
        .collect::<Result<Vec<_>>>()?;
    let corners: Vec<[Corner; 4]> = prepared.iter().map(|p| p.3).collect();
    let mut twists: Vec<[nalgebra::Vector3<f64>; 4]> = prepared.iter().map(|p| p.4).collect();
    let normal = |node: u32| {
        net.nodes
            .get(node as usize)
            .and_then(|p| f.gradient(p).try_normalize(0.0))
    };
    solve_vertex_twists(&sampling.patches, &corners, &normal, &mut twists);
    let inputs: Vec<PatchInput> = prepared
        .into_par_iter()
        .zip(twists.into_par_iter())
        .zip(sampling.patches.par_iter())
        .map(|(((mut grid, pu, pv, _, _), tw), s)| {
            grid.twist = Twist::Given(tw);
            let surface = BSplineSurface::interpolate_grid(&grid, &pu, &pv)?;
            Ok(PatchInput {
                surface,
                corners: s.corners,
                // Quads are counter-clockwise seen from outside, corners (0,0), (1,0), (1,1),
                // (0,1): S_u x S_v points out.
                same_sense: true,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    PatchNetwork::from_patches(net.nodes.clone(), inputs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::net_smooth::{project_and_smooth, SmoothOptions};
    use crate::polygonize::test_shapes::*;
    use crate::polygonize::voxel_net::{build_voxel_net, VoxelNetOptions};
    use crate::quality::continuity::normal_jumps;
    use nalgebra::Point3;

    /// A sphere at two intervals per side (where the cross derivatives keep their shear,
    /// `cross_tangents::MIN_SHARED_INTERVALS`) and at four (the shared direction field): the
    /// patches join with a normal jump far under the 5-degree bar.
    #[test]
    fn sphere_network_is_nearly_g1_at_any_sampling() {
        let s = Sphere {
            c: Point3::new(0.02, -0.01, 0.03),
            r: 1.0,
        };
        let b = crate::mesh::Aabb {
            min: Point3::new(-1.2, -1.2, -1.2),
            max: Point3::new(1.2, 1.2, 1.2),
        };
        let h = 0.25;
        let mut v = build_voxel_net(
            &s,
            &seeds_on(&s, s.c, 1.2, 10),
            &b,
            &VoxelNetOptions::new(h),
        )
        .unwrap();
        project_and_smooth(&mut v.net, &s, &SmoothOptions::new(b.diagonal(), h)).unwrap();
        for (min_intervals, coarse) in [(2, true), (4, false)] {
            let mut opt = SampleOptions::new(1e-3 * b.diagonal(), b.diagonal());
            opt.min_intervals = min_intervals;
            let sampling = sample_patches(&v.net, &s, &opt).unwrap();
            let most = sampling.report.interval_histogram.iter().map(|x| x.0).max();
            assert_eq!(
                most == Some(2),
                coarse,
                "{:?}",
                sampling.report.interval_histogram
            );
            let network = patch_network(&s, &v.net, &sampling).unwrap();
            // Measured: max 0.007, p95 0.003 at 2 intervals; max 0.46, p95 0.31 at 4 (the
            // shared field drops the shear an exact sphere's patches have).
            let c = normal_jumps(&network, 5);
            let (max, p95) = if coarse { (0.05, 0.02) } else { (1.0, 0.5) };
            assert!(
                c.all_deg.max < max && c.all_deg.p95 < p95,
                "{min_intervals}: {:?}",
                c.all_deg
            );
        }
    }
}
