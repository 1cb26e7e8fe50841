//! The partition-of-unity implicit: local functions on an adaptive octree blended with the
//! weight of seed 003 eq. 7-8.
//!
//! ```text
//! t_r = (x_r - c_r) / a_r            (c: centre, a: half-widths of the support box)
//! d(x) = 1 - prod_r (1 - t_r^2)      (eq. 7a: 4 (x_r - S_r)(T_r - x_r) / (T_r - S_r)^2 = 1 - t_r^2)
//! W(d) = -6 d^5 + 15 d^4 - 10 d^3 + 1   (eq. 7b; 0 outside the box)
//! F(x) = sum_i W_i(x) f_i(x) / sum_i W_i(x)   (eq. 8)
//! ```
//!
//! Domains (seed 003 section 3.1, seed 004 section 2.1): the root cube around the points is split
//! while a cell's support holds more than `max_points` points or its best local function misses
//! the tolerance (never below the points' estimated noise, see `noise.rs`). A cell's weight
//! support is the cell enlarged by `overlap` (seed 003: about 10 %); its fit set is the points in
//! that box, grown while there are fewer than `min_points`. Each local function is fitted to
//! *all* points inside its support, so wherever the weights are non-zero every contributing
//! function nearly vanishes at the points, and so does the blend. A domain too small to split
//! keeps a polynomial within 1.5 times the tolerance (the misfit is noise there), else an RBF.
//!
//! **Blending band.** Where two cells' weights overlap, F slides from one local function to
//! the other across the band by which a support reaches beyond its cell. Each function is
//! only within the tolerance tol of the points, so neighbours may put the surface up to about
//! 2 tol apart, and across a band of width b the blended zero set tilts by up to 2 tol / b; at
//! a cell's corners, where all weights are small (W(d) ~ 10 (1 - d)^3 as d -> 1) and their
//! ratios change fastest, a narrow band turns that disagreement into folds and detached
//! flakes of the zero set a fraction of a band long. Seed 003's 10 % overlap gives fine cells
//! (the Stanford bunny's: 2e-3 across, tol 5e-5) a band of 1e-4 = 2 tol, and sections of the
//! bunny's implicit there show thin detached sheets and spikes beside the surface, which
//! `fit`'s patches followed into pockets and creases. So the band is at least `min_band`
//! (12) tolerances, capped at [`MAX_OVERLAP`] of the cell's half-width and never below
//! `overlap`: coarse cells keep seed 003's overlap, fine ones get up to half their
//! half-width. Measured (`docs/BENCHMARKS.md`, fit, session 7): lines through every 10th
//! triangle of the bunny crossing the zero set more than once 5 -> 0 of 6,946 (the test
//! below); patches `fit` reports folded 5 -> 1 (bunny), 125 -> 83 (cow); fit's normal jump
//! p95 on the bunny 0.27 -> 0.24 degrees, the cow's samples over 5 degrees 46 -> 26; the
//! implicit takes about twice as long to fit and to evaluate (more, smaller cells: a wider
//! support is harder to fit within the tolerance).
//!
//! Cells without points have one of two roles ([`CellRole`]):
//! * a *bridge* where the surface may cross the cell (a hole): fitted to the rim points nearest
//!   to it, with a wider support; bridges blend in with the distance from the points
//!   (see `PouImplicit::blend`), so near the data only the fitted cells count;
//! * a *fallback* beside the surface or far from it: a rough signed distance (a quadratic of the
//!   nearest points, their tangent plane, or a constant) used only where nothing else reaches,
//!   so that F is defined everywhere in the root cube.
//!
//! The three families meet in one quotient whose priorities fall smoothly to zero where the
//! family above covers a point, so F is C2 in the whole root cube (no seam where the fitted
//! cells' supports end; see `PouImplicit::blend`). Outside the supports (beyond the root cube's
//! overlap) F is the distance to the nearest point, signed by its normal.
//!
//! Fitting is parallel (rayon, one octree level at a time, collected in order): the result does
//! not depend on the thread count.

use super::local::{LocalFunction, LocalKind};
use super::Implicit;
use crate::mesh::Aabb;
use crate::spatial::{BoxIndex, Cube, KdTree, Octree};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

mod build;
mod density;
mod sharp_cell;
use build::Builder;
use density::{density_probes, DensityProbes, DENSITY_FULL, DENSITY_RADIUS};

