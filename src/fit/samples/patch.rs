//! One patch's sample grid from its four boundary edges: interior rows as section curves
//! (the Coons patch of the boundary rows as hint and fallback), cross-boundary derivatives, and
//! the deviation estimate that drives refinement (see the parent module's doc).

use super::super::edge_curve::{residual, sample_section, EdgeSamples};
use super::super::spline_check::spline_midpoints;
use super::near::keep_near;
use super::{uniform_params, PatchSamples, PatchSide, SampleOptions};
use crate::implicit::Implicit;
use crate::polygonize::newton::{project, solve_on_line, NewtonOptions};
use crate::polygonize::QuadNet;
use crate::quality::support::grid_cell;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// One side's samples in the patch direction: points, along-side derivatives, normals, and
/// the section plane's in-plane normal.
struct Side {
    p: Vec<Point3<f64>>,
    d: Vec<Vector3<f64>>,
    n: Vec<Vector3<f64>>,
    w: Vector3<f64>,
}

fn side(e: &EdgeSamples, reversed: bool) -> Side {
    if reversed {
        Side {
            p: e.points.iter().rev().copied().collect(),
            d: e.tangents.iter().rev().map(|t| -t).collect(),
            n: e.normals.iter().rev().copied().collect(),
            w: e.plane_w,
        }
    } else {
        Side {
            p: e.points.clone(),
            d: e.tangents.clone(),
            n: e.normals.clone(),
            w: e.plane_w,
        }
    }
}

/// Which parameter a side runs along: `V` sides (v = 0, v = 1) run along u, `U` sides along v.
#[derive(Clone, Copy)]
pub(super) enum SideKind {
    U,
    V,
}

/// The unit vector of the tangent plane (normal `n`) perpendicular to a side whose derivative
/// along itself is `along`, pointing the way the patch parameter across the side increases:
/// N x C' on a v side, C' x N on a u side, so that S_u x S_v points along N.
fn across(kind: SideKind, along: &Vector3<f64>, n: &Vector3<f64>) -> Option<Vector3<f64>> {
    match kind {
        SideKind::V => n.cross(along),
        SideKind::U => along.cross(n),
    }
    .try_normalize(1e-300)
}

/// Reflects the interior cross derivatives of one side that point backwards across it,
/// D -> D - 2 (D . e) e with e from [`across`]. A one-sided difference of the sample columns
/// reaches back across the side where the patch wraps the rim of a part thinner than the
/// sample spacing (the bunny's ear tip); left as it is, the patch's normal there is flipped
/// and the two neighbours' normals differ by 180 degrees at that sample. Reflection keeps the
/// derivative's length and its component along the side. Default bunny: the largest normal
/// jump (our measure) 180 -> 92 degrees, edge samples over 5 degrees 40 -> 36; the cow 314 ->
/// 236, the Utah teapot 571 -> 432.
pub(super) fn point_into_patch(
    d: &mut [Vector3<f64>],
    along: &[Vector3<f64>],
    normals: &[Vector3<f64>],
    kind: SideKind,
) {
    let n = d.len().min(along.len()).min(normals.len());
    for k in 1..n.saturating_sub(1) {
        if let Some(e) = across(kind, &along[k], &normals[k]) {
            let b = d[k].dot(&e);
            if b < 0.0 {
                d[k] -= e * (2.0 * b);
            }
        }
    }
}

fn tangent_part(x: Vector3<f64>, n: &Vector3<f64>) -> Vector3<f64> {
    x - n * n.dot(&x)
}

/// Derivative at p[0] of the polynomial through p[0], p[1], ... at uniform steps `h`, of
/// degree min(n, 3) (n the number of intervals available): one-sided differences of order up
/// to three.
fn one_sided_derivative(p: [Vector3<f64>; 4], n: usize, h: f64) -> Vector3<f64> {
    match n {
        0 => Vector3::zeros(),
        1 => (p[1] - p[0]) / h,
        2 => ((p[1] - p[0]) * 4.0 - (p[2] - p[0])) / (2.0 * h),
        _ => ((p[1] - p[0]) * 18.0 - (p[2] - p[0]) * 9.0 + (p[3] - p[0]) * 2.0) / (6.0 * h),
    }
}

