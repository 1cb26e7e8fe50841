//! Hole filling: find the holes of a triangle mesh and close them with new triangles that
//! continue the surrounding surface.
//!
//! Two methods, one per seed paper:
//!
//! - [`FillMethod::Rbf`] (default, seed 000): a local implicit surface through the hole's
//!   neighbourhood, a recursive-subdivision mesh of the ring's mean plane projected onto it, and
//!   area-weighted relaxation ([`fill_rbf`]).
//! - [`FillMethod::Planar`] (seed 002): constrained Delaunay triangulation of the projected ring,
//!   1-to-4 subdivision with circular-arc midpoints and circular-arc smoothing ([`fill_planar`]).
//!
//! plus [`FillMethod::Flat`], the planar triangulation with straight midpoints, as the baseline
//! the others are measured against.
//!
//! The result keeps every original vertex and face exactly (same indices, first) and appends the
//! fill; the fill is oriented like the mesh around it and never repeats an existing edge, so a
//! closed manifold with holes becomes a closed manifold. [`FillReport`] lists every loop: size,
//! what was done, the method used (and why, when it fell back), triangles added, deviation from
//! the fitted surface, time.
//!
//! ```
//! use scansurf::holes::{fill_holes, FillOptions};
//! use scansurf::holes::{cut::cut_ball, testing::cube_sphere};
//! use nalgebra::Point3;
//!
//! let sphere = cube_sphere(12, 1.0);
//! let cut = cut_ball(&sphere, &Point3::new(0.0, 0.0, 1.0), 0.4);
//! let (filled, report) = fill_holes(&cut, &FillOptions::default())?;
//! assert_eq!(report.holes_filled, 1);
//! assert!(filled.topology().is_closed_manifold());
//! # Ok::<(), scansurf::Error>(())
//! ```

// `!(x > t)` is used on purpose throughout: unlike `x <= t` it is also true when x is NaN, so
// degenerate geometry takes the rejecting branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod arc;
pub mod cut;
pub mod detect;
pub mod fill_planar;
pub mod fill_rbf;
pub mod flip;
pub mod intersect;
pub mod neighbourhood;
pub mod normal_fit;
pub mod patch;
pub mod plane;
pub mod rbf_local;
pub mod recursive_mesh;
pub mod relax;
pub mod split;
pub mod subdivide_fill;
pub mod testing;

pub use detect::{detect_holes, DetectedLoop, LoopKind};
pub use fill_planar::PlanarOptions;
pub use fill_rbf::RbfOptions;
pub use plane::PlaneKind;

use crate::error::{Error, Result};
use crate::implicit::Implicit;
use crate::mesh::{normals::vertex_normals, Mesh, Topology};
use nalgebra::Vector3;
use neighbourhood::{mean_edge_length_around, VertexFaces};
use patch::{key, Patch};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::time::Instant;

/// How holes are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FillMethod {
    /// Local thin-plate RBF surface, recursive subdivision, projection, relaxation (seed 000).
    #[default]
    Rbf,
    /// Planar constrained Delaunay, circular-arc subdivision and smoothing (seed 002).
    Planar,
    /// Planar constrained Delaunay with straight subdivision: a flat fill (the baseline).
    Flat,
}

impl std::str::FromStr for FillMethod {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "rbf" => Ok(FillMethod::Rbf),
            "planar" => Ok(FillMethod::Planar),
            "flat" => Ok(FillMethod::Flat),
            other => Err(Error::InvalidOption(format!(
                "unknown hole filling method '{other}' (expected rbf, planar or flat)"
            ))),
        }
    }
}

/// Options of [`fill_holes`], with documented defaults (`FillOptions::default()`).
#[derive(Debug, Clone, PartialEq)]
pub struct FillOptions {
    /// Fill method. Default: [`FillMethod::Rbf`].
    pub method: FillMethod,
    /// Leave holes whose size (bounding-box diagonal of the ring) exceeds this open: openings by
    /// design. Default: `None` (fill all).
    pub max_size: Option<f64>,
    /// Leave the outer border of an open sheet open (the loop [`Topology`] flags). Default: true.
    pub keep_border: bool,
    /// Projection direction to try first for every ring (seed 002 section 3.2); rings that fold
    /// under it use the automatic planes. Default: `None`.
    pub direction: Option<Vector3<f64>>,
    /// When a method fails on a hole, try the other one (rbf <-> planar). Default: true.
    pub fallback: bool,
    /// Measure each fill's deviation from the local RBF surface (fitted for the purpose when the
    /// method does not fit one). Default: true.
    pub measure_deviation: bool,
    /// Fill holes in parallel (rayon). The result does not depend on it. Default: true.
    pub parallel: bool,
    /// Use quadric-fitted normals around the hole ([`normal_fit`]) instead of the face-averaged
    /// ones, which lean away from the hole at its border. Default: true.
    pub fit_normals: bool,
    /// Options of the RBF method.
    pub rbf: RbfOptions,
    /// Options of the planar method.
    pub planar: PlanarOptions,
}