/// Options of [`PouImplicit::fit`], with documented defaults.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FitOptions {
    /// Largest accepted |f| at a domain's points, as a fraction of the bounding-box diagonal
    /// (default 2e-4, about the noise of a good scan; raised to the estimated noise of the
    /// points when that is larger). Domains that miss it are split; when too small to split
    /// they keep a polynomial within 1.5 times the tolerance, or else use an RBF.
    pub tolerance: f64,
    /// A domain whose support holds more points is split (default 120; seed 003: 30-300).
    pub max_points: usize,
    /// A support with fewer points is grown (default 20).
    pub min_points: usize,
    /// Support = cell enlarged by this fraction of its edge (default 0.1, seed 003).
    pub overlap: f64,
    /// Smallest width of the blending band beyond a cell, in tolerances (default 12; 0 gives
    /// the plain `overlap` of seed 003): see the module doc, "Blending band".
    pub min_band: f64,
    /// Largest growth of a support's half-width over the cell's, for sparse cells (default 4).
    pub max_growth: f64,
    /// Deepest octree level (default 16).
    pub max_depth: u32,
    /// Largest support handled by an RBF; larger ones are subsampled (default 60).
    pub rbf_max_points: usize,
    /// Smallest normal . axis for a height polynomial (default 0.3).
    pub min_normal_cos: f64,
    /// Empty cells next to the points widen their fit set until it surrounds them, so that
    /// the bridge reaches across a hole (default true). `fit --close open` turns it off: the
    /// surface beyond the data's edge is cut away there, and on a scan with a whole side
    /// missing the widening never succeeds and costs most of the fit (block scanned from
    /// above: implicit 63 s with, 4.8 s without).
    pub bridge_openings: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            tolerance: 2e-4,
            max_points: 120,
            min_points: 20,
            overlap: 0.1,
            min_band: 12.0,
            max_growth: 4.0,
            max_depth: 16,
            rbf_max_points: 60,
            min_normal_cos: 0.3,
            bridge_openings: true,
        }
    }
}

impl FitOptions {
    fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(Error::InvalidOption(m.to_string()));
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return bad("tolerance must be positive");
        }
        if self.min_points < 4 || self.max_points < 2 * self.min_points {
            return bad("need min_points >= 4 and max_points >= 2 min_points");
        }
        if !(self.overlap > 0.0 && self.overlap <= 2.0) {
            return bad("overlap must be in (0, 2]");
        }
        if !(self.min_band >= 0.0 && self.min_band.is_finite()) {
            return bad("min_band must be a non-negative number of tolerances");
        }
        if !(self.max_growth >= 1.0 && self.max_growth.is_finite()) {
            return bad("max_growth must be >= 1");
        }
        if self.max_depth == 0 || self.max_depth > 30 {
            return bad("max_depth must be in 1..=30");
        }
        if self.rbf_max_points < 10 {
            return bad("rbf_max_points must be >= 10");
        }
        Ok(())
    }
}

/// What the fit produced.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FitStats {
    /// Estimated scatter of the points about the surface (rms), relative to the diagonal.
    pub noise: f64,
    /// The tolerance used: the requested one, raised to the noise if that is larger.
    pub tolerance: f64,
    pub points: usize,
    pub cells: usize,
    pub linear: usize,
    pub quadratic: usize,
    pub cubic: usize,
    pub rbf: usize,
    /// Cells crossed by a crease: one polynomial per region, combined by max / min
    /// ([`super::sharp`]; only with regions given, [`PouImplicit::fit_with_regions`]).
    pub sharp: usize,
    pub constant: usize,
    /// Cells without points in their support (holes, empty space), counted in the kinds above.
    pub extrapolating: usize,
    /// Extrapolating cells that use an RBF (hole bridges).
    pub extrapolating_rbf: usize,
    /// Cells whose function misses the tolerance (too few points to split further).
    pub over_tolerance: usize,
    pub max_depth: u32,
    /// Largest |f| at a support point over all cells, relative to the diagonal.
    pub max_residual: f64,
    pub mean_support_points: f64,
    pub diagonal: f64,
}

