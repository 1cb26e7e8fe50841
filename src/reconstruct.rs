//! Surface reconstruction (library part of `scansurf reconstruct`): a mesh or point cloud to a
//! closed triangle mesh through the partition-of-unity implicit (seed 003 sections 3-3.3).
//!
//! Stages: oriented points (face normals for a mesh; given, repaired or estimated normals for a
//! cloud) -> [`PouImplicit::fit`] -> sparse marching cubes at a resolution set by the point
//! spacing -> area-weighted centroid relaxation with re-projection (eq. 9) -> 1-to-4 subdivision
//! with projection until the mesh is within the tolerance of the implicit -> deviation of the
//! input points from the result (exact point-to-triangle distances).

use crate::implicit::project::ProjectOptions;
use crate::implicit::{FitOptions, FitStats, PouImplicit};
use crate::mesh::{Mesh, Topology};
use crate::metrics::{deviation, Deviation};
use crate::normals::{oriented_points, NormalSource};
use crate::polygonize::components::keep_supported_components;
use crate::polygonize::{marching_cubes, refine, relax, RefineOptions, RefineReport};
use crate::{Error, Result};
use rayon::prelude::*;
use std::time::Instant;

/// Options of [`reconstruct`], with documented defaults.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReconstructOptions {
    /// Options of the implicit fit.
    pub fit: FitOptions,
    /// Marching-cubes cube edge as a multiple of the mean point spacing (default 1.0).
    pub resolution: f64,
    /// Absolute cube edge; overrides `resolution` when set.
    pub cell_size: Option<f64>,
    /// Relaxation rounds after marching cubes (default 2).
    pub relax_iterations: usize,
    /// Largest gap between the mesh and the implicit at triangle centroids and edge midpoints
    /// (99th percentile over the triangles), as a fraction of the bounding-box diagonal; `None`
    /// (the default) means three times the fit tolerance.
    pub tolerance: Option<f64>,
    /// At most this many 1-to-4 subdivisions (default 2).
    pub max_subdivisions: usize,
    /// Neighbours for normal estimation and repair (default 12).
    pub normal_neighbours: usize,
    /// Measure the deviation of the input points from the result (default true).
    pub measure_deviation: bool,
}

impl Default for ReconstructOptions {
    fn default() -> Self {
        ReconstructOptions {
            fit: FitOptions::default(),
            resolution: 1.0,
            cell_size: None,
            relax_iterations: 2,
            tolerance: None,
            max_subdivisions: 2,
            normal_neighbours: 12,
            measure_deviation: true,
        }
    }
}

/// Seconds spent per stage.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Timings {
    pub normals: f64,
    pub fit: f64,
    pub polygonize: f64,
    pub relax: f64,
    pub refine: f64,
    pub deviation: f64,
    pub total: f64,
}

/// What [`reconstruct`] did and how good the result is.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReconstructReport {
    pub input_points: usize,
    pub normal_source: NormalSource,
    pub normals_flipped: usize,
    pub normals_estimated: usize,
    pub mean_spacing: f64,
    pub diagonal: f64,
    pub fit: FitStats,
    pub cell_size: f64,
    pub marching_cubes_vertices: usize,
    pub marching_cubes_faces: usize,
    /// Components of the marching-cubes mesh dropped as unsupported by the data.
    pub removed_components: usize,
    pub relax_failures: usize,
    pub refine: RefineReport,
    pub vertices: usize,
    pub faces: usize,
    pub closed_manifold: bool,
    pub euler_characteristic: i64,
    pub components: usize,
    pub deviation: Option<Deviation>,
    pub timings: Timings,
}

/// Mean distance from each point to its nearest other point.
pub fn mean_spacing(points: &[nalgebra::Point3<f64>], kd: &crate::spatial::KdTree) -> f64 {
    if points.len() < 2 {
        return 0.0;
    }
    let s: Vec<f64> = points
        .par_iter()
        .map(|p| kd.knn(p, 2).get(1).map_or(0.0, |x| x.1))
        .collect();
    s.iter().sum::<f64>() / s.len() as f64
}