impl Default for FillOptions {
    fn default() -> Self {
        FillOptions {
            method: FillMethod::Rbf,
            max_size: None,
            keep_border: true,
            direction: None,
            fallback: true,
            measure_deviation: true,
            parallel: true,
            fit_normals: true,
            rbf: RbfOptions::default(),
            planar: PlanarOptions::default(),
        }
    }
}

impl FillOptions {
    /// Checks the options' ranges.
    pub fn validate(&self) -> Result<()> {
        if let Some(m) = self.max_size {
            if !(m >= 0.0) {
                return Err(Error::InvalidOption(format!(
                    "max size {m} must be zero or positive"
                )));
            }
        }
        if let Some(d) = self.direction {
            let l = d.norm();
            if !(l > 0.0 && l.is_finite()) {
                return Err(Error::InvalidOption(
                    "projection direction must be a non-zero finite vector".into(),
                ));
            }
        }
        if !(self.rbf.offset > 0.0 && self.rbf.offset.is_finite()) {
            return Err(Error::InvalidOption(format!(
                "RBF offset {} must be positive",
                self.rbf.offset
            )));
        }
        if !(self.rbf.weights.c1 >= 0.0 && self.rbf.weights.c2 >= 0.0)
            || self.rbf.weights.c1 + self.rbf.weights.c2 <= 0.0
        {
            return Err(Error::InvalidOption(
                "split weights C1, C2 must be non-negative and not both zero".into(),
            ));
        }
        if !(self.planar.ratio > 0.0 && self.planar.ratio.is_finite()) {
            return Err(Error::InvalidOption(format!(
                "subdivision ratio {} must be positive",
                self.planar.ratio
            )));
        }
        Ok(())
    }
}

/// What happened to a loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum HoleStatus {
    Filled,
    /// Left open: the outer border of an open sheet.
    OuterBorder,
    /// Left open: larger than `max_size`.
    TooLarge,
    /// Every method tried failed; see `error`.
    Failed,
}

/// One loop in the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HoleReport {
    /// Index of the boundary loop in [`Topology::loops`].
    pub loop_index: usize,
    /// Part of a twisted loop (0 for a simple loop).
    pub part: usize,
    pub twisted: bool,
    /// Vertices on the ring.
    pub boundary_vertices: usize,
    pub perimeter: f64,
    /// Bounding-box diagonal of the ring: the size `max_size` is compared with.
    pub size: f64,
    pub status: HoleStatus,
    /// Method that produced the fill.
    pub method: Option<FillMethod>,
    /// Why the requested method was not used, when it failed and the other one filled.
    pub fallback: Option<String>,
    /// The projection plane of each part (more than one when the ring folded and was cut).
    pub planes: Vec<PlaneKind>,
    pub vertices_added: usize,
    pub triangles_added: usize,
    /// Largest |f| / |grad f| over the fill's face centroids and new vertices, f the local RBF
    /// surface (the vertices are on it by construction with the RBF method, and not measured).
    pub max_deviation: Option<f64>,
    /// Root mean square of the same.
    pub rms_deviation: Option<f64>,
    /// Pairs of triangles where the fill cuts through the mesh near the hole or through itself
    /// (0 unless both methods gave such fills).
    pub self_intersections: usize,
    /// Wall time spent on this hole, seconds.
    pub time_s: f64,
    /// Why it failed.
    pub error: Option<String>,
}

/// The report of [`fill_holes`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FillReport {
    pub method: FillMethod,
    /// Simple loops considered (twisted loops count once per part).
    pub loops: usize,
    pub holes_filled: usize,
    pub holes_left_open: usize,
    pub holes_failed: usize,
    pub vertices_added: usize,
    pub triangles_added: usize,
    /// Total wall time, seconds.
    pub time_s: f64,
    pub holes: Vec<HoleReport>,
}