/// An interior row: points, normals, d/du at both ends, samples left off the surface, the
/// largest |f| / |grad f| of its points.
type Row = (
    Vec<Point3<f64>>,
    Vec<Vector3<f64>>,
    Vector3<f64>,
    Vector3<f64>,
    usize,
    f64,
);

/// The transfinite (Coons) patch of four boundary sample rows, for interior hints and the
/// fallback: P = (1-v) B(u) + v T(u) + (1-u) L(v) + u R(v) - bilinear(corners).
struct Coons<'a> {
    bot: &'a Side,
    top: &'a Side,
    left: &'a Side,
    right: &'a Side,
    corners: [Point3<f64>; 4],
}

impl Coons<'_> {
    /// Point at sample (i, j), parameters (u, v).
    fn point(&self, i: usize, j: usize, u: f64, v: f64) -> Point3<f64> {
        let [ca, cb, cc, cd] = self.corners.map(|p| p.coords);
        Point3::from(
            self.bot.p[i].coords * (1.0 - v)
                + self.top.p[i].coords * v
                + self.left.p[j].coords * (1.0 - u)
                + self.right.p[j].coords * u
                - (ca * ((1.0 - u) * (1.0 - v))
                    + cb * (u * (1.0 - v))
                    + cc * (u * v)
                    + cd * ((1.0 - u) * v)),
        )
    }
    /// Unit normal P_u x P_v at sample (i, j) (outward); the blend of the boundary normals where
    /// that degenerates.
    fn normal(&self, i: usize, j: usize, u: f64, v: f64) -> Vector3<f64> {
        let [ca, cb, cc, cd] = self.corners;
        let (b, t, l, r) = (self.bot, self.top, self.left, self.right);
        let su = b.d[i] * (1.0 - v) + t.d[i] * v + (r.p[j] - l.p[j])
            - ((cb - ca) * (1.0 - v) + (cc - cd) * v);
        let sv = l.d[j] * (1.0 - u) + r.d[j] * u + (t.p[i] - b.p[i])
            - ((cd - ca) * (1.0 - u) + (cc - cb) * u);
        let s = b.n.len() - 1;
        let blend = b.n[i] * (1.0 - v) + t.n[i] * v + l.n[j] * (1.0 - u) + r.n[j] * u
            - (b.n[0] * ((1.0 - u) * (1.0 - v))
                + b.n[s] * (u * (1.0 - v))
                + t.n[s] * (u * v)
                + t.n[0] * ((1.0 - u) * v));
        su.cross(&sv)
            .try_normalize(1e-12 * su.norm() * sv.norm())
            .or_else(|| blend.try_normalize(1e-12))
            .unwrap_or_else(Vector3::zeros)
    }

    /// Largest distance an interior sample may lie from its Coons point: twice the longer
    /// diagonal of the quad. A section curve that leaves this band has run onto another
    /// sheet (in a concave crease narrower than a patch the section plane also cuts the
    /// surface across the crease: on the bunny's base two rows ran 3-4 patch widths down to
    /// the bottom and the patch grew a spike). Half a diagonal removed those spikes too but
    /// rejected honest rows on the cow's thin legs, where the Coons surface is far from the
    /// surface (mean deviation 4.1e-4 -> 8.2e-4); twice the diagonal keeps them (4.4e-4).
    fn reach(&self) -> f64 {
        let [ca, cb, cc, cd] = self.corners;
        2.0 * (cc - ca).norm().max((cd - cb).norm())
    }

    /// Whether every sample of row j lies within [`Coons::reach`] of its Coons point.
    fn row_near(&self, row: &[Point3<f64>], j: usize, pu: &[f64], v: f64) -> bool {
        let r2 = self.reach().powi(2);
        row.iter()
            .zip(pu)
            .enumerate()
            .all(|(i, (p, &u))| (p - self.point(i, j, u, v)).norm_squared() <= r2)
    }

    /// d/du of the Coons patch at both ends of row j (at `v`).
    fn row_ends(&self, j: usize, v: f64) -> (Vector3<f64>, Vector3<f64>) {
        let s = self.bot.p.len() - 1;
        let [ca, cb, cc, cd] = self.corners;
        let common = (self.right.p[j] - self.left.p[j]) - ((cb - ca) * (1.0 - v) + (cc - cd) * v);
        let d0 = self.bot.d[0] * (1.0 - v) + self.top.d[0] * v + common;
        let d1 = self.bot.d[s] * (1.0 - v) + self.top.d[s] * v + common;
        (d0, d1)
    }

    /// Row j as the Coons points themselves, all left off f = 0 (the last resort of
    /// [`unballoon`]), with the Coons normals and the largest |f| / |grad f| of its points (how
    /// far off they are, for the report).
    fn row_raw<I: Implicit + ?Sized>(&self, f: &I, j: usize, pu: &[f64], v: f64) -> Row {
        let s = pu.len() - 1;
        let row: Vec<Point3<f64>> = (0..=s).map(|i| self.point(i, j, pu[i], v)).collect();
        let normals = (0..=s).map(|i| self.normal(i, j, pu[i], v)).collect();
        let worst = row[1..s].iter().fold(0.0, |w: f64, p| {
            let (val, g) = f.value_and_gradient(p);
            w.max(residual(val, &g))
        });
        let (d0, d1) = self.row_ends(j, v);
        (row, normals, d0, d1, s.saturating_sub(1), worst)
    }

    /// Row j from Coons points moved onto f = 0 along the Coons normal (kept where that fails),
    /// with the row's end derivatives from the Coons derivative; also the count of points left
    /// off the surface.
    fn row_fallback<I: Implicit + ?Sized>(
        &self,
        f: &I,
        j: usize,
        pu: &[f64],
        v: f64,
        tol: f64,
        scale: f64,
    ) -> Row {
        let s = pu.len() - 1;
        let reach = 0.5 * self.reach();
        let newton = NewtonOptions::new(scale, reach);
        let mut missed = 0;
        let row: Vec<Point3<f64>> = (0..=s)
            .map(|i| {
                if i == 0 {
                    return self.left.p[j];
                }
                if i == s {
                    return self.right.p[j];
                }
                let x = self.point(i, j, pu[i], v);
                let n = self.normal(i, j, pu[i], v);
                if n.norm_squared() > 0.0 {
                    if let Ok((sv, _)) = solve_on_line(f, x, n, reach, tol) {
                        return x + n * sv;
                    }
                }
                match project(f, x, &newton) {
                    Ok((p, _)) => p,
                    Err(_) => {
                        missed += 1;
                        x
                    }
                }
            })
            .collect();
        let (d0, d1) = self.row_ends(j, v);
        let mut worst = 0.0f64;
        let normals = row
            .iter()
            .map(|p| {
                let (v, g) = f.value_and_gradient(p);
                worst = worst.max(residual(v, &g));
                g.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
            })
            .collect();
        (row, normals, d0, d1, missed, worst)
    }
}

