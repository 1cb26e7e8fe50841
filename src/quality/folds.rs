//! Folds: where a patch's normal turns away from the implicit surface it interpolates.
//!
//! Each patch interpolates a grid of points on f = 0 (seed 004 eq. 9-14) and, at the grid
//! points, its normal S_u x S_v is close to the implicit's unit gradient n. Between them the
//! bicubic can turn over: where two boundary curves leave a corner almost in one direction
//! (a sliver corner), or where the implicit has a feature narrower than a grid cell. A CAD
//! system sees such a spot as a crease or a small pocket, and OpenCASCADE's point projection
//! can fall into it (a local minimum of the distance).
//!
//! **Measure.** For every grid cell of every patch, the normal of the patch at the cell's
//! centre is compared with the unit gradients of f at the cell's four grid points (kept by the
//! sampler, which computed them when it put the points on f = 0); the cell's
//! fold angle is the smallest of the four angles (a surface that merely turns across the cell,
//! over a rounded crease, stays close to one of its corners' normals; a fold faces away from
//! all of them), and a patch's fold angle is the largest over its cells. A patch is folded
//! when that angle exceeds [`FOLD_DEG`]. Nothing here changes the patches: it is the figure
//! the `fit` report gives so that a user sees how many patches to inspect (`worst` lists
//! where).

use crate::nurbs::PatchNetwork;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use serde::Serialize;

/// Fold angle over which a patch counts as folded, degrees.
pub const FOLD_DEG: f64 = 45.0;

/// How many folded patches [`FoldReport::worst`] lists.
pub const WORST_LISTED: usize = 10;

/// One patch's largest fold angle and where it is.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct FoldSample {
    pub patch: usize,
    pub angle_deg: f64,
    pub point: [f64; 3],
}

/// Folds of a patch network (module doc).
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct FoldReport {
    /// Patches whose normal leaves the implicit's by more than 45 and 90 degrees somewhere.
    pub patches_over_45_deg: usize,
    pub patches_over_90_deg: usize,
    /// Largest fold angle over all patches.
    pub max_deg: f64,
    /// The patches with the largest fold angles over 45 degrees, largest first.
    pub worst: Vec<FoldSample>,
}

/// The sample grid of one patch: points on f = 0 at the parameters `params_u` x `params_v`,
/// and the implicit's normals there (any length; only directions are compared).
pub struct SampleGrid<'a> {
    pub points: &'a [Vec<Point3<f64>>],
    pub normals: &'a [Vec<Vector3<f64>>],
    pub params_u: &'a [f64],
    pub params_v: &'a [f64],
}

/// Largest fold angle over the patch's cells (module doc), with the surface point where it
/// occurs.
fn patch_fold(surface: &crate::nurbs::BSplineSurface, grid: &SampleGrid<'_>) -> (f64, Point3<f64>) {
    let normals = grid.normals;
    let (pu, pv) = (grid.params_u, grid.params_v);
    let mut worst = (0.0, grid.points[0][0]);
    for i in 0..pu.len().saturating_sub(1) {
        for j in 0..pv.len().saturating_sub(1) {
            let d = surface.derivatives(0.5 * (pu[i] + pu[i + 1]), 0.5 * (pv[j] + pv[j + 1]));
            let n = d.du.cross(&d.dv);
            let angle = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                .iter()
                .map(|&(a, b)| n.angle(&normals[a][b]).to_degrees())
                .fold(f64::INFINITY, f64::min);
            if angle > worst.0 {
                worst = (angle, d.point);
            }
        }
    }
    worst
}

