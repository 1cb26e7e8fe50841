//! Sketch modelling (seed 001, Cordier, Seo & Cho 2006): a 2D drawing of closed contours in the
//! z = 0 plane to a closed 3D mesh.
//!
//! Stages: [`input`] (SVG / JSON) -> [`contour`] (resampling, filtering, intersections, holes,
//! panels and their depth order; section 3) -> [`chordal_axis`] per panel (section 4.1) ->
//! [`skeleton3d`] (depths and slopes by constrained least squares, section 4.4, solved by
//! [`lsi`]) -> [`volume`] (blended spherical implicits fitted to the silhouette, section 5) ->
//! the crate's marching cubes, relaxation and subdivision (as in `reconstruct`).
//!
//! All the geometry is computed in normalised units (drawing centred, bounding-box diagonal 1)
//! and mapped back at the end; the viewer looks down the -z axis, so "in front" is larger z.

pub mod chordal_axis;
pub mod completion;
pub mod contour;
pub mod input;
pub mod lsi;
pub mod paneling;
pub mod skeleton3d;
pub mod volume;

pub use input::{read_drawing, Drawing};
pub use skeleton3d::Weights;
pub use volume::SketchImplicit;

use crate::implicit::project::ProjectOptions;
use crate::implicit::Implicit;
use crate::mesh::{Aabb, Mesh, Topology};
use crate::polygonize::{marching_cubes, refine, relax, RefineOptions};
use crate::{Error, Result};
use nalgebra::{Point2, Point3};
use std::time::Instant;

/// Options of [`sketch`]; lengths are fractions of the drawing's bounding-box diagonal.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SketchOptions {
    /// Energy weights of the skeleton (default 1, 0.3, 0.3).
    pub weights: Weights,
    /// Contour resampling step (default 1/150).
    pub spacing: f64,
    /// Distance between skeleton vertices (default 1/40).
    pub skeleton_spacing: f64,
    /// Smallest gap between the surfaces of overlapping parts, d_MinSurf (default 0.02).
    pub min_gap: f64,
    /// Marching-cubes cube edge (default 1/90).
    pub cell: f64,
    /// Relaxation rounds after marching cubes (default 2).
    pub relax_iterations: usize,
    /// At most this many 1-to-4 subdivisions with projection (default 1).
    pub max_subdivisions: usize,
    /// A contour that crosses itself outlines a folded sheet: put the fold (the doubly
    /// covered layer) behind the rest instead of in front (default false).
    pub fold_behind: bool,
}

impl Default for SketchOptions {
    fn default() -> Self {
        SketchOptions {
            weights: Weights::default(),
            spacing: 1.0 / 150.0,
            skeleton_spacing: 1.0 / 40.0,
            min_gap: 0.02,
            cell: 1.0 / 90.0,
            relax_iterations: 2,
            max_subdivisions: 1,
            fold_behind: false,
        }
    }
}

/// One panel in the report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PartReport {
    /// Index of the drawing contour that outlines it.
    pub contour: usize,
    /// Layer of a folded (self-crossing) contour, 1 otherwise.
    pub level: i32,
    pub holes: usize,
    pub skeleton_vertices: usize,
    pub skeleton_edges: usize,
    /// Mean and range of the skeleton depth z (drawing units).
    pub mean_z: f64,
    pub min_z: f64,
    pub max_z: f64,
    /// Mean (x, y) of the outline, drawing units (y up).
    pub centroid: [f64; 2],
}

/// What [`sketch`] did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SketchReport {
    pub contours: usize,
    pub crossings: usize,
    /// Self-crossings of folded contours.
    pub self_crossings: usize,
    /// Open strokes ending on closed contours, and the contours completed from them (after
    /// the closed ones in the contour numbering), with the matchings searched.
    pub t_junctions: usize,
    pub completed: Vec<completion::Completed>,
    pub completion_search: usize,
    /// (front, back) part pairs.
    pub overlaps: Vec<(usize, usize)>,
    pub parts: Vec<PartReport>,
    pub depth_constraints: usize,
    pub active_constraints: usize,
    pub options: SketchOptions,
    pub vertices: usize,
    pub faces: usize,
    pub closed_manifold: bool,
    pub components: usize,
    pub euler_characteristic: i64,
    /// Sum of the component genera, (2 components - chi) / 2.
    pub genus: i64,
    /// Projected mesh area / drawing area, and intersection over union (rasterised, 256^2).
    pub silhouette_area_ratio: f64,
    pub silhouette_iou: f64,
    /// Smallest distance between the surfaces of overlapping parts (drawing units; null
    /// without overlaps), and the constraint gap that gave it (fraction of the diagonal).
    pub surface_gap: Option<f64>,
    pub constraint_gap: f64,
    /// Diagonal of the drawing's bounding box (the unit of the fractional options).
    pub drawing_diagonal: f64,
    pub seconds: f64,
}