/// How many times the Coons patch's area a patch's sample grid may cover in an open fit
/// before its rows are looked at again ([`unballoon`]). The cow seen from its side
/// (`scripts/view_scans.py`): a few patches on the rim strip covered 10-28 times their Coons
/// area round the far ear, horn and tail; rebuilt, the area farther than 1 % of the diagonal
/// from the data fell from 0.557 % to 0.070 % and the input points' p99 from 1.10e-3 to
/// 3.90e-4 of the diagonal. Without the test for cells away from the data, patches wrapping
/// the ear of the cow cut at its middle (on the data) were flattened too: p99 4.46e-4 ->
/// 7.51e-4.
pub(super) const BALLOON: f64 = 3.0;

/// Area of a grid of points (`points(i, j)`, S x T cells) and of its cells whose centre is
/// `away`, each cell measured as [`crate::quality::support`] measures it
/// ([`grid_cell`]).
fn grid_area(
    points: impl Fn(usize, usize) -> Point3<f64>,
    s: usize,
    t: usize,
    away: impl Fn(&Point3<f64>) -> bool,
) -> (f64, f64) {
    let (mut area, mut off) = (0.0, 0.0);
    for i in 0..s {
        for j in 0..t {
            let (a, c) = grid_cell(
                points(i, j),
                points(i + 1, j),
                points(i, j + 1),
                points(i + 1, j + 1),
            );
            area += a;
            if away(&c) {
                off += a;
            }
        }
    }
    (area, off)
}

