//! Surface reconstruction (library part of `scansurf reconstruct`): a mesh or point cloud to a
//! closed triangle mesh through the partition-of-unity implicit (seed 003 sections 3-3.3).
//!
//! Stages: oriented points (face normals for a mesh; given, repaired or estimated normals for a
//! cloud) -> [`PouImplicit::fit`] -> sparse marching cubes at a resolution set by the point
//! spacing -> area-weighted centroid relaxation with re-projection (eq. 9) -> 1-to-4 subdivision
//! with projection until the mesh is within the tolerance of the implicit -> deviation of the
//! input points from the result (exact point-to-triangle distances).

use crate::features::sharp_field::SharpField;
use crate::features::{SharpChoice, SharpMode};
use crate::implicit::project::ProjectOptions;
use crate::implicit::{FitOptions, FitStats, PouImplicit};
use crate::mesh::shape::{triangle_shape, TriangleShape};
use crate::mesh::{Mesh, Topology};
use crate::metrics::{deviation, Deviation};
use crate::normals::{oriented_points, NormalSource};
use crate::polygonize::components::keep_supported_components;
use crate::polygonize::crease_mesh::{crease_mesh, CreaseMeshReport};
use crate::polygonize::crease_split::{split_at_creases, CreaseSplitOptions, CreaseSplitReport};
use crate::polygonize::{marching_cubes, refine, relax, RefineOptions, RefineReport};
use crate::{Error, Result};
use rayon::prelude::*;
use std::time::Instant;

/// Options of [`reconstruct`], with documented defaults.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReconstructOptions {
    /// Options of the implicit fit.
    pub fit: FitOptions,
    /// Marching-cubes cube edge as a multiple of the typical point spacing (default 1.5; the
    /// refinement then subdivides where the tolerance asks for it).
    pub resolution: f64,
    /// Absolute cube edge; overrides `resolution` when set.
    pub cell_size: Option<f64>,
    /// Relaxation rounds after marching cubes (default 2).
    pub relax_iterations: usize,
    /// Largest gap between the mesh and the implicit at triangle centroids (99th percentile over
    /// the triangles), as a fraction of the bounding-box diagonal; `None`
    /// (the default) means three times the fit tolerance.
    pub tolerance: Option<f64>,
    /// At most this many 1-to-4 subdivisions (default 2).
    pub max_subdivisions: usize,
    /// No subdivision beyond this many triangles (default 4,000,000).
    pub max_faces: usize,
    /// Neighbours for normal estimation and repair (default 12).
    pub normal_neighbours: usize,
    /// Measure the deviation of the input points from the result (default true).
    pub measure_deviation: bool,
    /// Keep sharp edges: the input is segmented into smooth regions ([`crate::features`]) and
    /// cells crossed by a crease get one function per region ([`crate::implicit::sharp`]):
    /// `On` whenever there is more than one region, `Auto` (the default) when the input looks
    /// machined ([`crate::features::sharp_choice`]), `Off` never. With a single region (an
    /// organic model) the result is the same in every mode.
    pub sharp: SharpMode,
    /// With the sharp edges kept: remesh the result into a light mesh with its edges on the
    /// creases and its vertices on the regions' surfaces ([`crate::polygonize::crease_mesh`];
    /// no subdivision before it). Default false; ignored (`remesh` None in the report) when
    /// the sharp edges are not kept.
    pub remesh: bool,
}

impl Default for ReconstructOptions {
    fn default() -> Self {
        ReconstructOptions {
            fit: FitOptions::default(),
            resolution: 1.5,
            cell_size: None,
            relax_iterations: 2,
            tolerance: None,
            max_subdivisions: 2,
            max_faces: 4_000_000,
            normal_neighbours: crate::normals::DEFAULT_NEIGHBOURS,
            measure_deviation: true,
            sharp: SharpMode::Auto,
            remesh: false,
        }
    }
}