/// Builds the closed mesh of a drawing.
pub fn sketch(drawing: &Drawing, opts: &SketchOptions) -> Result<(Mesh, SketchReport)> {
    opts.weights.check()?;
    for (name, v) in [
        ("spacing", opts.spacing),
        ("skeleton spacing", opts.skeleton_spacing),
        ("min gap", opts.min_gap),
        ("cell", opts.cell),
    ] {
        if !(v > 0.0 && v < 1.0) {
            return Err(Error::InvalidOption(format!(
                "{name} must be a fraction of the diagonal in (0, 1), got {v}"
            )));
        }
    }
    let t0 = Instant::now();
    let all: Vec<Point2<f64>> = drawing
        .contours
        .iter()
        .chain(&drawing.strokes)
        .flatten()
        .copied()
        .collect();
    let (lo, hi) = all.iter().fold(
        (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        ),
        |(a, b), p| (a.inf(p), b.sup(p)),
    );
    let diag = (hi - lo).norm();
    if !(diag > 0.0 && diag.is_finite()) {
        return Err(Error::Degenerate("the drawing has no extent".into()));
    }
    let center = Point2::from((lo.coords + hi.coords) / 2.0);
    // Both contours and strokes in the unit frame: centred, divided by the diagonal.
    let to_unit = |curves: &[Vec<Point2<f64>>]| -> Vec<Vec<Point2<f64>>> {
        curves
            .iter()
            .map(|c| {
                c.iter()
                    .map(|p| Point2::from((p - center) / diag))
                    .collect()
            })
            .collect()
    };
    let norm = to_unit(&drawing.contours);
    // Occluded contours: open strokes ending on closed contours are completed behind them
    // (T-junctions, section 3.2), and the occluders go in front of the completed contours.
    let strokes = to_unit(&drawing.strokes);
    let done = completion::complete(&norm, &strokes, opts.spacing)?;
    let mut norm = norm;
    norm.extend(done.contours.iter().cloned());
    let mut over = drawing.over.clone();
    over.extend(done.over.iter().copied());
    let an = contour::analyse(&norm, &over, opts.spacing, opts.fold_behind)?;
    let skels: Vec<chordal_axis::Skeleton2> = an
        .parts
        .iter()
        .map(|p| chordal_axis::chordal_axis(p, opts.skeleton_spacing))
        .collect::<Result<_>>()?;
    // d_MinSurf holds at the skeleton vertices (eq. 3); the blended surfaces between them can
    // come closer. Measure the real gap on the mesh and, where it falls short, solve again with
    // the constraint gap widened by the shortfall (at most GAP_ROUNDS times).
    let mut gap = opts.min_gap;
    let mut built = build_volume(&an, &skels, opts, gap, diag, center)?;
    let mut surface_gap = part_gap(&built.mesh, &built.f, &an.overlaps);
    for _ in 0..GAP_ROUNDS {
        if surface_gap >= opts.min_gap * (1.0 - 1e-3) {
            break;
        }
        gap += 1.5 * (opts.min_gap - surface_gap);
        built = build_volume(&an, &skels, opts, gap, diag, center)?;
        surface_gap = part_gap(&built.mesh, &built.f, &an.overlaps);
    }
    let Built {
        mut mesh,
        sk3,
        part_reports,
        ..
    } = built;
    let (area_ratio, iou) = silhouette_match(&an.parts, &mesh);
    for p in &mut mesh.positions {
        *p = Point3::new(p.x * diag + center.x, p.y * diag + center.y, p.z * diag);
    }
    mesh.normals = None;
    let topo = Topology::build(&mesh);
    let chi = mesh.positions.len() as i64 - topo.edges.len() as i64 + mesh.faces.len() as i64;
    let comps = topo.components.len() as i64;
    let report = SketchReport {
        contours: drawing.contours.len(),
        crossings: an.crossings,
        self_crossings: an.self_crossings,
        t_junctions: 2 * drawing.strokes.len(),
        completed: done.completed.clone(),
        completion_search: done.searched,
        overlaps: an.overlaps.clone(),
        parts: part_reports,
        depth_constraints: sk3.constraints,
        active_constraints: sk3.active,
        options: opts.clone(),
        vertices: mesh.positions.len(),
        faces: mesh.faces.len(),
        closed_manifold: topo.is_closed_manifold(),
        components: topo.components.len(),
        euler_characteristic: chi,
        genus: (2 * comps - chi) / 2,
        silhouette_area_ratio: area_ratio,
        silhouette_iou: iou,
        surface_gap: surface_gap.is_finite().then_some(surface_gap * diag),
        constraint_gap: gap,
        drawing_diagonal: diag,
        seconds: t0.elapsed().as_secs_f64(),
    };
    Ok((mesh, report))
}

