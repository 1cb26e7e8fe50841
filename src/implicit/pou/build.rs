//! The split rule of the partition-of-unity implicit ([`super::PouImplicit`]): how a cell of
//! the octree is fitted (seed 003 section 3.1, seed 004 section 2.1) and whether it is a leaf.

use super::{Cell, CellRole, FitOptions};
use crate::implicit::local::{self, LocalFit, LocalFunction, LocalParams};
use crate::implicit::poly::Degree;
use crate::mesh::Aabb;
use crate::spatial::{BoxIndex, CellContext, Cube, Decision, KdTree};
use nalgebra::{Point3, Vector3};

/// Largest overlap the blending band ([`FitOptions::min_band`]) may give a cell, relative to
/// its half-width.
const MAX_OVERLAP: f64 = 0.5;

/// Largest edge of a bridge cell, in point spacings.
const MAX_BRIDGE_CELL: f64 = 8.0;

/// Support of an extrapolating cell relative to a fitted cell's.
const EXTRAPOLATION_SPREAD: f64 = 1.5;

/// A hole cell fits its bridge to this many times `min_points` rim points nearest to it (many,
/// so that neighbouring hole cells share most of them and agree).
const BRIDGE_POINTS: usize = 8;

/// A domain too small to split keeps a polynomial whose residual is within this many times the
/// tolerance (the misfit is noise there).
const LEAF_FACTOR: f64 = 1.5;

/// A crease cell too small to split keeps its sharp function within this many times the
/// tolerance, rather than a smooth fit or an RBF through its points, which rounds the crease or
/// overshoots it between the points: where a face's side is itself not one quadratic (a fillet
/// running into a plane beside the crease) the sharp function misses by a few tolerances at
/// every size, and the RBF that took such cells bulged 0.1 mm past make_parts' block's bottom
/// edge at the end of a vertical fillet (crease distance 1.8e-3 of the diagonal).
const SHARP_LEAF_FACTOR: f64 = 4.0;

/// The share of a too-small crease cell's support points whose normals must agree with its
/// sharp function for it to be kept ([`SHARP_LEAF_FACTOR`]). On a noisy cloud one point in
/// twenty beside the crease carries the other face's label or a normal estimated across the
/// edge; the RBF that took such cells rounded make_parts' block's bottom edges by 0.15 mm.
const SHARP_LEAF_AGREEMENT: f64 = 0.9;

/// The split rule of the octree: fits a cell and decides whether it is a leaf.
pub(super) struct Builder<'a> {
    pub(super) pts: &'a [Point3<f64>],
    pub(super) nrm: &'a [Vector3<f64>],
    /// Each point's normal of its own region alone, by which (as by `nrm`) a crease cell's
    /// sharp function is judged ([`super::PouImplicit::fit_with_sides`]; `None`: by `nrm`).
    pub(super) side_nrm: Option<&'a [Vector3<f64>]>,
    pub(super) kd: &'a KdTree,
    /// The same points for the cells' box queries.
    pub(super) boxes: &'a BoxIndex,
    pub(super) opts: &'a FitOptions,
    pub(super) tol: f64,
    /// Typical point spacing.
    pub(super) spacing: f64,
    pub(super) root_half: f64,
    /// Smooth region of every point, when the fit is feature-aware
    /// ([`super::PouImplicit::fit_with_regions`]).
    pub(super) labels: Option<&'a [u32]>,
}