/// Reconstructs a closed mesh from a mesh (its referenced vertices and face normals) or a point
/// cloud. `progress(stage, fraction_done)` is called between stages.
pub fn reconstruct(
    input: &Mesh,
    opts: &ReconstructOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<(Mesh, ReconstructReport)> {
    if !(opts.resolution > 0.0 && opts.resolution.is_finite()) {
        return Err(Error::InvalidOption("resolution must be positive".into()));
    }
    let mesh_tol = opts.tolerance.unwrap_or(3.0 * opts.fit.tolerance);
    if !(mesh_tol > 0.0 && mesh_tol.is_finite()) {
        return Err(Error::InvalidOption("tolerance must be positive".into()));
    }
    let t_all = Instant::now();
    let mut timings = Timings::default();

    progress("normals", 0.0);
    let t = Instant::now();
    let op = oriented_points(input, opts.normal_neighbours)?;
    timings.normals = t.elapsed().as_secs_f64();

    progress("fit", 0.1);
    let t = Instant::now();
    let f = PouImplicit::fit(&op.points, &op.normals, &opts.fit)?;
    timings.fit = t.elapsed().as_secs_f64();
    let diag = f.diagonal();
    let spacing = mean_spacing(f.points().0, f.kdtree());

    progress("polygonize", 0.4);
    let t = Instant::now();
    let cell = match opts.cell_size {
        Some(c) => c,
        None => opts.resolution * spacing.max(1e-6 * diag),
    };
    let root = f.domain();
    let dom = crate::mesh::Aabb {
        min: root.min,
        max: root.max(),
    };
    let mesh = marching_cubes(&f, f.points().0, &dom, cell)?;
    if mesh.faces.is_empty() {
        return Err(Error::Degenerate(
            "the implicit surface has no zero crossing near the points".into(),
        ));
    }
    // Spurious sheets beside the surface are the nearest surface for no input point.
    let min_votes = 3usize.max(op.points.len() / 10_000);
    let (mut mesh, removed_components) = keep_supported_components(mesh, &op.points, min_votes)?;
    timings.polygonize = t.elapsed().as_secs_f64();
    let (mc_v, mc_f) = (mesh.positions.len(), mesh.faces.len());

    progress("relax", 0.55);
    let t = Instant::now();
    let proj = ProjectOptions::for_diagonal(diag);
    let relax_failures = relax(&mut mesh, &f, opts.relax_iterations, &proj);
    timings.relax = t.elapsed().as_secs_f64();

    progress("refine", 0.7);
    let t = Instant::now();
    let ropts = RefineOptions {
        tolerance: mesh_tol * diag,
        quantile: 0.99,
        max_levels: opts.max_subdivisions,
        relax_iterations: 1,
    };
    let (mesh, refine_report) = refine(mesh, &f, &ropts, &proj);
    timings.refine = t.elapsed().as_secs_f64();

    progress("deviation", 0.9);
    let t = Instant::now();
    let dev = if opts.measure_deviation {
        Some(deviation(&op.points, &mesh, diag)?)
    } else {
        None
    };
    timings.deviation = t.elapsed().as_secs_f64();
    let topo = Topology::build(&mesh);
    timings.total = t_all.elapsed().as_secs_f64();
    progress("done", 1.0);
    let report = ReconstructReport {
        input_points: op.points.len(),
        normal_source: op.source,
        normals_flipped: op.flipped,
        normals_estimated: op.estimated,
        mean_spacing: spacing,
        diagonal: diag,
        fit: f.stats().clone(),
        cell_size: cell,
        marching_cubes_vertices: mc_v,
        marching_cubes_faces: mc_f,
        removed_components,
        relax_failures,
        refine: refine_report,
        vertices: mesh.positions.len(),
        faces: mesh.faces.len(),
        closed_manifold: topo.is_closed_manifold(),
        euler_characteristic: mesh.positions.len() as i64 - topo.edges.len() as i64
            + mesh.faces.len() as i64,
        components: topo.components.len(),
        deviation: dev,
        timings,
    };
    Ok((mesh, report))
}