/// Rounds of widening the depth-constraint gap until the surfaces are d_MinSurf apart.
const GAP_ROUNDS: usize = 3;

/// The volume of the parts and its mesh (normalised units), for one constraint gap.
struct Built {
    mesh: Mesh,
    f: SketchImplicit,
    sk3: skeleton3d::Skeleton3,
    part_reports: Vec<PartReport>,
}

/// Skeleton depths (section 4.4, constraint gap `gap`), sphere blends (section 5) and their
/// polygonization (marching cubes, relaxation, subdivision as in `reconstruct`).
fn build_volume(
    an: &contour::Analysis,
    skels: &[chordal_axis::Skeleton2],
    opts: &SketchOptions,
    gap: f64,
    diag: f64,
    center: Point2<f64>,
) -> Result<Built> {
    let sk3 = skeleton3d::solve(skels, &an.overlaps, &opts.weights, gap)?;
    if sk3.z.iter().any(|z| !z.is_finite()) {
        return Err(Error::Numerical(
            "the skeleton depths came out non-finite".into(),
        ));
    }

    // Spherical implicits per part, fitted to the silhouette (section 5).
    let mut jobs = Vec::with_capacity(skels.len());
    let mut seeds = Vec::new();
    let mut centers_all = Vec::new();
    let mut rmax = 0.0f64;
    let mut off = 0;
    let mut part_reports = Vec::new();
    for (part, sk) in an.parts.iter().zip(skels) {
        let z = &sk3.z[off..off + sk.nodes.len()];
        off += sk.nodes.len();
        let centers: Vec<Point3<f64>> = sk
            .nodes
            .iter()
            .zip(z)
            .map(|(p, z)| Point3::new(p.x, p.y, *z))
            .collect();
        let mut sil = Vec::new();
        for lp in part.loops() {
            for q in lp {
                let k = (0..sk.nodes.len())
                    .min_by(|&a, &b| {
                        (sk.nodes[a] - q)
                            .norm_squared()
                            .total_cmp(&(sk.nodes[b] - q).norm_squared())
                    })
                    .unwrap_or(0);
                sil.push(Point3::new(q.x, q.y, z[k]));
            }
        }
        rmax = sk.radius.iter().copied().fold(rmax, f64::max);
        let (zmin, zmax) = z
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
        let cen = part
            .outer
            .iter()
            .fold(nalgebra::Vector2::zeros(), |s, p| s + p.coords)
            / part.outer.len() as f64;
        part_reports.push(PartReport {
            contour: part.contour,
            level: part.level,
            holes: part.holes.len(),
            skeleton_vertices: sk.nodes.len(),
            skeleton_edges: sk.edges.len(),
            mean_z: z.iter().sum::<f64>() / z.len().max(1) as f64 * diag,
            min_z: zmin * diag,
            max_z: zmax * diag,
            centroid: [cen.x * diag + center.x, cen.y * diag + center.y],
        });
        centers_all.extend(centers.iter().copied());
        // Seeds for marching cubes: points from the nearest centre out to 1.5 times the
        // silhouette point, so some seed cube straddles the surface even where the fit is off.
        for q in &sil {
            let c = centers
                .iter()
                .min_by(|a, b| (*a - q).norm_squared().total_cmp(&(*b - q).norm_squared()))
                .copied()
                .unwrap_or(*q);
            for k in 1..=12 {
                seeds.push(c + (q - c) * (k as f64 / 8.0));
            }
        }
        jobs.push((centers, &sk.radius, sil));
    }
    // The parts' fits are independent: in parallel (each one is sequential, so the result
    // does not depend on the thread count).
    let blends: Vec<volume::SphereBlend> = {
        use rayon::prelude::*;
        jobs.into_par_iter()
            .map(|(centers, radius, sil)| volume::SphereBlend::fit(centers, radius, &sil))
            .collect::<Result<_>>()?
    };
    for (k, blend) in blends.iter().enumerate() {
        if blend.weights.iter().any(|w| !w.is_finite()) || blend.weights.iter().all(|w| *w <= 0.0) {
            return Err(Error::Numerical(format!(
                "the sphere weights of part {k} did not fit the silhouette"
            )));
        }
    }
    let f = SketchImplicit { parts: blends };

    // Polygonize as `reconstruct` does: marching cubes, relaxation, subdivision.
    let mut bb = Aabb::of(&centers_all)
        .ok_or_else(|| Error::Degenerate("the drawing has no skeleton".into()))?;
    let pad = 2.0 * rmax + 3.0 * opts.cell;
    bb.min -= nalgebra::Vector3::repeat(pad);
    bb.max += nalgebra::Vector3::repeat(pad);
    let mut mesh = marching_cubes(&f, &seeds, &bb, opts.cell)?;
    if mesh.faces.is_empty() {
        let (wmin, wmax) = f.parts[0]
            .weights
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), w| (a.min(*w), b.max(*w)));
        return Err(Error::Degenerate(format!(
            "the fitted volume has no surface near the drawing (weights {wmin:.3e}..{wmax:.3e}, f = {:.3e} at a centre, {:.3e} on the outline)",
            f.value(&centers_all[0]),
            f.value(&seeds[7])
        )));
    }
    let proj = ProjectOptions::for_diagonal(1.0);
    relax(&mut mesh, &f, opts.relax_iterations, &proj);
    let ropts = RefineOptions {
        tolerance: 2e-4,
        quantile: 0.99,
        max_levels: opts.max_subdivisions,
        relax_iterations: 0,
        max_faces: 2_000_000,
    };
    let (mut mesh, _) = refine(mesh, &f, &ropts, &proj);
    if mesh.signed_volume() < 0.0 {
        for t in &mut mesh.faces {
            t.swap(1, 2);
        }
    }
    Ok(Built {
        mesh,
        f,
        sk3,
        part_reports,
    })
}