/// What a domain's function is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum CellRole {
    /// Fitted to the points in its support (seed 003/004 local functions).
    Fitted,
    /// Bridges a hole: fitted to the rim points around an empty cell the surface crosses.
    Bridge,
    /// Empty space beside the surface or far from it: a rough signed distance that only counts
    /// where nothing else reaches.
    Fallback,
}

/// One domain: its support box and function.
#[derive(Debug, Clone)]
pub struct Cell {
    pub center: Point3<f64>,
    pub half: Vector3<f64>,
    /// 1 / `half`, per axis: the blend multiplies by it (divisions were a tenth of the blend).
    pub inv_half: Vector3<f64>,
    /// Half-width of the cell itself relative to its support's (the support reaches one
    /// blending band beyond the cell: module doc, "Blending band").
    pub core: f64,
    /// 1 / (1 - `core`), the blending band's width in units of `half`, inverted.
    pub inv_band: f64,
    pub function: LocalFunction,
    /// Fitted, bridge or fallback (see `PouImplicit::blend` for how they combine).
    pub role: CellRole,
    pub support_points: u32,
    pub max_residual: f64,
    pub meets_tolerance: bool,
}

/// The blended implicit surface.
#[derive(Debug)]
pub struct PouImplicit {
    tree: Octree<Cell>,
    points: Vec<Point3<f64>>,
    normals: Vec<Vector3<f64>>,
    kd: KdTree,
    /// The points in Morton order, for box queries ([`BoxIndex`]): the density's.
    boxes: BoxIndex,
    diagonal: f64,
    /// Typical point spacing (see `sample_spacing`).
    spacing: f64,
    /// `dense`'s first try, [`DensityProbes`].
    probes: DensityProbes,
    stats: FitStats,
}

/// With regions ([`PouImplicit::fit_with_regions`]) the tolerance is at least this many times
/// the points' noise (rms): a fit within one sigma at every point splits the cells until they
/// follow the noise (make_parts' block from its 0.01 mm noisy cloud, `reconstruct --sharp`:
/// face normal error p95 5.0 degrees with 1, 2.3 with 2, 1.3 with 3).
const REGION_NOISE_FACTOR: f64 = 3.0;

/// Median over up to 2000 strided points of the distance to the 8th nearest neighbour divided by
/// sqrt(8 / pi): the spacing of an even sampling with the same density.
fn sample_spacing(points: &[Point3<f64>], kd: &KdTree) -> f64 {
    const K: usize = 8;
    if points.len() <= K {
        return 0.0;
    }
    let step = (points.len() / 2000).max(1);
    let mut d: Vec<f64> = (0..points.len())
        .step_by(step)
        .map(|i| kd.knn(&points[i], K + 1).last().map_or(0.0, |x| x.1))
        .collect();
    let m = d.len() / 2;
    let (_, v, _) = d.select_nth_unstable_by(m, f64::total_cmp);
    *v / (K as f64 / std::f64::consts::PI).sqrt()
}

/// Seed 003 eq. 7b and its derivative dW/dd.
#[inline]
fn weight(d: f64) -> (f64, f64) {
    let d2 = d * d;
    let w = 1.0 + d2 * d * (-10.0 + d * (15.0 - 6.0 * d));
    let dw = -30.0 * d2 * (1.0 - d) * (1.0 - d);
    (w, dw)
}

/// Seed 003 eq. 7b as a C2 ramp from 1 (u <= 0) to 0 (u >= 1), and its derivative.
#[inline]
fn ramp(u: f64) -> (f64, f64) {
    if u <= 0.0 {
        (1.0, 0.0)
    } else if u >= 1.0 {
        (0.0, 0.0)
    } else {
        weight(u)
    }
}

impl PouImplicit {
    /// Fits the implicit to oriented points (normals point outwards, need not be unit).
    /// Points with a zero or non-finite normal are left out.
    pub fn fit(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        opts: &FitOptions,
    ) -> Result<PouImplicit> {
        Self::fit_with_regions(points, normals, None, opts)
    }

    /// [`Self::fit`] with the smooth region of every point ([`crate::features`];
    /// [`super::sharp::NO_REGION`] for none) and normals of that region alone: a cell whose
    /// support holds two or three regions is first fitted with a sharp function
    /// ([`super::sharp`]), so the zero set keeps the creases between them. `None` is
    /// [`Self::fit`].
    pub fn fit_with_regions(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        regions: Option<&[u32]>,
        opts: &FitOptions,
    ) -> Result<PouImplicit> {
        Self::fit_labelled(points, normals, regions, None, opts)
    }