impl Builder<'_> {
    /// Width of the blending band beyond a cell of half-width `half` (module doc, "Blending
    /// band"): `min_band` tolerances, but at least `overlap` and at most [`MAX_OVERLAP`] times
    /// the half-width.
    fn band_of_half(&self, half: f64) -> f64 {
        let lo = self.opts.overlap * half;
        (self.opts.min_band * self.tol).clamp(lo, lo.max(MAX_OVERLAP * half))
    }

    /// Half-width of the weight support of a cell of half-width `half`.
    fn support_half(&self, half: f64) -> f64 {
        half + self.band_of_half(half)
    }

    /// The band of the cell whose support half-width is `h0` (the inverse of
    /// [`Self::support_half`]).
    fn band(&self, h0: f64) -> f64 {
        let ov = self.opts.overlap;
        let lo = h0 * ov / (1.0 + ov);
        let hi = lo.max(h0 * MAX_OVERLAP / (1.0 + MAX_OVERLAP));
        (self.opts.min_band * self.tol).clamp(lo, hi)
    }

    /// Indices of the points inside the box of half-width `h` around `c`.
    pub(super) fn in_box(&self, c: &Point3<f64>, h: f64) -> Vec<usize> {
        self.boxes.within_box(c, h)
    }

    pub(super) fn leaf(&self, c: Point3<f64>, h: f64, n: usize, fit: LocalFit) -> Decision<Cell> {
        self.leaf_with(c, h, n, fit, CellRole::Fitted)
    }

    fn leaf_with(
        &self,
        c: Point3<f64>,
        h: f64,
        n: usize,
        fit: LocalFit,
        role: CellRole,
    ) -> Decision<Cell> {
        let meets = fit.meets(self.tol);
        let core = 1.0 - self.band(h) / h;
        // Extrapolating cells overlap their neighbours more, so that bridges of a hole made by
        // different cells blend smoothly.
        let h = if role == CellRole::Bridge {
            h * EXTRAPOLATION_SPREAD
        } else {
            h
        };
        Decision::Leaf {
            payload: Cell {
                center: c,
                half: Vector3::repeat(h),
                inv_half: Vector3::repeat(1.0 / h),
                core,
                inv_band: 1.0 / (1.0 - core),
                function: fit.function,
                role,
                support_points: n as u32,
                max_residual: fit.max_residual,
                meets_tolerance: meets,
            },
            support: Aabb {
                min: c - Vector3::repeat(h),
                max: c + Vector3::repeat(h),
            },
        }
    }

    /// True when the fitted height surface crosses the cell somewhere farther than a quarter of
    /// the cell's edge from every point (the cell's points cover only part of it).
    fn has_gap(&self, cube: &Cube, f: &LocalFunction) -> bool {
        let LocalFunction::Poly(hp) = f else {
            return false;
        };
        let fr = &hp.frame;
        // Natural gaps between samples are below a few point spacings (the nearest-neighbour
        // distance, which stays small along the rim of a hole).
        let (i, _) = self.kd.nearest(&cube.center());
        let spacing = self.kd.knn(&self.pts[i], 2).get(1).map_or(0.0, |x| x.1);
        let gap = (0.25 * cube.size).max(2.5 * spacing);
        let half = 0.5 * cube.size * 3f64.sqrt() / fr.scale;
        let c = fr.local(&cube.center());
        const N: usize = 6;
        for i in 0..N {
            for j in 0..N {
                let u = c.x + half * (2.0 * (i as f64 + 0.5) / N as f64 - 1.0);
                let v = c.y + half * (2.0 * (j as f64 + 0.5) / N as f64 - 1.0);
                let x = hp.surface_point(u, v);
                if cube.contains(&x) && self.kd.nearest(&x).1 > gap {
                    return true;
                }
            }
        }
        false
    }

    /// True when `c` lies on the same side (outside both, or inside both) of two of the points
    /// `near` whose normals face opposite ways: the gap between two sheets (a tail beside a
    /// body, the inside of a thin part), where no hole needs bridging. A hole's rim has its
    /// points on one sheet, or on both sides of a thin wall with `c` between them.
    fn between_sheets(&self, near: &[(usize, f64)], c: &Point3<f64>) -> bool {
        let side = |i: usize| (c - self.pts[i]).dot(&self.nrm[i]);
        near.iter().any(|&(i, _)| {
            near.iter()
                .any(|&(j, _)| self.nrm[i].dot(&self.nrm[j]) < -0.5 && side(i) * side(j) > 0.0)
        })
    }

    /// An empty cell that the surface passes by rather than through (no tangent plane of the
    /// nearest points cuts its box, or it lies between two sheets) only needs a rough signed
    /// distance: a quadratic fitted to the nearest points, or the tangent plane of the nearest
    /// one. `None` for a possible hole.
    fn side_cell(&self, c: &Point3<f64>, h0: f64) -> Option<Decision<Cell>> {
        let o = self.opts;
        let near = self.kd.knn(c, o.min_points);
        let reach = h0 * 3f64.sqrt();
        if near
            .iter()
            .any(|&(i, _)| (c - self.pts[i]).dot(&self.nrm[i]).abs() <= reach)
            && !self.between_sheets(&near, c)
        {
            return None;
        }
        let p: Vec<Point3<f64>> = near.iter().map(|&(i, _)| self.pts[i]).collect();
        let n: Vec<Vector3<f64>> = near.iter().map(|&(i, _)| self.nrm[i]).collect();
        let scale = near.last().map_or(h0, |x| x.1).max(1e-300);
        let quad = crate::implicit::poly::Frame::from_normals(&p, &n, scale, o.min_normal_cos)
            .and_then(|fr| local::fit_poly(&p, &n, fr, Degree::Quadratic))
            .filter(|f| f.normal_agreement >= 0.9);
        let fit = match quad {
            Some(f) => f,
            None => {
                let (i, _) = near[0];
                let frame = crate::implicit::poly::Frame::new(self.pts[i], self.nrm[i], scale)?;
                local::assess(
                    LocalFunction::Poly(crate::implicit::poly::HeightPoly {
                        frame,
                        degree: Degree::Linear,
                        coef: [0.0; 10],
                    }),
                    &p,
                    &n,
                )
            }
        };
        Some(self.leaf_with(*c, h0, p.len(), fit, CellRole::Fallback))
    }

    /// A thin-plate RBF through the points (an evenly strided subset of at most
    /// `rbf_max_points` of them), assessed at all of them.
    fn rbf(&self, p: &[Point3<f64>], n: &[Vector3<f64>], params: &LocalParams) -> Option<LocalFit> {
        let m = self.opts.rbf_max_points;
        let fit = if p.len() > m {
            let step = p.len() as f64 / m as f64;
            let sel: Vec<usize> = (0..m).map(|k| (k as f64 * step) as usize).collect();
            let sp: Vec<Point3<f64>> = sel.iter().map(|&i| p[i]).collect();
            let sn: Vec<Vector3<f64>> = sel.iter().map(|&i| n[i]).collect();
            local::fit_rbf(&sp, &sn, params)?
        } else {
            return local::fit_rbf_assessed(p, n, params);
        };
        Some(local::assess(fit, p, n))
    }

    /// True when the points `idx`, seen in the plane across their mean normal, lie all around
    /// `c` (no empty angular sector wider than 120 degrees).
    fn surrounds(&self, idx: &[usize], c: &Point3<f64>) -> bool {
        let mean: Vector3<f64> = idx.iter().map(|&i| self.nrm[i]).sum();
        let Some(frame) = crate::implicit::poly::Frame::new(*c, mean, 1.0) else {
            return false;
        };
        let mut ang: Vec<f64> = idx
            .iter()
            .map(|&i| {
                let l = frame.local(&self.pts[i]);
                l.y.atan2(l.x)
            })
            .collect();
        if ang.len() < 3 {
            return false;
        }
        ang.sort_by(f64::total_cmp);
        let mut gap = ang[0] + std::f64::consts::TAU - ang[ang.len() - 1];
        for w in ang.windows(2) {
            gap = gap.max(w[1] - w[0]);
        }
        gap < 2.0 * std::f64::consts::FRAC_PI_3
    }

    /// Radius around the point nearest to `c` holding `min_points` points: the smallest useful
    /// support there.
    fn sampling_radius(&self, c: &Point3<f64>) -> f64 {
        let (i, _) = self.kd.nearest(c);
        self.kd
            .knn(&self.pts[i], self.opts.min_points)
            .last()
            .map_or(0.0, |x| x.1)
    }

    fn constant(&self, c: Point3<f64>, h: f64, n: usize) -> Decision<Cell> {
        let (i, d) = self.kd.nearest(&c);
        let s = if (c - self.pts[i]).dot(&self.nrm[i]) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        self.leaf_with(
            c,
            h,
            n,
            LocalFit {
                function: LocalFunction::Constant(s * d),
                max_residual: 0.0,
                rms_residual: 0.0,
                normal_agreement: 1.0,
            },
            CellRole::Fallback,
        )
    }

    pub(super) fn decide(&self, ctx: &CellContext) -> Decision<Cell> {
        let o = self.opts;
        let c = ctx.cube.center();
        // Weight support: the cell enlarged by the overlap (seed 003). The fit set may grow
        // beyond it, never shrink below it, so F vanishes near every point in the support.
        let h0 = self.support_half(0.5 * ctx.cube.size);
        let idx0 = self.in_box(&c, h0);
        if idx0.len() > o.max_points && ctx.can_split {
            return Decision::Split;
        }
        let mut h = h0;
        let mut idx = idx0.clone();
        let empty = idx0.is_empty();
        // Sparse cells grow their fit set up to `max_growth`; empty ones (holes) as far as needed.
        let limit = if empty {
            self.root_half
        } else {
            h0 * o.max_growth
        };
        while idx.len() < o.min_points && h < limit {
            h *= 1.25;
            idx = self.in_box(&c, h);
        }
        if empty && idx.len() < o.min_points {
            // Far from the points: a constant signed-distance estimate.
            return self.constant(c, h0, 0);
        }
        if empty {
            if let Some(side) = self.side_cell(&c, h0) {
                return side;
            }
            // A large empty cell near the surface is split until bridges are fitted at the scale
            // of the point sets they use (a bridge extrapolated over a box much larger than its
            // data makes spurious sheets).
            if ctx.can_split && ctx.cube.size > MAX_BRIDGE_CELL * self.spacing {
                return Decision::Split;
            }
        }
        if empty {
            // A hole (or the space beside the surface): widen the fit set until it surrounds the
            // cell, reaching across the hole rather than only to its nearest edge. Only points
            // facing the same way as the nearest ones count (the rim of a hole in a flat base,
            // not the far side of a thin part).
            let nref: Vector3<f64> = self
                .kd
                .knn(&c, o.min_points)
                .iter()
                .map(|&(i, _)| self.nrm[i])
                .sum();
            let nref = nref.try_normalize(1e-12).unwrap_or_else(Vector3::zeros);
            let facing = |idx: Vec<usize>| -> Vec<usize> {
                idx.into_iter()
                    .filter(|&i| self.nrm[i].dot(&nref) > 0.5)
                    .collect()
            };
            idx = facing(idx);
            // A hole wider than a few times the distance to its nearest rim is not bridged
            // better by looking farther.
            let near = self.kd.nearest(&c).1;
            let hole_limit = limit.min(h0 + 6.0 * near);
            while o.bridge_openings
                && (idx.len() < 3 * o.min_points || !self.surrounds(&idx, &c))
                && h < hole_limit
            {
                h *= 1.25;
                idx = facing(self.in_box(&c, h));
            }
            // Bridge with the rim points nearest to the cell (seed 000: the hole's boundary and
            // its neighbourhood), not with the whole grown box, whose far parts only distort.
            let keep = BRIDGE_POINTS * o.min_points;
            if idx.len() > keep {
                let d2 = |i: &usize| (self.pts[*i] - c).norm_squared();
                idx.select_nth_unstable_by(keep - 1, |a, b| d2(a).total_cmp(&d2(b)).then(a.cmp(b)));
                idx.truncate(keep);
                idx.sort_unstable();
            }
        }
        let p: Vec<Point3<f64>> = idx.iter().map(|&i| self.pts[i]).collect();
        let n: Vec<Vector3<f64>> = idx.iter().map(|&i| self.nrm[i]).collect();
        let params = LocalParams {
            tolerance: self.tol,
            min_normal_cos: o.min_normal_cos,
            scale: h,
            rbf_eps: 0.1 * h,
        };
        let mut loose_sharp = None;
        if !empty {
            match self.sharp_cell(ctx, &c, h0, &idx, &p, &n, h) {
                Ok(d) => return d,
                Err(f) => loose_sharp = f,
            }
        }
        let mut best: Option<LocalFit> = None;
        // Empty cells only extrapolate: a looser tolerance, and the lowest degree meeting it.
        let tol = if empty { 10.0 * self.tol } else { self.tol };
        if let Some(frame) = local::height_frame(&p, &n, &params) {
            for degree in [Degree::Quadratic, Degree::Cubic] {
                let fit = local::fit_poly(&p, &n, frame, degree);
                if let Some(f) = fit.as_ref().filter(|f| f.meets(tol)) {
                    if empty {
                        return self.leaf_with(c, h0, p.len(), f.clone(), CellRole::Bridge);
                    }
                    if ctx.can_split && self.has_gap(&ctx.cube, &f.function) {
                        // The points cover only part of the cell: extrapolating over the rest
                        // (a hole) is better done by smaller cells with wider fits.
                        return Decision::Split;
                    }
                    return self.leaf(c, h0, p.len(), f.clone());
                }
                best = local::better(best, fit, tol);
            }
        }
        if empty {
            // An empty cell next to the points (a hole, or the space beside the surface): its
            // function only extrapolates, so a looser fit is fine. Where no height function fits
            // (the hole's rim bends), a thin-plate RBF through the rim bridges it as in seed 003;
            // a bad fit becomes a constant.
            // A cheap polynomial within the loose tolerance is enough; the RBF only where the
            // polynomials are far off.
            if !best
                .as_ref()
                .is_some_and(|f| f.max_residual <= tol && f.normal_agreement >= 0.9)
            {
                best = local::better(best, self.rbf(&p, &n, &params), tol);
            }
            // Any sensible bridge beats a constant, whose jumps to its neighbours are walls.
            return match best {
                Some(f) if f.max_residual <= tol.max(0.25 * h) && f.normal_agreement >= 0.9 => {
                    self.leaf_with(c, h0, p.len(), f, CellRole::Bridge)
                }
                _ => self.constant(c, h0, 0),
            };
        }
        // Split while that makes the fit set more local: the cell holds more than a few points,
        // or its fit set had to grow well beyond it (the cell clips the surface at a corner).
        if ctx.can_split
            && (idx0.len() > o.min_points / 2 || (h > 2.0 * h0 && h0 > self.sampling_radius(&c)))
        {
            return Decision::Split;
        }
        // Too small to split. A crease cell keeps its sharp function when that is within
        // SHARP_LEAF_FACTOR times the tolerance: the smooth fits below would round the crease,
        // and the interpolating RBF overshoots it between the points.
        if let Some(f) = loose_sharp.filter(|f| {
            f.max_residual <= SHARP_LEAF_FACTOR * self.tol
                && f.normal_agreement >= SHARP_LEAF_AGREEMENT
        }) {
            return self.leaf(c, h0, p.len(), *f);
        }
        // A polynomial within a few times the tolerance is kept: what it
        // misses at this size is noise, which a least-squares fit smooths and an interpolating
        // RBF would follow with wiggles. Otherwise (folds, sharp features) an RBF through the
        // (sub-sampled) support.
        if best
            .as_ref()
            .is_some_and(|f| f.max_residual <= LEAF_FACTOR * self.tol && f.normal_agreement >= 1.0)
        {
            return self.leaf(c, h0, p.len(), best.unwrap_or_else(|| unreachable!()));
        }
        best = local::better(best, self.rbf(&p, &n, &params), self.tol);
        if best.is_none() {
            // Last resort: a plane-like height function along the mean normal.
            let mean: Vector3<f64> = n.iter().sum();
            let centroid = p.iter().map(|q| q.coords).sum::<Vector3<f64>>() / p.len() as f64;
            if let Some(frame) = crate::implicit::poly::Frame::new(Point3::from(centroid), mean, h)
            {
                best = local::fit_poly(&p, &n, frame, Degree::Linear);
            }
        }
        match best {
            Some(f) => self.leaf(c, h0, p.len(), f),
            None => self.constant(c, h0, p.len()),
        }
    }
}