/// Smallest distance between the surfaces of two overlapping parts (normalised units;
/// infinity without overlaps): every vertex goes to the part whose implicit is lowest there,
/// and the vertices of each (front, back) pair are compared through a k-d tree.
fn part_gap(mesh: &Mesh, f: &SketchImplicit, overlaps: &[(usize, usize)]) -> f64 {
    use rayon::prelude::*;
    if overlaps.is_empty() || f.parts.len() < 2 {
        return f64::INFINITY;
    }
    let owner: Vec<usize> = mesh.positions.par_iter().map(|p| f.owner(p)).collect();
    let mut best = f64::INFINITY;
    for &(a, b) in overlaps {
        let pa: Vec<Point3<f64>> = (0..mesh.positions.len())
            .filter(|&v| owner[v] == a)
            .map(|v| mesh.positions[v])
            .collect();
        let pb: Vec<Point3<f64>> = (0..mesh.positions.len())
            .filter(|&v| owner[v] == b)
            .map(|v| mesh.positions[v])
            .collect();
        if pa.is_empty() || pb.is_empty() {
            continue;
        }
        let Ok(tree) = crate::spatial::KdTree::build(&pb) else {
            continue;
        };
        let d = pa
            .par_iter()
            .map(|p| tree.nearest(p).1)
            .reduce(|| f64::INFINITY, f64::min);
        best = best.min(d);
    }
    best
}