/// Seconds spent per stage.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Timings {
    pub normals: f64,
    /// The segmentation into smooth regions (`sharp` other than off).
    pub features: f64,
    pub fit: f64,
    pub polygonize: f64,
    pub relax: f64,
    pub refine: f64,
    /// The split of the mesh on the creases (`sharp`).
    pub creases: f64,
    /// The crease-aligned remesh (`remesh`).
    pub remesh: f64,
    pub deviation: f64,
    pub total: f64,
}

/// What [`reconstruct`] did and how good the result is.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReconstructReport {
    /// Distinct input points (exact duplicates merged).
    pub input_points: usize,
    /// Points added on the triangles of a coarse input mesh.
    pub sample_points: usize,
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
    /// The result enclosed a negative volume and was turned inside out (inverted normals).
    pub flipped_output: bool,
    pub vertices: usize,
    pub faces: usize,
    pub closed_manifold: bool,
    /// The output triangles' angles: smallest, slivers and degenerate ones
    /// ([`crate::mesh::shape`]).
    pub triangles: TriangleShape,
    pub euler_characteristic: i64,
    pub components: usize,
    pub deviation: Option<Deviation>,
    /// Whether the sharp edges were kept, and why (`None` with `--sharp off`: not segmented).
    pub sharp: Option<SharpChoice>,
    /// The smooth regions the implicit was fitted with (`None` when the sharp edges were not
    /// kept).
    pub features: Option<crate::features::SegmentStats>,
    /// The mesh's edges split at the creases (`sharp`).
    pub creases: Option<CreaseSplitReport>,
    /// The crease-aligned remesh (`remesh` with the sharp edges kept).
    pub remesh: Option<CreaseMeshReport>,
    pub timings: Timings,
}

/// Typical point spacing: the mean over the points of the distance to their 8th nearest
/// neighbour divided by sqrt(8 / pi) (for an even sampling of a surface with spacing s, k
/// neighbours fill a disc of radius s sqrt(k / pi)). Less sensitive to jitter and clustering than
/// the nearest-neighbour distance.
pub fn mean_spacing(points: &[nalgebra::Point3<f64>], kd: &crate::spatial::KdTree) -> f64 {
    const K: usize = 8;
    if points.len() <= K {
        return 0.0;
    }
    let s: Vec<f64> = points
        .par_iter()
        .map(|p| kd.knn(p, K + 1).last().map_or(0.0, |x| x.1))
        .collect();
    s.iter().sum::<f64>() / s.len() as f64 / (K as f64 / std::f64::consts::PI).sqrt()
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

    let t = Instant::now();
    let (segmentation, sharp) = if opts.sharp == SharpMode::Off {
        (None, None)
    } else {
        progress("features", 0.1);
        let seg =
            crate::features::segment(input, &op, &crate::features::FeatureOptions::default())?;
        let choice = crate::features::sharp_choice::choose(opts.sharp, &seg.stats);
        (choice.sharp.then_some(seg), Some(choice))
    };
    timings.features = t.elapsed().as_secs_f64();
    progress("fit", 0.15);
    let t = Instant::now();
    let f = match &segmentation {
        Some(seg) => {
            // A cloud's points keep their own normals: one-sided normals beside a convex
            // crease face away from each other, and the hole bridging of the empty cells there
            // then widens its search to no end (make_parts' block from its cloud: 23 s against
            // 2.8 s, and a worse crease). A mesh's may get their own region's
            // (`features::MeshOptions::face_labels`).
            // Their crease cells are judged by their one-sided normals too, and fitted with
            // them where their own give a side no frame (`labels_normals_and_sides`).
            let (l, n, sn) = seg.labels_normals_and_sides(&op.points, &op.normals);
            PouImplicit::fit_with_sides(&op.points, &n, &l, sn.as_deref(), &opts.fit)?
        }
        None => PouImplicit::fit(&op.points, &op.normals, &opts.fit)?,
    };
    timings.fit = t.elapsed().as_secs_f64();
    let side_field = segmentation.as_ref().map(|seg| SharpField { seg, f: &f });
    let remesh = opts.remesh && side_field.is_some();
    // The remesh starts from the marching-cubes mesh: subdividing it first buys nothing.
    let mesh_opts = ReconstructOptions {
        max_subdivisions: if remesh { 0 } else { opts.max_subdivisions },
        ..opts.clone()
    };
    let SurfaceMesh {
        mesh,
        cell,
        spacing,
        marching_cubes: (mc_v, mc_f),
        removed_components,
        relax_failures,
        refine: refine_report,
        creases,
        flipped_output,
    } = surface_mesh(
        &f,
        &op.points[..op.original],
        side_field.as_ref(),
        &mesh_opts,
        &mut timings,
        progress,
    )?;
    let diag = f.diagonal();
    let (mesh, remesh_report) = match side_field.as_ref().filter(|_| remesh) {
        Some(field) => {
            progress("remesh", 0.8);
            let t = Instant::now();
            let (m, r) = crease_mesh(&mesh, &f, field)?;
            timings.remesh = t.elapsed().as_secs_f64();
            (m, Some(r))
        }
        None => (mesh, None),
    };

    progress("deviation", 0.9);
    let t = Instant::now();
    let dev = if opts.measure_deviation {
        Some(deviation(&op.points[..op.original], &mesh, diag)?)
    } else {
        None
    };
    timings.deviation = t.elapsed().as_secs_f64();
    let topo = Topology::build(&mesh);
    timings.total = t_all.elapsed().as_secs_f64();
    progress("done", 1.0);
    let report = ReconstructReport {
        input_points: op.original,
        sample_points: op.points.len() - op.original,
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
        flipped_output,
        vertices: mesh.positions.len(),
        faces: mesh.faces.len(),
        closed_manifold: topo.is_closed_manifold(),
        triangles: triangle_shape(&mesh),
        euler_characteristic: mesh.positions.len() as i64 - topo.edges.len() as i64
            + mesh.faces.len() as i64,
        components: topo.components.len(),
        deviation: dev,
        sharp,
        features: segmentation.map(|s| s.stats),
        creases,
        remesh: remesh_report,
        timings,
    };
    Ok((mesh, report))
}

