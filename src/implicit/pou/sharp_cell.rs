//! Crease cells of the partition-of-unity implicit (issue 35): a cell whose support holds points
//! of two or three smooth regions ([`crate::features`]) gets a sharp function
//! ([`crate::implicit::sharp`]: one height polynomial per region, combined by max and min) when
//! it fits the support within [`SHARP_FACTOR`] times the tolerance, and is split when more than
//! three regions meet in it.
//!
//! **Supports grown at corners.** A region is a side only with [`sharp::MIN_SIDE`] points in the
//! support. Beside a corner the third face often crosses the support in a sliver holding a point
//! or two (or none, between the samples), so the cell is fitted with two sides, and its function
//! continues those two faces straight through the third one. Either the fit then misses the few
//! points of the third face, or it passes, and the function is wrong where the third face is
//! but has no points. Both are found on a support [`SHARP_GROWTH`] times wider: a region that
//! reaches `MIN_SIDE` points there and (for a fit that passed) whose points the function misses
//! by more than `SHARP_FACTOR` tolerances. The cell is fitted again on the wider support with
//! the third side, and that fit is kept when it passes; the weight keeps the cell's own support.
//!
//! The same holds for an edge: a cell with one side and a few points of another region (a
//! face sampled more coarsely than its neighbour, as a mesh's large flat triangles are, or a
//! narrow face) is fitted on the grown supports too, instead of by a smooth fit that rounds
//! the edge (the stepped shaft of `scripts/extra_parts.py` from its mesh: the corner of its
//! milled flat was cut 0.22 mm, crease distance 2.3e-3 of the diagonal, 9.5e-4 with this).

use super::build::Builder;
use super::Cell;
use crate::implicit::local::{self, LocalFit, LocalFunction};
use crate::implicit::sharp::{self, SharpFunction};
use crate::spatial::{CellContext, Decision};
use nalgebra::{Point3, Vector3};

/// A sharp function within this many times the tolerance is kept (module doc of
/// [`crate::implicit::sharp`]): split further, a crease cell soon holds too few points of one
/// side for a side of its own, and the smooth fits that take over round the crease off
/// (make_parts' block from its mesh, `reconstruct --sharp`: 1 -> 2 takes the band normal error
/// beside the creases from 4.1 to 1.3 degrees, p95).
pub(super) const SHARP_FACTOR: f64 = 2.0;

/// The share of a crease cell's points whose normals must agree with its sharp function for it
/// to be kept (with [`SHARP_FACTOR`]). On a noisy cloud a point beside an edge can carry one
/// face's label and the normal of the other face, estimated across the edge, a few tolerances
/// from where the two faces tie: one such point in 44 split make_parts' cornerblock's corner
/// cell until its children fell to smooth fits, which cut the corner 0.1 mm.
const SHARP_AGREEMENT: f64 = 0.95;

/// Widths of the grown supports tried at a corner, relative to the cell's fit support (module
/// doc). Measured from the mesh of a wedge with a slot across its top: the corner of the slot's
/// floor, the slot's wall and the back face was rounded 0.25 mm (crease distance 2.6e-3 of the
/// diagonal, 7.3e-4 with growth); an L-plate's box corner 0.22 mm.
const SHARP_GROWTH: [f64; 2] = [1.5, 2.0];

/// What one sharp fit on one support gives.
enum Attempt {
    /// More than [`sharp::MAX_SIDES`] regions: split the cell.
    Split,
    /// A function within the tolerance.
    Kept(Box<LocalFit>),
    /// A function that misses (kept for [`super::build`]'s too-small cells).
    Loose(Box<LocalFit>),
    /// Under two sides, or no function could be fitted.
    Nothing,
}