/// Rasterises the drawing's regions and the mesh projected on z = 0 on a 256^2 grid over the
/// drawing's box (normalised units); returns (mesh area / drawing area, intersection / union).
fn silhouette_match(parts: &[contour::Part], mesh: &Mesh) -> (f64, f64) {
    const N: usize = 256;
    let pts: Vec<Point2<f64>> = parts.iter().flat_map(|p| p.outer.iter().copied()).collect();
    let (lo, hi) = pts.iter().fold(
        (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        ),
        |(a, b), p| (a.inf(p), b.sup(p)),
    );
    let ext = (hi - lo) * 0.1;
    let (lo, hi) = (lo - ext, hi + ext);
    let h = (hi - lo) / N as f64;
    let mut drawn = vec![false; N * N];
    let mut shadow = vec![false; N * N];
    for j in 0..N {
        for i in 0..N {
            let p = Point2::new(lo.x + (i as f64 + 0.5) * h.x, lo.y + (j as f64 + 0.5) * h.y);
            drawn[j * N + i] = parts.iter().any(|q| q.contains(&p));
        }
    }
    for t in &mesh.faces {
        let v = t.map(|k| {
            let p = mesh.positions[k as usize];
            Point2::new(p.x, p.y)
        });
        let (a, b) = (v[0].inf(&v[1]).inf(&v[2]), v[0].sup(&v[1]).sup(&v[2]));
        let i0 = (((a.x - lo.x) / h.x - 0.5).ceil().max(0.0)) as usize;
        let j0 = (((a.y - lo.y) / h.y - 0.5).ceil().max(0.0)) as usize;
        let i1 = (((b.x - lo.x) / h.x - 0.5).floor().min(N as f64 - 1.0)).max(-1.0);
        let j1 = (((b.y - lo.y) / h.y - 0.5).floor().min(N as f64 - 1.0)).max(-1.0);
        if i1 < 0.0 || j1 < 0.0 {
            continue;
        }
        let cross = |o: Point2<f64>, p: Point2<f64>, q: Point2<f64>| {
            (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x)
        };
        let area = cross(v[0], v[1], v[2]);
        if area.abs() < 1e-300 {
            continue;
        }
        for j in j0..=(j1 as usize) {
            for i in i0..=(i1 as usize) {
                let p = Point2::new(lo.x + (i as f64 + 0.5) * h.x, lo.y + (j as f64 + 0.5) * h.y);
                let s = [
                    cross(v[0], v[1], p),
                    cross(v[1], v[2], p),
                    cross(v[2], v[0], p),
                ];
                if s.iter().all(|x| x * area >= 0.0) {
                    shadow[j * N + i] = true;
                }
            }
        }
    }
    let d = drawn.iter().filter(|x| **x).count() as f64;
    let s = shadow.iter().filter(|x| **x).count() as f64;
    let inter = drawn
        .iter()
        .zip(&shadow)
        .filter(|(a, b)| **a && **b)
        .count() as f64;
    let union = drawn
        .iter()
        .zip(&shadow)
        .filter(|(a, b)| **a || **b)
        .count() as f64;
    (s / d.max(1.0), inter / union.max(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ellipse(cx: f64, cy: f64, a: f64, b: f64) -> Vec<Point2<f64>> {
        (0..120)
            .map(|i| {
                let t = i as f64 / 120.0 * std::f64::consts::TAU;
                Point2::new(cx + a * t.cos(), cy + b * t.sin())
            })
            .collect()
    }

    #[test]
    fn blob_gives_one_closed_sphere_like_mesh() {
        let d = Drawing {
            contours: vec![ellipse(0.0, 0.0, 50.0, 30.0)],
            ..Default::default()
        };
        let (m, r) = sketch(&d, &SketchOptions::default()).unwrap();
        assert!(r.closed_manifold, "{r:?}");
        assert_eq!(r.components, 1);
        assert_eq!(r.genus, 0);
        assert!((r.silhouette_area_ratio - 1.0).abs() < 0.1, "{r:?}");
        assert!(m.signed_volume() > 0.0);
    }
}