/// Fits the implicit surface of one hole: interpolation points and their values (0 on the
/// surface, positive offsets outside; seed 000 eq. 1-2). The default is
/// [`rbf_local::fit_hole_rbf`]; any interpolant will do (e.g. the shared `implicit::rbf`).
pub type SurfaceFitter =
    dyn Fn(&[nalgebra::Point3<f64>], &[f64]) -> Result<Box<dyn Implicit>> + Sync;

/// The default [`SurfaceFitter`]: the local thin-plate RBF.
pub fn default_fitter(
    points: &[nalgebra::Point3<f64>],
    values: &[f64],
) -> Result<Box<dyn Implicit>> {
    if points.len() > rbf_local::MAX_POINTS {
        return Err(Error::Degenerate(format!(
            "the hole's neighbourhood has {} interpolation points, more than the local RBF \
             takes ({}); use the planar method or fewer rings",
            points.len(),
            rbf_local::MAX_POINTS
        )));
    }
    Ok(Box::new(rbf_local::fit_hole_rbf(points, values)?))
}

/// Fills the holes of `mesh` (see the module doc). Errors: a mesh without faces, non-finite
/// coordinates, face indices out of range, invalid options. A hole that cannot be filled is
/// reported as failed and left open; it is not an error.
pub fn fill_holes(mesh: &Mesh, opts: &FillOptions) -> Result<(Mesh, FillReport)> {
    fill_holes_with(mesh, opts, &default_fitter)
}

/// [`fill_holes`] with another surface fitter for the RBF method and the deviation measure.
pub fn fill_holes_with(
    mesh: &Mesh,
    opts: &FillOptions,
    fitter: &SurfaceFitter,
) -> Result<(Mesh, FillReport)> {
    let t0 = Instant::now();
    opts.validate()?;
    validate_mesh(mesh)?;
    let topo = Topology::build(mesh);
    let normals = vertex_normals(mesh);
    let vf = VertexFaces::build(mesh);
    let loops = detect_holes(mesh, &topo, opts.keep_border, opts.max_size);
    let ctx = Context {
        mesh,
        normals: &normals,
        vf: &vf,
        opts,
        fitter,
    };
    let outcomes: Vec<(HoleReport, Option<Patch>)> = if opts.parallel {
        loops.par_iter().map(|l| ctx.process(l)).collect()
    } else {
        loops.iter().map(|l| ctx.process(l)).collect()
    };

    let mut out = mesh.clone();
    let mut report = FillReport {
        method: opts.method,
        loops: loops.len(),
        holes_filled: 0,
        holes_left_open: 0,
        holes_failed: 0,
        vertices_added: 0,
        triangles_added: 0,
        time_s: 0.0,
        holes: Vec::with_capacity(outcomes.len()),
    };
    for (hr, patch) in outcomes {
        match hr.status {
            HoleStatus::Filled => report.holes_filled += 1,
            HoleStatus::Failed => report.holes_failed += 1,
            _ => report.holes_left_open += 1,
        }
        if let Some(p) = patch {
            append_patch(&mut out, &p);
            report.vertices_added += hr.vertices_added;
            report.triangles_added += hr.triangles_added;
        }
        report.holes.push(hr);
    }
    report.time_s = t0.elapsed().as_secs_f64();
    Ok((out, report))
}

/// Rejects what the algorithms cannot work on.
fn validate_mesh(mesh: &Mesh) -> Result<()> {
    if mesh.faces.is_empty() {
        return Err(Error::Degenerate(
            "hole filling needs a triangle mesh; this one has no faces".into(),
        ));
    }
    if let Some(i) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(Error::Degenerate(format!(
            "vertex {i} has a non-finite coordinate"
        )));
    }
    let n = mesh.positions.len();
    if mesh
        .faces
        .iter()
        .any(|f| f.iter().any(|&v| v as usize >= n))
    {
        return Err(Error::Degenerate(
            "a face uses a vertex index past the vertex list".into(),
        ));
    }
    if n >= u32::MAX as usize {
        return Err(Error::Degenerate("too many vertices".into()));
    }
    Ok(())
}

/// Appends a filled patch: its new vertices after the mesh's, its faces after the mesh's.
fn append_patch(out: &mut Mesh, p: &Patch) {
    let base = out.positions.len() as u32;
    let ring = p.ring_len() as u32;
    let map = |v: u32| {
        if v < ring {
            p.global[v as usize]
        } else {
            base + (v - ring)
        }
    };
    out.positions
        .extend_from_slice(&p.positions[ring as usize..]);
    if let Some(n) = out.normals.as_mut() {
        n.extend_from_slice(&p.normals[ring as usize..]);
    }
    out.faces
        .extend(p.faces.iter().map(|f| [map(f[0]), map(f[1]), map(f[2])]));
}