/// The interior rows of an open fit's patch, with whether they were replaced. The section
/// rows stay unless their grid both covers more than [`BALLOON`] times the area of the Coons
/// patch of the sides and has cells `away` from the data: rows running round a part beside
/// the patch, out of the data (a patch wrapping a thin part of the data honestly covers more
/// than its Coons patch too, but on the data). Then the first of `projected()` (the Coons rows
/// projected onto f = 0) and `raw()` (the Coons rows themselves, off the implicit) that covers
/// at most that much with at most half as much area away from the data replaces them.
fn unballoon(
    coons: &Coons,
    rows: Vec<Row>,
    pu: &[f64],
    pv: &[f64],
    away: impl Fn(&Point3<f64>) -> bool,
    projected: impl FnOnce() -> Vec<Row>,
    raw: impl FnOnce() -> Vec<Row>,
) -> (Vec<Row>, bool) {
    let (s, t) = (pu.len() - 1, pv.len() - 1);
    // With `off`: the area away from the data too (a nearest-point query per cell, made only
    // for patches that cover too much).
    let area = |rows: &[Row], off: bool| {
        let at = |i: usize, j: usize| {
            if j == 0 {
                coons.bot.p[i]
            } else if j == t {
                coons.top.p[i]
            } else {
                rows[j - 1].0[i]
            }
        };
        grid_area(at, s, t, |c| off && away(c))
    };
    let (coons_area, _) = grid_area(|i, j| coons.point(i, j, pu[i], pv[j]), s, t, |_| false);
    let limit = BALLOON * coons_area;
    if area(&rows, false).0 <= limit {
        return (rows, false);
    }
    let (_, off) = area(&rows, true);
    if off == 0.0 {
        return (rows, false);
    }
    let better = |rows: &[Row]| {
        let (a, o) = area(rows, true);
        a <= limit && o <= 0.5 * off
    };
    let other = projected();
    if better(&other) {
        return (other, true);
    }
    let other = raw();
    if better(&other) {
        (other, true)
    } else {
        (rows, false)
    }
}