    /// [`Self::fit_with_regions`] with, for a cloud, a second normal per point, of its own region
    /// alone (`side_normals`, [`crate::features::Segmentation::labels_normals_and_sides`];
    /// `None`, a mesh's case, is `fit_with_regions`): a crease
    /// cell's sharp function is fitted with `normals` (with `side_normals` where those give a
    /// side no height frame), and a point counts against it only when neither of its normals
    /// agrees ([`super::sharp::SharpFunction::evaluate`]: an estimated normal beside a crease
    /// can be the other face's or lie along the crease).
    pub fn fit_with_sides(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        regions: &[u32],
        side_normals: Option<&[Vector3<f64>]>,
        opts: &FitOptions,
    ) -> Result<PouImplicit> {
        if let Some(sn) = side_normals.filter(|sn| sn.len() != points.len()) {
            return Err(Error::Degenerate(format!(
                "{} points but {} one-sided normals",
                points.len(),
                sn.len()
            )));
        }
        Self::fit_labelled(points, normals, Some(regions), side_normals, opts)
    }

    fn fit_labelled(
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        regions: Option<&[u32]>,
        side_normals: Option<&[Vector3<f64>]>,
        opts: &FitOptions,
    ) -> Result<PouImplicit> {
        opts.validate()?;
        if points.len() != normals.len() {
            return Err(Error::Degenerate(format!(
                "{} points but {} normals",
                points.len(),
                normals.len()
            )));
        }
        if let Some(r) = regions {
            if r.len() != points.len() {
                return Err(Error::Degenerate(format!(
                    "{} points but {} region labels",
                    points.len(),
                    r.len()
                )));
            }
        }
        let mut pts = Vec::with_capacity(points.len());
        let mut nrm = Vec::with_capacity(points.len());
        let mut labels = Vec::new();
        let mut side_nrm = Vec::new();
        for (i, (p, n)) in points.iter().zip(normals).enumerate() {
            if !p.coords.iter().all(|c| c.is_finite()) {
                return Err(Error::Degenerate("non-finite point coordinate".into()));
            }
            if let Some(u) = n.try_normalize(1e-300) {
                if u.iter().all(|c| c.is_finite()) {
                    pts.push(*p);
                    nrm.push(u);
                    if let Some(r) = regions {
                        labels.push(r[i]);
                    }
                    if let Some(sn) = side_normals {
                        side_nrm.push(sn[i].try_normalize(1e-300).unwrap_or(u));
                    }
                }
            }
        }
        if pts.len() < 10 {
            return Err(Error::Degenerate(format!(
                "an implicit surface needs at least 10 oriented points, got {}",
                pts.len()
            )));
        }
        let bbox = Aabb::of(&pts).ok_or_else(|| Error::Degenerate("no points".into()))?;
        let diagonal = bbox.diagonal();
        if diagonal.is_nan() || diagonal <= 0.0 {
            return Err(Error::Degenerate("all points coincide".into()));
        }
        // Points on one plane (or line) enclose no volume: no closed surface to find.
        {
            let mut mean = Vector3::zeros();
            for p in &pts {
                mean += p.coords;
            }
            mean /= pts.len() as f64;
            let mut cov = nalgebra::Matrix3::zeros();
            for p in &pts {
                let d = p.coords - mean;
                cov += d * d.transpose();
            }
            let ev = nalgebra::SymmetricEigen::new(cov / pts.len() as f64).eigenvalues;
            let thinnest = ev.min().max(0.0).sqrt();
            if thinnest <= 1e-6 * diagonal {
                return Err(Error::Degenerate(format!(
                    "the points lie on a plane: they enclose no volume (thinnest spread \
                     {thinnest:.3e} against a bounding-box diagonal of {diagonal:.3e}; parts \
                     far apart make each part look flat, so fit them separately)"
                )));
            }
        }
        let kd = KdTree::build(&pts)?;
        let root = Cube::around(&bbox, 0.1);
        // The tolerance is never below the points' own scatter (see `noise`): asking more only
        // splits domains until they interpolate the noise.
        let noise = super::noise::estimate_noise(&pts, &nrm, &kd, opts.min_points, 2000);
        // With regions every face is smooth at the scale of the noise: its cells may leave the
        // noise's own scatter (about 3 sigma at most) rather than follow it.
        let noise_factor = if regions.is_some() {
            REGION_NOISE_FACTOR
        } else {
            1.0
        };
        let tol = (opts.tolerance * diagonal).max(noise_factor * noise);
        let spacing = sample_spacing(&pts, &kd).max(1e-9 * diagonal);
        let boxes = BoxIndex::build(&pts);
        let builder = Builder {
            pts: &pts,
            nrm: &nrm,
            kd: &kd,
            boxes: &boxes,
            opts,
            tol,
            spacing,
            root_half: 0.5 * root.size,
            labels: regions.map(|_| labels.as_slice()),
            side_nrm: side_normals.map(|_| side_nrm.as_slice()),
        };
        let tree = Octree::build(root, &pts, opts.max_depth, |c| builder.decide(c));
        let mut stats = FitStats {
            noise: noise / diagonal,
            tolerance: tol / diagonal,
            points: pts.len(),
            cells: tree.payloads().len(),
            diagonal,
            ..Default::default()
        };
        let mut support_sum = 0usize;
        for (cell, &depth) in tree.payloads().iter().zip(tree.leaf_depths()) {
            match cell.function.kind() {
                LocalKind::Linear => stats.linear += 1,
                LocalKind::Quadratic => stats.quadratic += 1,
                LocalKind::Cubic => stats.cubic += 1,
                LocalKind::Rbf => stats.rbf += 1,
                LocalKind::Sharp => stats.sharp += 1,
                LocalKind::Constant => stats.constant += 1,
            }
            if cell.role != CellRole::Fitted {
                stats.extrapolating += 1;
                if cell.function.kind() == LocalKind::Rbf {
                    stats.extrapolating_rbf += 1;
                }
            } else {
                if !cell.meets_tolerance {
                    stats.over_tolerance += 1;
                }
                stats.max_residual = stats.max_residual.max(cell.max_residual / diagonal);
            }
            stats.max_depth = stats.max_depth.max(depth);
            support_sum += cell.support_points as usize;
        }
        stats.mean_support_points = support_sum as f64 / stats.cells.max(1) as f64;
        let probes = density_probes(&tree, &kd, DENSITY_RADIUS * spacing);
        Ok(PouImplicit {
            tree,
            points: pts,
            normals: nrm,
            kd,
            boxes,
            diagonal,
            spacing,
            probes,
            stats,
        })
    }