/// What every hole's fill reads.
struct Context<'a> {
    mesh: &'a Mesh,
    normals: &'a [Vector3<f64>],
    vf: &'a VertexFaces,
    opts: &'a FillOptions,
    fitter: &'a SurfaceFitter,
}

impl Context<'_> {
    /// Fills one loop (or reports why not).
    fn process(&self, l: &DetectedLoop) -> (HoleReport, Option<Patch>) {
        let t0 = Instant::now();
        let mut hr = HoleReport {
            loop_index: l.loop_index,
            part: l.part,
            twisted: l.twisted,
            boundary_vertices: l.vertices.len(),
            perimeter: l.perimeter,
            size: l.size,
            status: HoleStatus::Filled,
            method: None,
            fallback: None,
            planes: Vec::new(),
            vertices_added: 0,
            triangles_added: 0,
            max_deviation: None,
            rms_deviation: None,
            self_intersections: 0,
            time_s: 0.0,
            error: None,
        };
        match l.kind {
            LoopKind::OuterBorder => hr.status = HoleStatus::OuterBorder,
            LoopKind::TooLarge => hr.status = HoleStatus::TooLarge,
            LoopKind::Hole => {}
        }
        if hr.status != HoleStatus::Filled {
            hr.time_s = t0.elapsed().as_secs_f64();
            return (hr, None);
        }
        let result = self.fill(l, &mut hr);
        hr.time_s = t0.elapsed().as_secs_f64();
        match result {
            Ok(p) => {
                hr.vertices_added = p.positions.len() - p.ring_len();
                hr.triangles_added = p.faces.len();
                (hr, Some(p))
            }
            Err(e) => {
                hr.status = HoleStatus::Failed;
                hr.error = Some(e.to_string());
                (hr, None)
            }
        }
    }

    /// The ring of a loop as a fresh patch (fill order: the reverse of the boundary walk).
    fn ring_patch(&self, l: &DetectedLoop) -> Patch {
        let global: Vec<u32> = l.vertices.iter().rev().copied().collect();
        let local: HashMap<u32, u32> = global
            .iter()
            .enumerate()
            .map(|(i, &g)| (g, i as u32))
            .collect();
        let mut mesh_edges = HashSet::new();
        for (i, &g) in global.iter().enumerate() {
            for &f in self.vf.of(g) {
                for &u in &self.mesh.faces[f as usize] {
                    if u != g {
                        if let Some(&j) = local.get(&u) {
                            mesh_edges.insert(key(i as u32, j));
                        }
                    }
                }
            }
        }
        let normals = if self.opts.fit_normals {
            normal_fit::fitted_normals(self.mesh, self.vf, self.normals, &global)
        } else {
            global.iter().map(|&g| self.normals[g as usize]).collect()
        };
        Patch::from_ring(
            global
                .iter()
                .map(|&g| self.mesh.positions[g as usize])
                .collect(),
            normals,
            global,
            mesh_edges,
        )
    }

    /// Fits the local surface of a hole (seed 000 section 2.1).
    fn fit_surface(&self, l: &DetectedLoop, target: f64) -> Result<Box<dyn Implicit>> {
        let (pts, vals) = fill_rbf::hole_samples(
            self.mesh,
            self.normals,
            self.vf,
            &l.vertices,
            self.opts.rbf.rings,
            self.opts.rbf.offset * target,
            self.opts.fit_normals,
        );
        (self.fitter)(&pts, &vals)
    }

    /// Fills with the requested method, falling back to the other one on failure. A fill must
    /// be manifold and must not cut through the mesh near the hole or through itself; when both
    /// methods give self-intersecting fills, the one with fewer intersections is kept (a closed
    /// mesh with a flaw is more use downstream than a hole) and the count is reported.
    fn fill(&self, l: &DetectedLoop, hr: &mut HoleReport) -> Result<Patch> {
        let o = self.opts;
        let base = self.ring_patch(l);
        let target = mean_edge_length_around(self.mesh, self.vf, &l.vertices)
            .unwrap_or(l.perimeter / l.vertices.len().max(1) as f64);
        let first = self.fill_checked(o.method, l, &base, target, hr);
        let (patch, crossings) = match first {
            Ok((p, 0)) => (p, 0),
            Ok((p, n)) if !o.fallback || o.method == FillMethod::Flat => (p, n),
            Err(e) if !o.fallback || o.method == FillMethod::Flat => return Err(e),
            first => {
                let other = if o.method == FillMethod::Rbf {
                    FillMethod::Planar
                } else {
                    FillMethod::Rbf
                };
                let why = match &first {
                    Ok((_, n)) => format!("{n} self-intersections"),
                    Err(e) => e.to_string(),
                };
                let mut hr2 = hr.clone();
                match (first, self.fill_checked(other, l, &base, target, &mut hr2)) {
                    (Ok((p, n)), Ok((_, m))) if n <= m => (p, n),
                    (_, Ok((p, m))) => {
                        *hr = hr2;
                        hr.fallback = Some(format!("{} failed: {why}", method_name(o.method)));
                        (p, m)
                    }
                    (Ok((p, n)), Err(_)) => (p, n),
                    (Err(e), Err(e2)) => {
                        return Err(Error::Numerical(format!(
                            "{}: {e}; {}: {e2}",
                            method_name(o.method),
                            method_name(other)
                        )))
                    }
                }
            }
        };
        hr.self_intersections = crossings;
        if o.measure_deviation && hr.max_deviation.is_none() {
            if let Ok(surface) = self.fit_surface(l, target) {
                measure(&patch, surface.as_ref(), true, hr);
            }
        }
        Ok(patch)
    }

    /// One method, checked: manifold (else an error), and the number of self-intersections.
    fn fill_checked(
        &self,
        method: FillMethod,
        l: &DetectedLoop,
        base: &Patch,
        target: f64,
        hr: &mut HoleReport,
    ) -> Result<(Patch, usize)> {
        let p = self.fill_with(method, l, base, target, hr)?;
        p.check_topology().map_err(|m| {
            Error::Numerical(format!("internal error: the fill is not manifold ({m})"))
        })?;
        let n = intersect::patch_intersections(self.mesh, self.vf, &p);
        Ok((p, n))
    }

    fn fill_with(
        &self,
        method: FillMethod,
        l: &DetectedLoop,
        base: &Patch,
        target: f64,
        hr: &mut HoleReport,
    ) -> Result<Patch> {
        let o = self.opts;
        let mut p = base.clone();
        match method {
            FillMethod::Rbf => {
                let surface = self.fit_surface(l, target)?;
                let info = fill_rbf::fill_on_surface(
                    &mut p,
                    surface.as_ref(),
                    target,
                    l.size,
                    o.direction,
                    &o.rbf,
                )?;
                hr.planes = info.projection.planes;
                if o.measure_deviation {
                    measure(&p, surface.as_ref(), false, hr);
                }
            }
            FillMethod::Planar | FillMethod::Flat => {
                let popts = PlanarOptions {
                    circular_arc: method == FillMethod::Planar && o.planar.circular_arc,
                    ..o.planar
                };
                let proj = fill_planar::fill_planar(&mut p, o.direction, &popts)?;
                hr.planes = proj.planes;
                hr.max_deviation = None;
                hr.rms_deviation = None;
            }
        }
        hr.method = Some(method);
        Ok(p)
    }
}