/// Builds the samples of quad `q` from the edge data.
pub(super) fn build_patch<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    edges: &[Option<EdgeSamples>],
    q: usize,
    opt: &SampleOptions,
) -> Result<PatchSamples> {
    let [a, b, c, d] = net.quads[q];
    let qe = net.quad_edges[q];
    // Patch sides: (net edge, patch walks from -> to).
    let sides = [
        PatchSide {
            edge: qe[0],
            reversed: a > b,
        },
        PatchSide {
            edge: qe[1],
            reversed: b > c,
        },
        PatchSide {
            edge: qe[2],
            reversed: d > c,
        },
        PatchSide {
            edge: qe[3],
            reversed: a > d,
        },
    ];
    let get = |s: &PatchSide| -> Result<Side> {
        edges[s.edge as usize]
            .as_ref()
            .map(|e| side(e, s.reversed))
            .ok_or_else(|| Error::Numerical(format!("edge {} has no samples", s.edge)))
    };
    let (bot, right, top, left) = (
        get(&sides[0])?,
        get(&sides[1])?,
        get(&sides[2])?,
        get(&sides[3])?,
    );
    let (s, t) = (bot.p.len() - 1, left.p.len() - 1);
    if top.p.len() != s + 1 || right.p.len() != t + 1 {
        return Err(Error::Numerical(format!(
            "quad {q}: opposite sides have different sample counts"
        )));
    }
    let (pu, pv) = (uniform_params(s), uniform_params(t));
    let (ca, cb, cc, cd) = (bot.p[0], bot.p[s], top.p[s], top.p[0]);
    let tol = 1e-12 * opt.scale;
    let mut points = vec![vec![Point3::origin(); t + 1]; s + 1];
    for (i, col) in points.iter_mut().enumerate() {
        col[0] = bot.p[i];
        col[t] = top.p[i];
    }
    points[0].copy_from_slice(&left.p);
    points[s].copy_from_slice(&right.p);
    let mut normals = vec![vec![Vector3::zeros(); t + 1]; s + 1];
    for (i, col) in normals.iter_mut().enumerate() {
        col[0] = bot.n[i];
        col[t] = top.n[i];
    }
    normals[0].copy_from_slice(&left.n);
    normals[s].copy_from_slice(&right.n);
    // d/du at the ends of every row: the boundary edges' tangents at the corners, the row
    // curves' own tangents in between.
    let mut tan_u0 = vec![Vector3::zeros(); t + 1];
    let mut tan_u1 = vec![Vector3::zeros(); t + 1];
    (tan_u0[0], tan_u1[0], tan_u0[t], tan_u1[t]) = (bot.d[0], bot.d[s], top.d[0], top.d[s]);
    // Interior rows: the section curve from the row's left sample to its right one (the edge
    // machinery: lines, tracing), hinted by the Coons surface's normal at the row's middle.
    // Where even that fails: Coons points moved onto f = 0 along the Coons normal.
    let coons = Coons {
        bot: &bot,
        top: &top,
        left: &left,
        right: &right,
        corners: [ca, cb, cc, cd],
    };
    let rows: Vec<Row> = (1..t)
        .map(|j| {
            // The plane normal blends the bottom and top edges' (rows 0 and T would be those
            // edges exactly); where they disagree (a patch wrapping a rim along v), the Coons
            // normal at the row's middle makes up the missing length.
            let hint = coons.normal(s / 2, j, 0.5, pv[j]);
            let blend = bot.w * (1.0 - pv[j]) + top.w * pv[j];
            let w = blend + hint * (1.0 - blend.norm()).max(0.0);
            let fallback = || coons.row_fallback(f, j, &pu, pv[j], tol, opt.scale);
            match sample_section(f, left.p[j], right.p[j], w, s, tol) {
                Ok(row) if coons.row_near(&row.points, j, &pu, pv[j]) => {
                    let worst = row.residuals.iter().fold(0.0, |a: f64, &b| a.max(b));
                    let section = (
                        row.points,
                        row.normals,
                        row.tangents[0],
                        row.tangents[s],
                        0,
                        worst,
                    );
                    // In an open fit a section that strays from the data gives way to the
                    // Coons row projected onto f = 0 when that lies clearly nearer the data.
                    keep_near(opt.near, section, |r| &r.0, || Some(fallback()))
                }
                _ => fallback(),
            }
        })
        .collect();
    // In an open fit a patch whose sample grid covers far more area than the Coons patch of
    // its sides, partly off the data, has section rows running round something beside it (on
    // the cow seen from its side, rows round the far ear and horn, outside the data's rim) and
    // gives way to the Coons rows when those cover clearly less.
    let (rows, coons_rows) = match opt.near {
        Some(near) => unballoon(
            &coons,
            rows,
            &pu,
            &pv,
            |c| near.beyond(c),
            || {
                (1..t)
                    .map(|j| coons.row_fallback(f, j, &pu, pv[j], tol, opt.scale))
                    .collect()
            },
            || (1..t).map(|j| coons.row_raw(f, j, &pu, pv[j])).collect(),
        ),
        None => (rows, false),
    };
    let mut unprojected = 0;
    // Largest |f| / |grad f| of the samples, as the root finders left them: the four edges',
    // then the rows'.
    let mut max_residual = sides
        .iter()
        .filter_map(|sd| edges[sd.edge as usize].as_ref())
        .flat_map(|e| e.residuals.iter().copied())
        .fold(0.0, f64::max);
    for (j, (row, row_normals, d0, d1, missed, worst)) in (1..t).zip(rows) {
        max_residual = max_residual.max(worst);
        for i in 1..s {
            points[i][j] = row[i];
            normals[i][j] = row_normals[i];
        }
        tan_u0[j] = tangent_part(d0, &left.n[j]);
        tan_u1[j] = tangent_part(d1, &right.n[j]);
        unprojected += missed;
    }
    // d/dv on the rows v = 0 and v = 1: the side edges' tangents at the corners; in between,
    // the one-sided difference of each column, in the tangent plane.
    let dv = pv[1] - pv[0];
    let one_sided = |p: [Point3<f64>; 4]| {
        one_sided_derivative([p[0].coords, p[1].coords, p[2].coords, p[3].coords], t, dv)
    };
    let mut tan_v0 = Vec::with_capacity(s + 1);
    let mut tan_v1 = Vec::with_capacity(s + 1);
    for (i, col) in points.iter().enumerate() {
        let (v0, v1) = if i == 0 {
            (left.d[0], left.d[t])
        } else if i == s {
            (right.d[0], right.d[t])
        } else {
            let at = |k: usize| col[k.min(t)];
            let from_top = |k: usize| col[t - k.min(t)];
            (
                tangent_part(one_sided([at(0), at(1), at(2), at(3)]), &bot.n[i]),
                -tangent_part(
                    one_sided([from_top(0), from_top(1), from_top(2), from_top(3)]),
                    &top.n[i],
                ),
            )
        };
        tan_v0.push(v0);
        tan_v1.push(v1);
    }
    // A cross derivative reaching back across its side (a one-sided difference over the rim
    // of a part thinner than the sample spacing) is reflected into the patch.
    point_into_patch(&mut tan_v0, &bot.d, &bot.n, SideKind::V);
    point_into_patch(&mut tan_v1, &top.d, &top.n, SideKind::V);
    point_into_patch(&mut tan_u0, &left.d, &left.n, SideKind::U);
    point_into_patch(&mut tan_u1, &right.d, &right.n, SideKind::U);
    let mut p = PatchSamples {
        quad: q,
        corners: [a, b, c, d],
        sides,
        points,
        normals,
        params_u: pu,
        params_v: pv,
        tan_u0,
        tan_u1,
        tan_v0,
        tan_v1,
        deviation_u: 0.0,
        deviation_v: 0.0,
        deviation_cell: 0.0,
        unprojected,
        max_residual,
        coons_rows,
        measured: false,
    };
    if opt.measure {
        measure(f, &mut p);
    }
    Ok(p)
}

