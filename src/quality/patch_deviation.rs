//! Distance of points from a patch network by point inversion on the exact surfaces.
//!
//! Each patch is sampled on a g x g grid; a k-d tree over the samples gives, for each point,
//! the nearest samples, whose patches are the candidates. On each candidate patch Newton's
//! point inversion (`BSplineSurface::closest_point`) starts from the nearest sample's (u, v);
//! the smallest distance wins. Candidates from the `k` nearest samples cover points near patch
//! edges and corners, where the true foot point can lie on any of up to (valence) patches.
//! A candidate whose control points' bounding box is no nearer than the best distance found
//! is skipped: a B-spline patch lies in the convex hull of its control points, so it cannot be
//! nearer either (the result is the same as trying it).

use crate::metrics::deviation::Deviation;
use crate::nurbs::PatchNetwork;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use serde::Serialize;
use std::num::NonZeroUsize;

/// Samples per patch and direction for the candidate search.
const GRID: usize = 6;
/// Nearest samples consulted per point.
const NEAREST: usize = 12;

/// Per-point distances and their statistics.
#[derive(Debug, Clone, Serialize)]
pub struct PatchDeviation {
    #[serde(flatten)]
    pub stats: Deviation,
    /// Distance of each input point, in input order.
    #[serde(skip)]
    pub distances: Vec<f64>,
}

/// Distances of `points` from the surfaces of `net`; relative figures against `reference`.
pub fn deviation_from_patches(
    net: &PatchNetwork,
    points: &[Point3<f64>],
    reference: f64,
) -> PatchDeviation {
    // Samples: (patch, u, v) with positions in a k-d tree.
    let mut samples: Vec<(u32, f64, f64)> = Vec::with_capacity(net.faces.len() * GRID * GRID);
    let mut positions: Vec<[f64; 3]> = Vec::with_capacity(net.faces.len() * GRID * GRID);
    for (fi, f) in net.faces.iter().enumerate() {
        let (u0, u1) = f.surface.domain_u();
        let (v0, v1) = f.surface.domain_v();
        for i in 0..GRID {
            for j in 0..GRID {
                let u = u0 + (u1 - u0) * (i as f64 + 0.5) / GRID as f64;
                let v = v0 + (v1 - v0) * (j as f64 + 0.5) / GRID as f64;
                let p = f.surface.evaluate(u, v);
                positions.push([p.x, p.y, p.z]);
                samples.push((fi as u32, u, v));
            }
        }
    }
    let boxes: Vec<(Vector3<f64>, Vector3<f64>)> =
        net.faces.iter().map(|f| f.surface.ctrl_bounds()).collect();
    let box_distance = |fi: usize, p: &Point3<f64>| {
        let (lo, hi) = &boxes[fi];
        (lo - p.coords)
            .sup(&(p.coords - hi))
            .sup(&Vector3::zeros())
            .norm()
    };
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&positions).ok();
    let distances: Vec<f64> = match (tree, NonZeroUsize::new(NEAREST.min(samples.len()))) {
        (Some(tree), Some(k)) => points
            .par_iter()
            .map(|p| {
                let near = tree
                    .query(&[p.x, p.y, p.z])
                    .nearest_n::<SquaredEuclidean<f64>>(k)
                    .execute();
                let mut tried: Vec<u32> = Vec::with_capacity(NEAREST);
                let mut best = f64::INFINITY;
                for n in near {
                    let (fi, u, v) = samples[n.item as usize];
                    if tried.contains(&fi) {
                        continue;
                    }
                    tried.push(fi);
                    if box_distance(fi as usize, p) >= best {
                        continue;
                    }
                    let c = net.faces[fi as usize].surface.closest_point(p, (u, v));
                    best = best.min(c.distance);
                }
                best
            })
            .collect(),
        _ => vec![f64::INFINITY; points.len()],
    };
    PatchDeviation {
        stats: Deviation::from_distances(&distances, reference),
        distances,
    }
}