fn method_name(m: FillMethod) -> &'static str {
    match m {
        FillMethod::Rbf => "rbf",
        FillMethod::Planar => "planar",
        FillMethod::Flat => "flat",
    }
}

/// Deviation of the fill from `surface` at its face centroids and, with `vertices`, its new
/// vertices (which the RBF method has put on the surface already).
fn measure(p: &Patch, surface: &dyn Implicit, vertices: bool, hr: &mut HoleReport) {
    let mut d: Vec<f64> = if vertices {
        p.positions[p.ring_len()..]
            .iter()
            .map(|x| crate::implicit::project::distance_estimate(surface, x))
            .collect()
    } else {
        Vec::with_capacity(p.faces.len())
    };
    for f in &p.faces {
        let c = nalgebra::Point3::from(
            (p.positions[f[0] as usize].coords
                + p.positions[f[1] as usize].coords
                + p.positions[f[2] as usize].coords)
                / 3.0,
        );
        d.push(crate::implicit::project::distance_estimate(surface, &c));
    }
    if d.is_empty() {
        return;
    }
    let max = d.iter().copied().fold(0.0, f64::max);
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    hr.max_deviation = Some(max);
    hr.rms_deviation = Some(rms);
}

#[cfg(test)]
mod tests {
    use super::cut::cut_ball;
    use super::testing::cube_sphere;
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn errors_and_options() {
        assert!(fill_holes(&Mesh::default(), &FillOptions::default()).is_err());
        let mut m = cube_sphere(4, 1.0);
        m.positions[0].x = f64::NAN;
        assert!(fill_holes(&m, &FillOptions::default()).is_err());
        let m = cube_sphere(4, 1.0);
        let bad = FillOptions {
            direction: Some(Vector3::zeros()),
            ..Default::default()
        };
        assert!(fill_holes(&m, &bad).is_err());
        assert_eq!("Planar".parse::<FillMethod>().unwrap(), FillMethod::Planar);
        assert!("poisson".parse::<FillMethod>().is_err());
        // A closed mesh: nothing to do, same mesh back.
        let (out, rep) = fill_holes(&m, &FillOptions::default()).unwrap();
        assert_eq!(out, m);
        assert_eq!(rep.loops, 0);
    }