    /// Fits the implicit to the input of a command: the referenced vertices of a mesh with its
    /// face normals, or a cloud with its own normals (flips repaired) or estimated ones (PCA
    /// over 12 neighbours, oriented by a minimum spanning tree). The two steps separately are
    /// [`crate::normals::oriented_points`] and [`PouImplicit::fit`].
    pub fn from_mesh(input: &crate::mesh::Mesh, opts: &FitOptions) -> Result<PouImplicit> {
        let op = crate::normals::oriented_points(input, crate::normals::DEFAULT_NEIGHBOURS)?;
        PouImplicit::fit(&op.points, &op.normals, opts)
    }

    /// Fit statistics.
    pub fn stats(&self) -> &FitStats {
        &self.stats
    }
    /// The oriented points the implicit was fitted to.
    pub fn points(&self) -> (&[Point3<f64>], &[Vector3<f64>]) {
        (&self.points, &self.normals)
    }
    /// k-d tree over [`Self::points`].
    pub fn kdtree(&self) -> &KdTree {
        &self.kd
    }
    /// Bounding-box diagonal of the points.
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }
    /// The root cube of the domain decomposition.
    pub fn domain(&self) -> Cube {
        self.tree.root()
    }
    /// The domains (for inspection and tests).
    pub fn cells(&self) -> &[Cell] {
        self.tree.payloads()
    }

    /// The cells whose support holds `x`, with their blending weight (seed 003 eq. 7) and value
    /// at `x` (for inspection and tests).
    pub fn contributions(&self, x: &Point3<f64>) -> Vec<(usize, f64, f64)> {
        let cells = self.tree.payloads();
        let mut out = Vec::new();
        self.tree.for_each_support(x, |l| {
            let c = &cells[l];
            let t = (x - c.center).component_mul(&c.inv_half);
            let prod: f64 = (0..3).map(|k| (1.0 - t[k] * t[k]).max(0.0)).product();
            let w = weight(1.0 - prod).0;
            out.push((l, w, c.function.value(x)));
        });
        out
    }

    /// F and grad F on the side of `region` of every crease: where sharp cells
    /// ([`super::sharp`]) with a side of that region reach x, the blend (seed 003 eq. 8) of
    /// those sides alone, so that the zero set continues the region's own surface past its
    /// creases (the two surfaces whose meeting is the crease, f_a = f_b = 0) without the
    /// smooth neighbours' rounding pulling it in; elsewhere the implicit itself.
    pub fn side_value_and_gradient(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let cells = self.tree.payloads();
        let (mut s, mut a) = (0.0, 0.0);
        let (mut gs, mut ga) = (Vector3::zeros(), Vector3::zeros());
        self.tree.for_each_support(x, |l| {
            let c = &cells[l];
            let LocalFunction::Sharp(sf) = &c.function else {
                return;
            };
            let Some((f, gf)) = sf.side_value_and_gradient(region, x) else {
                return;
            };
            let t = (x - c.center).component_mul(&c.inv_half);
            let q = Vector3::new(1.0 - t.x * t.x, 1.0 - t.y * t.y, 1.0 - t.z * t.z);
            if q.x <= 0.0 || q.y <= 0.0 || q.z <= 0.0 {
                return;
            }
            let (w, dw) = weight(1.0 - q.x * q.y * q.z);
            if w <= 0.0 {
                return;
            }
            let ih = c.inv_half;
            let gw = Vector3::new(
                2.0 * t.x * ih.x * q.y * q.z,
                2.0 * t.y * ih.y * q.x * q.z,
                2.0 * t.z * ih.z * q.x * q.y,
            ) * dw;
            s += w;
            a += w * f;
            gs += gw;
            ga += gw * f + gf * w;
        });
        if s > 0.0 {
            let f = a / s;
            (f, (ga - gs * f) / s)
        } else {
            self.blend(x, true)
        }
    }

    /// Signed distance to the nearest point (sign from its normal): F outside all supports.
    fn fallback(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let (i, d) = self.kd.nearest(x);
        let v = x - self.points[i];
        let s = if v.dot(&self.normals[i]) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let g = if d > 0.0 {
            v * (s / d)
        } else {
            self.normals[i]
        };
        (s * d, g)
    }

    /// F(x) and, when `with_gradient`, grad F(x) (seed 003 eq. 8 and its derivative).
    ///
    /// The three families of cells are blended in one quotient with priorities:
    ///
    /// ```text
    /// F = (A_fit + p A_bridge + q A_fallback) / (S_fit + p S_bridge + q S_fallback)
    /// A: sum of W_i f_i, S: sum of W_i over the family's cells whose support holds x
    /// C_k(x) = sum over family k of prod_r psi(t_r)   (coverage: psi = 1 on the cell itself,
    ///          falling C2 to 0 at the support's edge, so C_fit >= 1 wherever a fitted cell is)
    /// p = 1 - (1 - R(C_fit)) (1 - R(rho / rho_0))     (rho: data density, see `density`)
    /// q = R(C_fit + C_bridge)
    /// R(u) = W(clamp(u, 0, 1))                         (seed 003 eq. 7b as a C2 ramp 1 -> 0)
    /// ```
    ///
    /// Near the data (rho >= rho_0, about 1.5 spacings) and on fitted cells only the fitted
    /// functions count; bridges take over smoothly across the overlap band where the fitted
    /// cells end and, inside a hole, with the distance from the points; fallback cells only
    /// where neither reaches. Every weight is C2 and the denominator is positive everywhere in
    /// the root cube (its leaf cells tile it and each family reaches where the ones above end),
    /// so F is C2 there. Outside all supports (beyond the root cube's overlap) F is the signed
    /// distance to the nearest point.
    #[inline]
    fn blend(&self, x: &Point3<f64>, with_gradient: bool) -> (f64, Vector3<f64>) {
        #[derive(Default)]
        struct Acc {
            s: f64,
            a: f64,
            gs: Vector3<f64>,
            ga: Vector3<f64>,
            c: f64,
            gc: Vector3<f64>,
        }
        let mut acc = [Acc::default(), Acc::default(), Acc::default()];
        let cells = self.tree.payloads();
        let node = self.tree.for_each_support(x, |l| {
            let c = &cells[l];
            let t = (x - c.center).component_mul(&c.inv_half);
            let q = Vector3::new(1.0 - t.x * t.x, 1.0 - t.y * t.y, 1.0 - t.z * t.z);
            if q.x <= 0.0 || q.y <= 0.0 || q.z <= 0.0 {
                return;
            }
            let prod = q.x * q.y * q.z;
            let d = 1.0 - prod;
            let (w, dw) = weight(d);
            if w <= 0.0 {
                return;
            }
            let a = &mut acc[c.role as usize];
            let need_cover = c.role != CellRole::Fallback;
            let (core, inv_band) = (c.core, c.inv_band);
            let psi = |t: f64| -> (f64, f64) {
                let at = t.abs();
                if at <= core {
                    (1.0, 0.0)
                } else {
                    let (r, dr) = ramp((at - core) * inv_band);
                    (r, dr * t.signum() * inv_band)
                }
            };
            if with_gradient {
                let (f, gf) = c.function.value_and_gradient(x);
                // d d / d x_r = 2 t_r / a_r * prod_{s != r} q_s
                let ih = c.inv_half;
                let gd = Vector3::new(
                    2.0 * t.x * ih.x * q.y * q.z,
                    2.0 * t.y * ih.y * q.x * q.z,
                    2.0 * t.z * ih.z * q.x * q.y,
                );
                let gw = gd * dw;
                a.s += w;
                a.a += w * f;
                a.gs += gw;
                a.ga += gw * f + gf * w;
                if need_cover {
                    let (px, dx) = psi(t.x);
                    let (py, dy) = psi(t.y);
                    let (pz, dz) = psi(t.z);
                    a.c += px * py * pz;
                    a.gc += Vector3::new(
                        dx * ih.x * py * pz,
                        dy * ih.y * px * pz,
                        dz * ih.z * px * py,
                    );
                }
            } else {
                a.s += w;
                a.a += w * c.function.value(x);
                if need_cover {
                    a.c += psi(t.x).0 * psi(t.y).0 * psi(t.z).0;
                }
            }
        });
        let [fit, br, fb] = &acc;
        // Priority of the bridges: where no fitted cell covers x, or far from the points.
        let (pc, dpc) = ramp(fit.c);
        let (p, gp) = if br.s <= 0.0 || pc >= 1.0 {
            (pc, fit.gc * dpc)
        } else if self.dense(x, node) {
            // R(rho / rho_0) = 0 with zero slope: p = 1 - (1 - pc) = pc.
            (pc, fit.gc * dpc)
        } else {
            let (rho, grho) = self.density(x, with_gradient);
            if rho >= DENSITY_FULL {
                // As just above, so that the result does not depend on how it was decided.
                (pc, fit.gc * dpc)
            } else {
                let (pd, dpd) = ramp(rho / DENSITY_FULL);
                let p = 1.0 - (1.0 - pc) * (1.0 - pd);
                let gp = if with_gradient {
                    fit.gc * (dpc * (1.0 - pd)) + grho * (dpd / DENSITY_FULL * (1.0 - pc))
                } else {
                    Vector3::zeros()
                };
                (p, gp)
            }
        };
        // Priority of the fallback cells: where neither fitted cells nor bridges cover x.
        let (q, dq) = ramp(fit.c + br.c);
        let sw = fit.s + p * br.s + q * fb.s;
        if sw.is_nan() || sw <= 0.0 {
            return self.fallback(x);
        }
        let f = (fit.a + p * br.a + q * fb.a) / sw;
        if with_gradient {
            let gq = (fit.gc + br.gc) * dq;
            let ga = fit.ga + br.ga * p + gp * br.a + fb.ga * q + gq * fb.a;
            let gs = fit.gs + br.gs * p + gp * br.s + fb.gs * q + gq * fb.s;
            (f, (ga - gs * f) / sw)
        } else {
            (f, Vector3::zeros())
        }
    }
}

impl Implicit for PouImplicit {
    fn value(&self, x: &Point3<f64>) -> f64 {
        self.blend(x, false).0
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.blend(x, true).1
    }
    fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        self.blend(x, true)
    }
}

#[cfg(test)]
pub(crate) mod tests;