/// Measures a patch's samples: the deviation from f = 0 of its row splines (u) and column
/// splines (v) at their interval midpoints, and the estimate at the cell centres.
pub(super) fn measure<I: Implicit + ?Sized>(f: &I, p: &mut PatchSamples) {
    let (s, t) = (p.s(), p.t());
    let (points, pu, pv) = (&p.points, &p.params_u, &p.params_v);
    let (tan_u0, tan_u1, tan_v0, tan_v1) = (&p.tan_u0, &p.tan_u1, &p.tan_v0, &p.tan_v1);
    // Tolerance estimate along rows (u), columns (v) and at cell centres.
    let dist = |p: &Vector3<f64>| {
        let (val, g) = f.value_and_gradient(&Point3::from(*p));
        residual(val, &g)
    };
    let max_dist = |v: &[Vector3<f64>]| v.iter().map(dist).fold(0.0, f64::max);
    let row_mids: Vec<Vec<Vector3<f64>>> = (0..=t)
        .map(|j| {
            let row: Vec<Vector3<f64>> = (0..=s).map(|i| points[i][j].coords).collect();
            spline_midpoints(&row, pu, &tan_u0[j], &tan_u1[j])
        })
        .collect();
    let deviation_u = row_mids.iter().map(|r| max_dist(r)).fold(0.0, f64::max);
    let deviation_v = (0..=s)
        .map(|i| {
            let col: Vec<Vector3<f64>> = points[i].iter().map(|p| p.coords).collect();
            max_dist(&spline_midpoints(&col, pv, &tan_v0[i], &tan_v1[i]))
        })
        .fold(0.0, f64::max);
    // Cell centres: the v-spline through the row midpoints of each column of cells, with end
    // derivatives interpolated along u from tan_v0 / tan_v1 (end slopes of that interpolation,
    // the twists, from one-sided differences of order up to three). The tensor-product patch's value there depends
    // on how the interpolation treats twists, so this is an estimate.
    let du = pu[1] - pu[0];
    let twist = |d: &[Vector3<f64>], from_end: bool| {
        let at = |k: usize| {
            if from_end {
                d[s - k.min(s)]
            } else {
                d[k.min(s)]
            }
        };
        let sign = if from_end { -1.0 } else { 1.0 };
        sign * one_sided_derivative([at(0), at(1), at(2), at(3)], s, du)
    };
    let v0_mid = spline_midpoints(tan_v0, pu, &twist(tan_v0, false), &twist(tan_v0, true));
    let v1_mid = spline_midpoints(tan_v1, pu, &twist(tan_v1, false), &twist(tan_v1, true));
    let deviation_cell = (0..s)
        .map(|i| {
            let col: Vec<Vector3<f64>> = row_mids.iter().map(|r| r[i]).collect();
            max_dist(&spline_midpoints(&col, pv, &v0_mid[i], &v1_mid[i]))
        })
        .fold(0.0, f64::max);
    p.deviation_u = deviation_u;
    p.deviation_v = deviation_v;
    p.deviation_cell = deviation_cell;
    p.measured = true;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A side of the unit square in the plane z = 0 from `a` to `b`, at `n + 1` samples.
    fn flat_side(a: Point3<f64>, b: Point3<f64>, n: usize) -> Side {
        Side {
            p: (0..=n)
                .map(|k| a + (b - a) * (k as f64 / n as f64))
                .collect(),
            d: vec![b - a; n + 1],
            n: vec![Vector3::z(); n + 1],
            w: Vector3::z(),
        }
    }

    /// Interior rows of the unit square at height `z(i, j)`.
    fn rows(n: usize, z: impl Fn(usize, usize) -> f64) -> Vec<Row> {
        (1..n)
            .map(|j| {
                let v = j as f64 / n as f64;
                // The ends are the sides' samples, on the plane.
                let p = (0..=n)
                    .map(|i| {
                        let z = if i == 0 || i == n { 0.0 } else { z(i, j) };
                        Point3::new(i as f64 / n as f64, v, z)
                    })
                    .collect();
                (
                    p,
                    vec![Vector3::z(); n + 1],
                    Vector3::x(),
                    Vector3::x(),
                    0,
                    0.0,
                )
            })
            .collect()
    }

    #[test]
    fn rows_ballooning_off_the_data_give_way_to_the_first_coons_rows_that_do_not() {
        let n = 4;
        let o = Point3::origin();
        let (x, y, xy) = (
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
        );
        let (bot, top, left, right) = (
            flat_side(o, x, n),
            flat_side(y, xy, n),
            flat_side(o, y, n),
            flat_side(x, xy, n),
        );
        let coons = Coons {
            bot: &bot,
            top: &top,
            left: &left,
            right: &right,
            corners: [o, x, xy, y],
        };
        let pu = uniform_params(n);
        // The implicit the raw rows are reported against: the plane z = 0.25.
        let plane = crate::polygonize::test_shapes::Sphere {
            c: Point3::new(0.5, 0.5, -1e6),
            r: 1e6 + 0.25,
        };
        // The data lie on the square: a cell centre more than 0.5 off the plane is away.
        let run = |rows: Vec<Row>, projected: &dyn Fn() -> Vec<Row>, raw: &dyn Fn() -> Vec<Row>| {
            unballoon(&coons, rows, &pu, &pu, |c| c.z.abs() > 0.5, projected, raw)
        };
        // A gentle bump (area 1.2 times the square's): kept, no alternative made.
        let bump = |i: usize, j: usize| if (i, j) == (2, 2) { 0.3 } else { 0.0 };
        let (kept, replaced) = run(rows(n, bump), &|| panic!("not needed"), &|| {
            panic!("not needed")
        });
        assert!(!replaced);
        assert_eq!(kept[1].0[2].z, 0.3);
        // Rows zigzagging 2 up and down cover many times the area, but every cell's centre
        // stays on the data (a patch wrapping a thin part of it): kept.
        let zigzag = |i: usize, j: usize| if (i + j).is_multiple_of(2) { 2.0 } else { -2.0 };
        let (kept, replaced) = run(rows(n, zigzag), &|| panic!("not needed"), &|| {
            panic!("not needed")
        });
        assert!(!replaced);
        assert_eq!(kept[0].0[1].z, zigzag(1, 1));
        // Rows lifted 2 off the data (a box over the square): the projected Coons rows
        // replace them when they lie on the data ...
        let lifted = |_: usize, _: usize| 2.0;
        let (flat, replaced) = run(rows(n, lifted), &|| rows(n, |_, _| 0.01), &|| {
            panic!("not needed")
        });
        assert!(replaced);
        assert_eq!(flat[0].0[1].z, 0.01);
        // ... the raw Coons rows when the projected ones are as far off ...
        let (raw, replaced) = run(rows(n, lifted), &|| rows(n, |_, _| 1.5), &|| {
            (1..n)
                .map(|j| coons.row_raw(&plane, j, &pu, pu[j]))
                .collect()
        });
        assert!(replaced);
        assert!(raw.iter().all(|r| r.0.iter().all(|p| p.z == 0.0)));
        assert_eq!(raw[0].4, n - 1, "interior samples left off f = 0");
        assert!((raw[0].5 - 0.25).abs() < 1e-6, "how far off, {}", raw[0].5);
        // ... and nothing changes when no alternative is clearly better.
        let (same, replaced) = run(rows(n, lifted), &|| rows(n, lifted), &|| {
            rows(n, |_, _| 1.8)
        });
        assert!(!replaced);
        assert_eq!(same[0].0[1].z, 2.0);
    }
}