/// Folds of `network`, whose face k interpolates `grids[k]`.
pub fn folds(network: &PatchNetwork, grids: &[SampleGrid<'_>]) -> FoldReport {
    let per: Vec<(f64, Point3<f64>)> = network
        .faces
        .par_iter()
        .zip(grids.par_iter())
        .map(|(face, g)| patch_fold(&face.surface, g))
        .collect();
    let mut folded: Vec<FoldSample> = per
        .iter()
        .enumerate()
        .filter(|(_, w)| w.0 > FOLD_DEG)
        .map(|(patch, w)| FoldSample {
            patch,
            angle_deg: w.0,
            point: [w.1.x, w.1.y, w.1.z],
        })
        .collect();
    folded.sort_by(|a, b| b.angle_deg.total_cmp(&a.angle_deg));
    FoldReport {
        patches_over_45_deg: folded.len(),
        patches_over_90_deg: folded.iter().filter(|s| s.angle_deg > 90.0).count(),
        max_deg: per.iter().map(|w| w.0).fold(0.0, f64::max),
        worst: folded.into_iter().take(WORST_LISTED).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::Implicit;
    use crate::nurbs::{BSplineSurface, Params, PatchGrid, PatchInput, Twist};
    use crate::polygonize::test_shapes::Sphere;

    /// One patch on a sphere cap from its exact grid, and the same grid with one interior
    /// point pushed through the surface: the first has no fold, the second a fold the
    /// report finds where the point was moved.
    #[test]
    fn a_dent_through_the_surface_is_a_fold() {
        let s = Sphere {
            c: Point3::origin(),
            r: 1.0,
        };
        let n = 6;
        let params: Vec<f64> = (0..=n).map(|k| k as f64 / n as f64).collect();
        let at = |i: usize, j: usize| {
            let (x, y) = (params[i] - 0.5, params[j] - 0.5);
            Point3::from(Vector3::new(x, y, 1.0).normalize())
        };
        let exact: Vec<Vec<Point3<f64>>> = (0..=n)
            .map(|i| (0..=n).map(|j| at(i, j)).collect())
            .collect();
        let build = |points: Vec<Vec<Point3<f64>>>| {
            let h = 1e-6;
            let d = |i: usize, j: usize, du: bool| {
                let (x, y) = (params[i] - 0.5, params[j] - 0.5);
                let p = |x: f64, y: f64| Vector3::new(x, y, 1.0).normalize();
                if du {
                    (p(x + h, y) - p(x - h, y)) / (2.0 * h)
                } else {
                    (p(x, y + h) - p(x, y - h)) / (2.0 * h)
                }
            };
            let grid = PatchGrid {
                du_u0: (0..=n).map(|j| d(0, j, true)).collect(),
                du_u1: (0..=n).map(|j| d(n, j, true)).collect(),
                dv_v0: (0..=n).map(|i| d(i, 0, false)).collect(),
                dv_v1: (0..=n).map(|i| d(i, n, false)).collect(),
                points,
                twist: Twist::Estimate,
            };
            let p = Params::new(&params).unwrap();
            let surface = BSplineSurface::interpolate_grid(&grid, &p, &p).unwrap();
            let net = PatchNetwork::from_patches(
                vec![at(0, 0), at(n, 0), at(n, n), at(0, n)],
                vec![PatchInput {
                    surface,
                    corners: [0, 1, 2, 3],
                    same_sense: true,
                }],
            )
            .unwrap();
            let normals: Vec<Vec<Vector3<f64>>> = grid
                .points
                .iter()
                .map(|col| col.iter().map(|p| s.gradient(p)).collect())
                .collect();
            let g = [SampleGrid {
                points: &grid.points,
                normals: &normals,
                params_u: &params,
                params_v: &params,
            }];
            folds(&net, &g)
        };
        let r = build(exact.clone());
        assert_eq!(r.patches_over_45_deg, 0, "{r:?}");
        // The reference normals are the cell's corners', up to half a cell away: on this cap
        // (cells 1/6 of the radius) that alone differs by up to 5 degrees.
        assert!(r.max_deg < 10.0, "{r:?}");
        let mut dented = exact;
        dented[3][3] = Point3::from(dented[3][3].coords * 0.8);
        let r = build(dented);
        assert_eq!(r.patches_over_45_deg, 1, "{r:?}");
        let p = Vector3::from(r.worst[0].point);
        assert!((p - at(3, 3).coords).norm() < 0.25, "{r:?}");
    }
}