impl Builder<'_> {
    /// The sharp function of the cell centred at `c` (weight support `h0`) fitted to `idx`
    /// (points `p`, normals `n`, within `h` of `c`), or a split (module doc). `Err` leaves the
    /// cell to the smooth fits, with the sharp function that was fitted but missed the
    /// tolerance, if any.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sharp_cell(
        &self,
        ctx: &CellContext,
        c: &Point3<f64>,
        h0: f64,
        idx: &[usize],
        p: &[Point3<f64>],
        n: &[Vector3<f64>],
        h: f64,
    ) -> Result<Decision<Cell>, Option<Box<LocalFit>>> {
        let Some(labels) = self.labels else {
            return Err(None);
        };
        match self.sharp_attempt(ctx, labels, idx, p, n, h) {
            Attempt::Split => Ok(Decision::Split),
            Attempt::Kept(fit) => Ok(match self.grown(ctx, labels, c, idx, h, Some(&fit)) {
                Some((g, count)) => self.leaf(*c, h0, count, g),
                None => self.leaf(*c, h0, p.len(), *fit),
            }),
            Attempt::Loose(fit) => match self.grown(ctx, labels, c, idx, h, None) {
                Some((g, count)) => Ok(self.leaf(*c, h0, count, g)),
                None => Err(Some(fit)),
            },
            // One side and a few points of another region: the second face of an edge, or
            // the third of a corner, crosses the support in a sliver (module doc).
            Attempt::Nothing if Self::several_regions(labels, idx) => {
                match self.grown(ctx, labels, c, idx, h, None) {
                    Some((g, count)) => Ok(self.leaf(*c, h0, count, g)),
                    None => Err(None),
                }
            }
            Attempt::Nothing => Err(None),
        }
    }

    /// True when the points `idx` belong to more than one region (of any size).
    fn several_regions(labels: &[u32], idx: &[usize]) -> bool {
        let mut l = idx
            .iter()
            .map(|&i| labels[i])
            .filter(|&r| r != sharp::NO_REGION);
        match l.next() {
            Some(first) => l.any(|r| r != first),
            None => false,
        }
    }

    /// The regions with at least [`sharp::MIN_SIDE`] of the points `idx`, sorted.
    fn sides_of(labels: &[u32], idx: &[usize]) -> Vec<u32> {
        let l: Vec<u32> = idx.iter().map(|&i| labels[i]).collect();
        let mut r: Vec<u32> = sharp::region_groups(&l, sharp::MIN_SIDE)
            .into_iter()
            .map(|g| g.0)
            .collect();
        r.sort_unstable();
        r
    }

    /// The fit on a grown support (module doc), with its point count: `None` when no wider
    /// support adds a side, when `kept` (the fit that passed on the cell's own support) already
    /// follows the added side's points, or when no fit on a wider support passes.
    fn grown(
        &self,
        ctx: &CellContext,
        labels: &[u32],
        c: &Point3<f64>,
        idx: &[usize],
        h: f64,
        kept: Option<&LocalFit>,
    ) -> Option<(LocalFit, usize)> {
        let before = Self::sides_of(labels, idx);
        for g in SHARP_GROWTH {
            let hg = g * h;
            let ig = self.in_box(c, hg);
            let now = Self::sides_of(labels, &ig);
            if now.len() <= before.len() || !before.iter().all(|r| now.contains(r)) {
                continue;
            }
            if let Some(fit) = kept {
                let LocalFunction::Sharp(f) = &fit.function else {
                    return None;
                };
                let misses = ig.iter().any(|&i| {
                    !before.contains(&labels[i])
                        && now.contains(&labels[i])
                        && f.value(&self.pts[i]).abs() > SHARP_FACTOR * self.tol
                });
                if !misses {
                    return None;
                }
            }
            let pg: Vec<Point3<f64>> = ig.iter().map(|&i| self.pts[i]).collect();
            let ng: Vec<Vector3<f64>> = ig.iter().map(|&i| self.nrm[i]).collect();
            if let Attempt::Kept(fit) = self.sharp_attempt(ctx, labels, &ig, &pg, &ng, hg) {
                return Some((*fit, ig.len()));
            }
        }
        None
    }

    /// One sharp fit to `idx` (points `p`, normals `n`, within `h` of the cell's centre).
    fn sharp_attempt(
        &self,
        ctx: &CellContext,
        labels: &[u32],
        idx: &[usize],
        p: &[Point3<f64>],
        n: &[Vector3<f64>],
        h: f64,
    ) -> Attempt {
        let l: Vec<u32> = idx.iter().map(|&i| labels[i]).collect();
        let sides = sharp::region_groups(&l, sharp::MIN_SIDE).len();
        if sides < 2 {
            return Attempt::Nothing;
        }
        if sides > sharp::MAX_SIDES {
            return if ctx.can_split {
                Attempt::Split
            } else {
                Attempt::Nothing
            };
        }
        // Fitted with the points' own normals or, where those give some side no height frame
        // (estimates scattered beside an acute crease: the V block's cloud where a hole meets
        // a flank, 2.4e-3 -> 2.0e-3 of the diagonal), their one-sided ones (`side_nrm`), and
        // judged by both: either may agree (`SharpFunction::evaluate`).
        // (A mesh has no one-sided normals: no second try.)
        let ns: Option<Vec<Vector3<f64>>> = self
            .side_nrm
            .map(|side| idx.iter().map(|&i| side[i]).collect());
        let fit = |normals: &[Vector3<f64>]| {
            SharpFunction::fit(p, normals, &l, h, self.opts.min_normal_cos, 0.5 * self.tol)
        };
        let Some(f) = fit(n).or_else(|| ns.as_deref().and_then(fit)) else {
            return Attempt::Nothing;
        };
        let (values, agreement) = f.evaluate(p, n, ns.as_deref().unwrap_or(n), self.tol);
        let fit = LocalFit {
            normal_agreement: agreement,
            ..local::assess_values(LocalFunction::Sharp(f), &values, n)
        };
        if fit.max_residual <= SHARP_FACTOR * self.tol && fit.normal_agreement >= SHARP_AGREEMENT {
            Attempt::Kept(Box::new(fit))
        } else {
            Attempt::Loose(Box::new(fit))
        }
    }
}
