//! The data density that lets the bridge cells take over from the fitted ones away from the
//! points (see `PouImplicit::blend`): a C2 kernel density of the points within
//! `DENSITY_RADIUS` spacings, and a cheap test (`PouImplicit::dense`) that decides from a few
//! probe points per octree cell when it certainly reaches `DENSITY_FULL`.

use super::PouImplicit;
use crate::spatial::{Cube, KdTree, Octree};
use nalgebra::{Point3, Vector3};

/// Radius of the data density that lets bridges take over (`PouImplicit::density`), in point
/// spacings: beyond it from every point the bridges have full priority.
pub(super) const DENSITY_RADIUS: f64 = 3.0;

/// Data density (`PouImplicit::density`) above which only the fitted cells count: on an even
/// sampling about 1.5 spacings from the surface (7.07 (1 - d^2 / 9)^4 = 2 at d = 1.56).
pub(super) const DENSITY_FULL: f64 = 2.0;

/// Points summed by `PouImplicit::dense` before the full density: the nearest ones to x, or
/// to the centre of the octree cell holding x (near the surface three or four of them already
/// reach `DENSITY_FULL`).
const DENSE_PROBE: usize = 8;

/// `PouImplicit::dense` answers yes only when its partial sum beats `DENSITY_FULL` by this
/// relative margin, far above rounding, so the exact sum certainly reaches it too and `blend`
/// gives bit-identical results whichever way it was decided.
const DENSE_MARGIN: f64 = 1.0 + 1e-9;

/// Base u = max(0, 1 - d^2 / R^2) of one point's term u^3 in the data density (`d^2` its squared
/// distance, `r2` = R^2): one formula for `PouImplicit::density` and the partial sums of
/// `PouImplicit::dense`, which must bound the same sum from below.
#[inline]
fn density_base(d2: f64, r2: f64) -> f64 {
    (1.0 - d2 / r2).max(0.0)
}

/// The `DENSE_PROBE` points nearest to the centre of each terminal octree cell not much larger
/// than the density radius `r` (larger cells get none: from most of such a cell the points
/// nearest its centre are too far to count), for `PouImplicit::dense`.
pub(super) fn density_probes<T: Send>(tree: &Octree<T>, kd: &KdTree, r: f64) -> DensityProbes {
    use rayon::prelude::*;
    let cells: Vec<(usize, Cube)> = tree.terminal_nodes().collect();
    let found: Vec<(usize, [u32; DENSE_PROBE])> = cells
        .par_iter()
        .filter(|(_, cube)| cube.size <= r)
        .map(|(ni, cube)| {
            let mut probe = [u32::MAX; DENSE_PROBE];
            for (slot, (i, _)) in probe.iter_mut().zip(kd.knn(&cube.center(), DENSE_PROBE)) {
                *slot = i as u32;
            }
            (*ni, probe)
        })
        .collect();
    let mut slot = vec![u32::MAX; tree.node_count()];
    let mut probes = Vec::with_capacity(found.len());
    for (ni, probe) in found {
        slot[ni] = probes.len() as u32;
        probes.push(probe);
    }
    DensityProbes { slot, probes }
}

/// Per terminal octree cell, the `DENSE_PROBE` points nearest to its centre (`u32::MAX` where
/// fewer exist): a slot per octree node (inner nodes and cells without probes: `u32::MAX`)
/// into the probe sets of the cells that have them.
#[derive(Debug)]
pub(super) struct DensityProbes {
    slot: Vec<u32>,
    probes: Vec<[u32; DENSE_PROBE]>,
}

impl DensityProbes {
    /// The probe points of octree node `node`, if it has any.
    fn of(&self, node: usize) -> Option<&[u32; DENSE_PROBE]> {
        let k = *self.slot.get(node)?;
        self.probes.get(k as usize)
    }
}

impl PouImplicit {
    /// Smooth proximity of the data at `x`: a kernel density of the points within
    /// `DENSITY_RADIUS` spacings, `rho(x) = sum_j (1 - |x - p_j|^2 / R^2)^3` (C2, zero where no
    /// point is within R), and its gradient.
    pub(super) fn density(&self, x: &Point3<f64>, with_gradient: bool) -> (f64, Vector3<f64>) {
        let r = DENSITY_RADIUS * self.spacing;
        let r2 = r * r;
        let mut rho = 0.0;
        let mut g = Vector3::zeros();
        // The points in the cube around the ball (the same terms in the same ascending order
        // as a ball query: those beyond r have u <= 0; the Morton runs answer faster than
        // the k-d tree, which was 4 % of `fit`).
        for i in self.boxes.within_box(x, r) {
            let v = x - self.points[i];
            let u = density_base(v.norm_squared(), r2);
            if u > 0.0 {
                rho += u * u * u;
                if with_gradient {
                    g -= v * (6.0 * u * u / r2);
                }
            }
        }
        (rho, g)
    }

    /// True when the data density at `x` certainly reaches `DENSITY_FULL`: a partial sum of
    /// rho over a few points already does (every term is non-negative), with `DENSE_MARGIN`.
    /// Then the density ramp of `blend` is 0 with zero slope and the full sum, a radius query,
    /// is not needed. The points tried are the probes of the octree cell holding x (`node`;
    /// no query at all), the `DENSE_PROBE` points nearest to its centre; near the surface,
    /// where `fit` evaluates, they nearly always decide.
    pub(super) fn dense(&self, x: &Point3<f64>, node: Option<usize>) -> bool {
        let r = DENSITY_RADIUS * self.spacing;
        let r2 = r * r;
        let term = |i: usize| {
            let u = density_base((x - self.points[i]).norm_squared(), r2);
            u * u * u
        };
        let full = DENSITY_FULL * DENSE_MARGIN;
        if let Some(probe) = node.and_then(|n| self.probes.of(n)) {
            let rho: f64 = probe
                .iter()
                .filter(|&&i| i != u32::MAX)
                .map(|&i| term(i as usize))
                .sum();
            if rho >= full {
                return true;
            }
        }
        // Otherwise the caller's full sum decides (a box query is cheaper than the k-d
        // tree's nearest few, which cost 3.5 % of `fit` here).
        false
    }
}