/// The mesh of an implicit's zero set and what making it took.
pub struct SurfaceMesh {
    pub mesh: Mesh,
    /// Marching-cubes cube edge and the points' typical spacing it was set from.
    pub cell: f64,
    pub spacing: f64,
    /// Vertices and faces of the marching-cubes mesh.
    pub marching_cubes: (usize, usize),
    pub removed_components: usize,
    pub relax_failures: usize,
    pub refine: RefineReport,
    /// The split at the creases (with a sharp field).
    pub creases: Option<CreaseSplitReport>,
    /// The mesh enclosed a negative volume and was turned inside out.
    pub flipped_output: bool,
}

/// Meshes the zero set of `f` (the stages between the fit and the deviation of
/// [`reconstruct`]): sparse marching cubes, the components `data` (the input points) do not
/// support dropped, centroid relaxation, subdivision to the tolerance, and with a sharp
/// `side_field` the split of the triangles across its creases; turned outward when it enclosed
/// a negative volume. `fit --sharp` meshes its sharp implicit with it too.
pub fn surface_mesh(
    f: &PouImplicit,
    data: &[nalgebra::Point3<f64>],
    side_field: Option<&SharpField>,
    opts: &ReconstructOptions,
    timings: &mut Timings,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<SurfaceMesh> {
    let diag = f.diagonal();
    let spacing = mean_spacing(f.points().0, f.kdtree());
    let mesh_tol = opts.tolerance.unwrap_or(3.0 * opts.fit.tolerance);

    progress("polygonize", 0.4);
    let t = Instant::now();
    // Never finer than 1/2000 of the diagonal: clustered points (a coarse mesh with a few dense
    // spots) would otherwise set a grid fine everywhere.
    let cell = match opts.cell_size {
        Some(c) => c,
        None => opts.resolution * spacing.max(diag / 2000.0),
    };
    let root = f.domain();
    let dom = crate::mesh::Aabb {
        min: root.min,
        max: root.max(),
    };
    let mesh = marching_cubes(f, f.points().0, &dom, cell)?;
    if mesh.faces.is_empty() {
        return Err(Error::Degenerate(
            "the implicit surface has no zero crossing near the points".into(),
        ));
    }
    // Spurious sheets beside the surface are the nearest surface for no input point.
    // A part with fewer points than half a fit needs is not reconstructible: noise or outliers.
    let min_votes = (opts.fit.min_points / 2).max(data.len() / 5_000);
    let (mut mesh, removed_components) = keep_supported_components(mesh, data, min_votes)?;
    timings.polygonize = t.elapsed().as_secs_f64();
    let (mc_v, mc_f) = (mesh.positions.len(), mesh.faces.len());

    progress("relax", 0.55);
    let t = Instant::now();
    let proj = ProjectOptions::for_diagonal(diag);
    let relax_failures = relax(&mut mesh, f, opts.relax_iterations, &proj);
    timings.relax = t.elapsed().as_secs_f64();

    progress("refine", 0.7);
    let t = Instant::now();
    let ropts = RefineOptions {
        tolerance: mesh_tol * diag,
        quantile: 0.99,
        max_levels: opts.max_subdivisions,
        relax_iterations: 0,
        max_faces: opts.max_faces,
    };
    // Sharp: the triangles across a crease count too; they keep the gap quantile high, and
    // the extra level they cost puts the split points below closer together (without them
    // make_parts' wedge.stl gets 99 k triangles instead of 1.5 M, but its crease p95 goes
    // from 1.6e-4 to 9.9e-4 of the diagonal).
    let (mut mesh, refine_report) = refine(mesh, f, &ropts, &proj);
    timings.refine = t.elapsed().as_secs_f64();
    // Sharp: the triangles that cut across a crease split where its two faces meet.
    let t = Instant::now();
    let creases =
        side_field.map(|field| split_at_creases(&mut mesh, field, &CreaseSplitOptions::default()));
    timings.creases = t.elapsed().as_secs_f64();
    // Global orientation check: a closed result must enclose a positive volume (it would not if
    // the normals, and so the implicit's sign, came out inverted).
    let flipped_output = mesh.signed_volume() < 0.0;
    if flipped_output {
        for tri in &mut mesh.faces {
            tri.swap(1, 2);
        }
    }

    Ok(SurfaceMesh {
        mesh,
        cell,
        spacing,
        marching_cubes: (mc_v, mc_f),
        removed_components,
        relax_failures,
        refine: refine_report,
        creases,
        flipped_output,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use nalgebra::{Point3, Vector3};

    /// Deterministic pseudo-random numbers in [-1, 1) (a 64-bit LCG; no crate needed for tests).
    pub(crate) struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    pub(crate) enum Shape {
        Sphere(f64),
        Torus(f64, f64),
    }

    impl Shape {
        pub(crate) fn distance(&self, x: &Point3<f64>) -> f64 {
            match *self {
                Shape::Sphere(r) => x.coords.norm() - r,
                Shape::Torus(big, small) => {
                    let q = (x.x * x.x + x.y * x.y).sqrt() - big;
                    (q * q + x.z * x.z).sqrt() - small
                }
            }
        }
        /// Points with normals; `noise` is the amplitude (absolute) of a displacement along the
        /// normal; `hole` removes the points in a patch.
        pub(crate) fn sample(&self, n: usize, noise: f64, hole: bool) -> Mesh {
            let mut rng = Lcg(12345);
            let mut pts = Vec::new();
            let mut nrm = Vec::new();
            match *self {
                Shape::Sphere(r) => {
                    let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
                    for i in 0..n {
                        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                        if hole && z > 0.25f64.cos() {
                            continue;
                        }
                        let s = (1.0 - z * z).sqrt();
                        let t = ga * i as f64;
                        let d = Vector3::new(s * t.cos(), s * t.sin(), z);
                        pts.push(Point3::from(d * (r + noise * rng.next())));
                        nrm.push(d);
                    }
                }
                Shape::Torus(big, small) => {
                    let nv = ((n as f64) * small / (big + small)).sqrt().max(8.0) as usize;
                    let nu = n / nv;
                    for i in 0..nu {
                        for j in 0..nv {
                            let u =
                                (i as f64 + 0.3 * rng.next()) / nu as f64 * std::f64::consts::TAU;
                            let v =
                                (j as f64 + 0.3 * rng.next()) / nv as f64 * std::f64::consts::TAU;
                            let (su, cu) = u.sin_cos();
                            let (sv, cv) = v.sin_cos();
                            // Missing patch on the outer equator around u = 0.
                            if hole
                                && !(0.2..=std::f64::consts::TAU - 0.2).contains(&u)
                                && cv > 0.95
                            {
                                continue;
                            }
                            let d = Vector3::new(cv * cu, cv * su, sv);
                            let c = Vector3::new(big * cu, big * su, 0.0);
                            pts.push(Point3::from(c + d * (small + noise * rng.next())));
                            nrm.push(d);
                        }
                    }
                }
            }
            Mesh::from_points(pts, Some(nrm))
        }
    }

    /// Runs the reconstruction and checks the bars: closed manifold of the right Euler
    /// characteristic, every output vertex (on the zero set) within 1e-3 of the diagonal of the
    /// true surface.
    fn check(shape: &Shape, cloud: Mesh, euler: i64) -> ReconstructReport {
        let opts = ReconstructOptions::default();
        let (mesh, rep) = reconstruct(&cloud, &opts, &mut |_, _| {}).unwrap();
        assert!(rep.closed_manifold, "{rep:?}");
        assert_eq!(rep.components, 1, "{rep:?}");
        assert_eq!(rep.euler_characteristic, euler, "{rep:?}");
        assert!(mesh.signed_volume() > 0.0);
        let worst = mesh
            .positions
            .iter()
            .map(|p| shape.distance(p).abs())
            .fold(0.0, f64::max)
            / rep.diagonal;
        assert!(
            worst < 1e-3,
            "zero set {worst:.3e} from the surface; {rep:?}"
        );
        rep
    }

    #[test]
    fn sphere_clean() {
        let s = Shape::Sphere(1.0);
        check(&s, s.sample(2000, 0.0, false), 2);
    }

    #[test]
    fn sphere_noisy() {
        let s = Shape::Sphere(1.0);
        let rep = check(&s, s.sample(2000, 1e-3, false), 2);
        assert!(rep.deviation.unwrap().relative.mean < 2e-4);
    }

    #[test]
    fn sphere_with_missing_patch() {
        let s = Shape::Sphere(1.0);
        check(&s, s.sample(2000, 0.0, true), 2);
    }

    #[test]
    fn torus_clean() {
        let t = Shape::Torus(1.0, 0.35);
        check(&t, t.sample(4500, 0.0, false), 0);
    }

    #[test]
    fn torus_noisy() {
        let t = Shape::Torus(1.0, 0.35);
        check(&t, t.sample(4500, 5e-4, false), 0);
    }

    #[test]
    fn torus_with_missing_patch() {
        let t = Shape::Torus(1.0, 0.35);
        check(&t, t.sample(4500, 0.0, true), 0);
    }

    #[test]
    fn sphere_without_normals() {
        let s = Shape::Sphere(1.0);
        let mut c = s.sample(2000, 0.0, false);
        c.normals = None;
        let rep = check(&s, c, 2);
        assert_eq!(rep.normal_source, NormalSource::Estimated);
    }

    #[test]
    fn inverted_normals_still_give_an_outward_mesh() {
        let s = Shape::Sphere(1.0);
        let mut c = s.sample(800, 0.0, false);
        if let Some(n) = c.normals.as_mut() {
            n.iter_mut().for_each(|v| *v = -*v);
        }
        let (m, rep) = reconstruct(&c, &ReconstructOptions::default(), &mut |_, _| {}).unwrap();
        assert!(rep.closed_manifold);
        assert!(m.signed_volume() > 0.0);
    }

    #[test]
    fn result_does_not_depend_on_thread_count() {
        let t = Shape::Sphere(1.0);
        let mut c = t.sample(800, 0.0, true);
        c.normals = None;
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| reconstruct(&c, &ReconstructOptions::default(), &mut |_, _| {}))
                .unwrap()
                .0
        };
        let a = run(1);
        let b = run(3);
        assert_eq!(a.faces, b.faces);
        assert_eq!(a.positions, b.positions);
    }

    #[test]
    fn duplicates_outliers_and_far_offsets() {
        let s = Shape::Sphere(1.0);
        let base = s.sample(1000, 0.0, false);
        // Every point three times, plus a few outliers, all far from the origin.
        let off = nalgebra::Vector3::new(1e5, -2e5, 3e5);
        let mut pts = Vec::new();
        let mut nrm = Vec::new();
        let bn = base.normals.clone().unwrap();
        for (p, n) in base.positions.iter().zip(&bn) {
            for _ in 0..3 {
                pts.push(p + off);
                nrm.push(*n);
            }
        }
        for k in 0..5 {
            pts.push(Point3::new(1.6 + 0.1 * k as f64, 0.3, -0.2) + off);
            nrm.push(nalgebra::Vector3::x());
        }
        let cloud = Mesh::from_points(pts, Some(nrm));
        let (m, rep) = reconstruct(&cloud, &ReconstructOptions::default(), &mut |_, _| {}).unwrap();
        assert!(rep.closed_manifold, "{rep:?}");
        assert_eq!(rep.euler_characteristic, 2, "{rep:?}");
        let worst = m
            .positions
            .iter()
            .map(|p| s.distance(&(p - off)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-3 * rep.diagonal * 2.0, "{worst} {rep:?}");
    }

    #[test]
    fn tiny_inputs_do_not_panic() {
        let o = ReconstructOptions::default();
        for n in [1usize, 2, 5, 12, 40] {
            let c = Shape::Sphere(1.0).sample(n, 0.0, false);
            if let Ok((m, r)) = reconstruct(&c, &o, &mut |_, _| {}) {
                assert!(r.closed_manifold || m.faces.is_empty());
            }
            let mut c = c;
            c.normals = None;
            let _ = reconstruct(&c, &o, &mut |_, _| {});
        }
        // Non-finite normals are left out (or estimated), never a panic.
        let mut c = Shape::Sphere(1.0).sample(500, 0.0, false);
        if let Some(n) = c.normals.as_mut() {
            n[3] = nalgebra::Vector3::new(f64::NAN, 0.0, 0.0);
            n[4] = nalgebra::Vector3::zeros();
        }
        let (_, r) = reconstruct(&c, &o, &mut |_, _| {}).unwrap();
        assert!(r.closed_manifold);
    }

    #[test]
    fn bad_input_is_an_error() {
        let o = ReconstructOptions::default();
        assert!(reconstruct(&Mesh::default(), &o, &mut |_, _| {}).is_err());
        let flat = Mesh::from_points(
            (0..100)
                .map(|i| Point3::new((i % 10) as f64, (i / 10) as f64, 0.0))
                .collect(),
            None,
        );
        // A plane has no inside: either an error or a closed result, never a panic.
        if let Ok((m, r)) = reconstruct(&flat, &o, &mut |_, _| {}) {
            assert!(r.closed_manifold || m.faces.is_empty());
        }
        let bad = ReconstructOptions {
            resolution: 0.0,
            ..Default::default()
        };
        let s = Shape::Sphere(1.0).sample(500, 0.0, false);
        assert!(reconstruct(&s, &bad, &mut |_, _| {}).is_err());
    }
}