    #[test]
    fn both_methods_close_a_sphere_hole_and_keep_the_original() {
        let s = cube_sphere(10, 1.0);
        let cut = cut_ball(&s, &Point3::new(0.3, 0.2, 0.93), 0.45);
        assert_eq!(cut.topology().loops.len(), 1);
        for method in [FillMethod::Rbf, FillMethod::Planar, FillMethod::Flat] {
            let opts = FillOptions {
                method,
                ..Default::default()
            };
            let (out, rep) = fill_holes(&cut, &opts).unwrap();
            assert_eq!(rep.holes_filled, 1, "{method:?}: {rep:?}");
            assert_eq!(rep.holes[0].method, Some(method));
            assert!(out.topology().is_closed_manifold(), "{method:?}");
            assert_eq!(&out.positions[..cut.positions.len()], &cut.positions[..]);
            assert_eq!(&out.faces[..cut.faces.len()], &cut.faces[..]);
            assert!(rep.holes[0].max_deviation.is_some());
            let json = serde_json::to_string(&rep).unwrap();
            assert!(json.contains("\"status\":\"filled\""));
        }
        // max_size leaves it open.
        let opts = FillOptions {
            max_size: Some(0.1),
            ..Default::default()
        };
        let (out, rep) = fill_holes(&cut, &opts).unwrap();
        assert_eq!(rep.holes[0].status, HoleStatus::TooLarge);
        assert_eq!(out, cut);
    }

    /// Two holes touching at a vertex (a pinched, "twisted" boundary there) in an open sheet:
    /// both close, the sheet's border stays open, and the shared vertex becomes manifold.
    #[test]
    fn holes_touching_at_a_vertex_in_an_open_sheet() {
        let n = 12;
        let mut m = testing::saddle(n, 1.0, 0.2);
        let quad = |i: usize, j: usize| 2 * (j * n + i);
        // Squares (5,5) and (6,6) share the grid vertex (6,6).
        let (a, b) = (quad(5, 5), quad(6, 6));
        m.faces.drain(b..b + 2);
        m.faces.drain(a..a + 2);
        let before = m.topology();
        assert_eq!(before.non_manifold_vertices.len(), 1);
        for method in [FillMethod::Rbf, FillMethod::Planar] {
            let opts = FillOptions {
                method,
                fallback: false,
                ..Default::default()
            };
            let (out, rep) = fill_holes(&m, &opts).unwrap();
            assert_eq!(rep.holes_filled, 2, "{method:?}: {rep:#?}");
            assert_eq!(rep.holes_left_open, 1);
            let t = out.topology();
            assert_eq!(t.loops.len(), 1, "{method:?}");
            assert!(t.loops[0].outer_border);
            assert!(t.non_manifold_vertices.is_empty() && t.non_manifold_edges.is_empty());
            assert_eq!(t.misoriented_edges, 0);
        }
    }

    /// Another surface fitter plugs in: here the exact sphere, whatever the samples.
    #[test]
    fn custom_fitter_is_used() {
        struct Sphere;
        impl Implicit for Sphere {
            fn value(&self, x: &Point3<f64>) -> f64 {
                x.coords.norm() - 1.0
            }
        }
        let s = cube_sphere(16, 1.0);
        let cut = cut_ball(&s, &Point3::new(0.0, 0.0, 1.0), 0.5);
        let fitter =
            |_: &[Point3<f64>], _: &[f64]| -> Result<Box<dyn Implicit>> { Ok(Box::new(Sphere)) };
        let (out, rep) = fill_holes_with(&cut, &FillOptions::default(), &fitter).unwrap();
        assert_eq!(rep.holes_filled, 1);
        let worst = out.positions[cut.positions.len()..]
            .iter()
            .map(|p| (p.coords.norm() - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
    }
}
