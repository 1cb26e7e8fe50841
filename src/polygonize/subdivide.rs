//! Refinement of a polygonized implicit: 1-to-4 subdivision with projection of the new vertices
//! onto the zero set, repeated until the mesh is within a tolerance of the implicit (seed 003
//! section 3.3: "subdivide, project onto the implicit, relax, until the required accuracy").
//!
//! The distance of the mesh from the surface is measured where it is about largest for a chord
//! mesh: at the triangles' centroids, as |f| there (f is about a distance).
//! The test uses a quantile of these gaps (default the 99th percentile), so that a few spots
//! where the implicit itself is rough (bridged holes) do not force the whole mesh finer.

use super::relax::relax;
use crate::implicit::project::{project, ProjectOptions};
use crate::implicit::Implicit;
use crate::mesh::subdivide::subdivide;
use crate::mesh::Mesh;
use nalgebra::Point3;
use rayon::prelude::*;

/// Options of [`refine`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RefineOptions {
    /// Largest accepted quantile of |f| at the triangle centroids (absolute).
    pub tolerance: f64,
    /// The quantile of the per-triangle gaps compared with the tolerance (0.99; 1 = all).
    pub quantile: f64,
    /// At most this many subdivisions.
    pub max_levels: usize,
    /// Relaxation rounds after each subdivision.
    pub relax_iterations: usize,
    /// No subdivision that would make more triangles than this.
    pub max_faces: usize,
}

/// What [`refine`] did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RefineReport {
    pub levels: usize,
    /// The tested quantile of the gaps before each subdivision and at the end.
    pub gaps: Vec<f64>,
    /// The largest gap before each subdivision and at the end.
    pub max_gaps: Vec<f64>,
    pub failed_projections: usize,
}

/// Per triangle, |f| at its centroid (infinite where f is NaN): for a mesh with its vertices on
/// the surface, about the chord's distance from the surface there.
pub fn surface_gaps<F: Implicit + ?Sized>(mesh: &Mesh, f: &F) -> Vec<f64> {
    mesh.faces
        .par_iter()
        .map(|t| {
            let c = Point3::from(
                (mesh.positions[t[0] as usize].coords
                    + mesh.positions[t[1] as usize].coords
                    + mesh.positions[t[2] as usize].coords)
                    / 3.0,
            );
            let g = f.value(&c).abs();
            if g.is_nan() {
                f64::INFINITY
            } else {
                g
            }
        })
        .collect()
}

/// The `q` quantile (nearest rank) and the maximum of `gaps` (0 for none).
pub fn gap_quantile(gaps: &[f64], q: f64) -> (f64, f64) {
    if gaps.is_empty() {
        return (0.0, 0.0);
    }
    let mut s = gaps.to_vec();
    let k = ((q.clamp(0.0, 1.0) * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    let (_, v, _) = s.select_nth_unstable_by(k, f64::total_cmp);
    let v = *v;
    (v, gaps.iter().copied().fold(0.0, f64::max))
}

/// Subdivides and projects until the gap quantile ([`surface_gaps`]) is within the tolerance or `max_levels` is
/// reached.
pub fn refine<F: Implicit + ?Sized>(
    mut mesh: Mesh,
    f: &F,
    opts: &RefineOptions,
    proj: &ProjectOptions,
) -> (Mesh, RefineReport) {
    let mut report = RefineReport::default();
    loop {
        let (gap, max) = gap_quantile(&surface_gaps(&mesh, f), opts.quantile);
        report.gaps.push(gap);
        report.max_gaps.push(max);
        if gap <= opts.tolerance
            || report.levels >= opts.max_levels
            || mesh.faces.is_empty()
            || mesh.faces.len().saturating_mul(4) > opts.max_faces
        {
            break;
        }
        let n_old = mesh.positions.len();
        let (mut m, _) = subdivide(&mesh);
        let projected: Vec<(Point3<f64>, bool)> = m.positions[n_old..]
            .par_iter()
            .map(|p| match project(f, p, proj) {
                Ok((q, _)) => (q, false),
                Err(_) => (*p, true),
            })
            .collect();
        for (k, (q, failed)) in projected.into_iter().enumerate() {
            m.positions[n_old + k] = q;
            report.failed_projections += failed as usize;
        }
        report.failed_projections += relax(&mut m, f, opts.relax_iterations, proj);
        mesh = m;
        report.levels += 1;
    }
    (mesh, report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Aabb, Topology};
    use crate::polygonize::marching_cubes;
    use nalgebra::Vector3;

    struct Sphere;
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - 0.8
        }
        fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
            x.coords.normalize()
        }
    }

    #[test]
    fn refinement_reaches_tolerance() {
        let dom = Aabb {
            min: Point3::new(-1.0, -1.0, -1.0),
            max: Point3::new(1.0, 1.0, 1.0),
        };
        let m = marching_cubes(&Sphere, &[Point3::new(0.8, 0.01, 0.02)], &dom, 0.2).unwrap();
        let opts = RefineOptions {
            tolerance: 1e-3,
            quantile: 1.0,
            max_levels: 4,
            relax_iterations: 1,
            max_faces: usize::MAX,
        };
        let (r, rep) = refine(
            m.clone(),
            &Sphere,
            &opts,
            &ProjectOptions::for_diagonal(2.0),
        );
        assert!(rep.levels >= 1 && rep.levels <= 4, "{rep:?}");
        assert!(*rep.gaps.last().unwrap() <= 1e-3, "{rep:?}");
        assert!(rep.gaps.windows(2).all(|w| w[1] < w[0]));
        assert!(Topology::build(&r).is_closed_manifold());
        assert_eq!(r.faces.len(), m.faces.len() * 4usize.pow(rep.levels as u32));
        for p in &r.positions {
            assert!((p.coords.norm() - 0.8).abs() < 1e-6);
        }
    }
}
