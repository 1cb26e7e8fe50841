//! The 3D skeleton (seed 001 section 4.4): per skeleton vertex the unknowns X_i = (z_i, xN_i,
//! yN_i) (depth and the slopes dz/dx, dz/dy of the local quadratic surface), found by
//! min ||U_Total X|| s.t. M_C1 X = 0, M_Coll X >= d_z (eq. 1).
//!
//! * C1 continuity (eq. 4-5): on edge j = (i, k) the quadratic
//!   S_j(x, y) = a x^2 + b x + c y^2 + d y + e xy + f must interpolate both end values and
//!   slopes; the 6x6 system of eq. 4 has rank 5, its compatibility condition is the row of
//!   eq. 5. Written symmetrically (restricting S_j to the edge gives a 1D quadratic, for which
//!   g(1) - g(0) = (g'(0) + g'(1)) / 2):
//!   z_k - z_i = ((xN_i + xN_k) dx + (yN_i + yN_k) dy) / 2, which is eq. 5 multiplied by
//!   (y_i - y_k) / 2 and has no division by y_i - y_k.
//! * Bending (eq. 6-10): thin-plate energy with D = 2, nu = 1/2,
//!   E_j = l_j^2 (4a^2 + 4c^2 + e^2 + 4ac) = l_j^2 ||U' C_j||^2; C_j = M_{X->C} X_{i,k} is the
//!   least-bending quadratic through the end data (eq. 7-9), computed here as
//!   C = (I - N (U'N)^T U' / |U'N|^2) M^+ X with N the null vector of M (same minimiser as the
//!   paper's block elimination, no 5x5 pivot choice). Coordinates are taken relative to the
//!   edge midpoint (a, c, e do not depend on the origin).
//! * Orientation (eq. 11): xN_i^2 + yN_i^2. Distance to the sketch plane (eq. 12): z_i^2.
//! * No collision (eq. 2-3): where a front part's vertex i and a back part's vertex k are
//!   closer in the plane than l < r_i + r_k + d_MinSurf,
//!   z_i - z_k >= sqrt((r_i + r_k + d_MinSurf)^2 - l^2). The viewer is at +z: front means
//!   larger z.

use super::chordal_axis::Skeleton2;
use super::lsi::lsei;
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, Matrix6, RowVector6, SMatrix};

/// Energy weights (w_Curv, w_Orient, w_Dist of seed 001 after eq. 12).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Weights {
    pub curvature: f64,
    pub orientation: f64,
    pub distance: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            curvature: 1.0,
            orientation: 0.3,
            distance: 0.3,
        }
    }
}

impl Weights {
    /// All positive and finite, largest / smallest at most 1e3 (the least-squares system is
    /// badly conditioned beyond).
    pub fn check(&self) -> Result<()> {
        let w = [self.curvature, self.orientation, self.distance];
        if w.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(Error::InvalidOption(format!(
                "weights must be positive numbers, got {},{},{}",
                w[0], w[1], w[2]
            )));
        }
        let (lo, hi) = w
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), x| (a.min(*x), b.max(*x)));
        if hi / lo > 1e3 {
            return Err(Error::InvalidOption(format!(
                "weights {},{},{}: largest / smallest is {:.3e}, keep it under 1e3",
                w[0],
                w[1],
                w[2],
                hi / lo
            )));
        }
        Ok(())
    }
}

/// The solved skeleton: per vertex (z, xN, yN), with part membership.
#[derive(Debug, Clone)]
pub struct Skeleton3 {
    pub z: Vec<f64>,
    pub slope: Vec<[f64; 2]>,
    /// Inequality constraints used (eq. 3 rows) and how many are active at the solution.
    pub constraints: usize,
    pub active: usize,
}

/// Curvature rows l U' M_{X->C} (3x6) of an edge from (x0, y0) to (x1, y1).
fn bending_rows(p0: [f64; 2], p1: [f64; 2]) -> Option<SMatrix<f64, 3, 6>> {
    let m = [(p0[0] + p1[0]) / 2.0, (p0[1] + p1[1]) / 2.0];
    let (x0, y0, x1, y1) = (p0[0] - m[0], p0[1] - m[1], p1[0] - m[0], p1[1] - m[1]);
    let l = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
    if l < 1e-12 {
        return None;
    }
    // Eq. 4 with C = (a, b, c, d, e, f), X = (z_i, xN_i, yN_i, z_k, xN_k, yN_k).
    let rows = [
        RowVector6::new(x0 * x0, x0, y0 * y0, y0, x0 * y0, 1.0),
        RowVector6::new(2.0 * x0, 1.0, 0.0, 0.0, y0, 0.0),
        RowVector6::new(0.0, 0.0, 2.0 * y0, 1.0, x0, 0.0),
        RowVector6::new(x1 * x1, x1, y1 * y1, y1, x1 * y1, 1.0),
        RowVector6::new(2.0 * x1, 1.0, 0.0, 0.0, y1, 0.0),
        RowVector6::new(0.0, 0.0, 2.0 * y1, 1.0, x1, 0.0),
    ];
    let mm = Matrix6::from_rows(&rows);
    let svd = mm.svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let s = svd.singular_values;
    let smax = s.max();
    let mut pinv = Matrix6::zeros();
    let mut null = nalgebra::Vector6::zeros();
    let mut smin = f64::MAX;
    for k in 0..6 {
        if s[k] > 1e-9 * smax {
            pinv += vt.row(k).transpose() * u.column(k).transpose() / s[k];
        }
        if s[k] < smin {
            smin = s[k];
            null = vt.row(k).transpose();
        }
    }
    let up = SMatrix::<f64, 3, 6>::from_row_slice(&[
        2.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        3f64.sqrt(),
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
    ]);
    let un = up * null;
    let nn = un.norm_squared();
    let k = if nn > 1e-300 {
        (Matrix6::identity() - null * (un.transpose() * up) / nn) * pinv
    } else {
        pinv
    };
    Some(up * k * l)
}

/// Solves for the 3D skeleton of all parts. `nodes` are the parts' skeletons (coordinates in
/// the drawing's normalised units), `overlaps` the (front, back) part pairs, `d_min` the
/// smallest gap between surfaces.
pub fn solve(
    parts: &[Skeleton2],
    overlaps: &[(usize, usize)],
    weights: &Weights,
    d_min: f64,
) -> Result<Skeleton3> {
    weights.check()?;
    let offset: Vec<usize> = parts
        .iter()
        .scan(0, |acc, p| {
            let o = *acc;
            *acc += p.nodes.len();
            Some(o)
        })
        .collect();
    let m: usize = parts.iter().map(|p| p.nodes.len()).sum();
    let n = 3 * m;
    let nedges: usize = parts.iter().map(|p| p.edges.len()).sum();
    let mut e = DMatrix::zeros(nedges, n);
    let mut a = DMatrix::zeros(3 * nedges + 3 * m, n);
    let mut row = 0;
    let mut erow = 0;
    for (pi, p) in parts.iter().enumerate() {
        for &[i, k] in &p.edges {
            let (gi, gk) = (offset[pi] + i, offset[pi] + k);
            let (pa, pb) = (p.nodes[i], p.nodes[k]);
            let (dx, dy) = (pb.x - pa.x, pb.y - pa.y);
            // Eq. 5 (symmetric form).
            e[(erow, 3 * gk)] = 1.0;
            e[(erow, 3 * gi)] = -1.0;
            e[(erow, 3 * gi + 1)] = -dx / 2.0;
            e[(erow, 3 * gk + 1)] = -dx / 2.0;
            e[(erow, 3 * gi + 2)] = -dy / 2.0;
            e[(erow, 3 * gk + 2)] = -dy / 2.0;
            erow += 1;
            // Eq. 10.
            if let Some(b) = bending_rows([pa.x, pa.y], [pb.x, pb.y]) {
                for r in 0..3 {
                    for c in 0..3 {
                        a[(row + r, 3 * gi + c)] = weights.curvature * b[(r, c)];
                        a[(row + r, 3 * gk + c)] = weights.curvature * b[(r, c + 3)];
                    }
                }
            }
            row += 3;
        }
    }
    for v in 0..m {
        // Eq. 11-12.
        a[(row, 3 * v + 1)] = weights.orientation;
        a[(row + 1, 3 * v + 2)] = weights.orientation;
        a[(row + 2, 3 * v)] = weights.distance;
        row += 3;
    }
    // Eq. 2-3.
    let mut g_rows: Vec<(usize, usize, f64)> = Vec::new();
    for &(f, b) in overlaps {
        let (pf, pb) = (&parts[f], &parts[b]);
        for i in 0..pf.nodes.len() {
            for k in 0..pb.nodes.len() {
                let l = (pf.nodes[i] - pb.nodes[k]).norm();
                let d = pf.radius[i] + pb.radius[k] + d_min;
                if l < d {
                    g_rows.push((offset[f] + i, offset[b] + k, (d * d - l * l).sqrt()));
                }
            }
        }
    }
    let mut g = DMatrix::zeros(g_rows.len(), n);
    let mut h = DVector::zeros(g_rows.len());
    for (r, &(i, k, dz)) in g_rows.iter().enumerate() {
        g[(r, 3 * i)] = 1.0;
        g[(r, 3 * k)] = -1.0;
        h[r] = dz;
    }
    let b = DVector::zeros(a.nrows());
    let x = lsei(&a, &b, &e, &g, &h)?;
    let gx = &g * &x;
    let active = (0..g_rows.len())
        .filter(|&r| gx[r] - h[r] < 1e-6 * h[r].abs().max(1e-9))
        .count();
    if (0..g_rows.len()).any(|r| gx[r] < h[r] - 1e-6 * h[r].abs().max(1e-9)) {
        return Err(Error::Numerical(
            "the skeleton solution violates a depth constraint".into(),
        ));
    }
    Ok(Skeleton3 {
        z: (0..m).map(|v| x[3 * v]).collect(),
        slope: (0..m).map(|v| [x[3 * v + 1], x[3 * v + 2]]).collect(),
        constraints: g_rows.len(),
        active,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    fn chain(y: f64, x0: f64, x1: f64, n: usize, r: f64) -> Skeleton2 {
        Skeleton2 {
            nodes: (0..n)
                .map(|i| Point2::new(x0 + (x1 - x0) * i as f64 / (n - 1) as f64, y))
                .collect(),
            radius: vec![r; n],
            edges: (0..n - 1).map(|i| [i, i + 1]).collect(),
        }
    }

    #[test]
    fn bending_of_a_quadratic_surface_is_its_thin_plate_energy() {
        // End data of S = x^2 + y^2 on the x axis: z = 0.25, slopes (2x, 2y). The quadratics
        // through them are S + alpha y^2 (a = 1, c = 1 + alpha, e = 0); 4a^2 + 4c^2 + 4ac is
        // least at c = -1/2: 4 + 1 - 2 = 3 (l = 1).
        let b = bending_rows([-0.5, 0.0], [0.5, 0.0]).unwrap();
        let x = nalgebra::Vector6::new(0.25, -1.0, 0.0, 0.25, 1.0, 0.0);
        let en = (b * x).norm_squared();
        assert!((en - 3.0).abs() < 1e-9, "{en}");
        // A plane costs nothing.
        let x = nalgebra::Vector6::new(0.1, 0.3, 0.2, 0.4, 0.3, 0.2);
        assert!((b * x).norm() < 1e-9);
    }

    #[test]
    fn lone_part_stays_flat_and_crossing_parts_separate_in_order() {
        let a = chain(0.0, -1.0, 1.0, 11, 0.2);
        let s = solve(std::slice::from_ref(&a), &[], &Weights::default(), 0.02).unwrap();
        assert!(s.z.iter().all(|z| z.abs() < 1e-9));
        // A vertical bar crossing a horizontal one, the vertical in front.
        let mut b = chain(0.0, -1.0, 1.0, 11, 0.2);
        b.nodes.iter_mut().for_each(|p| *p = Point2::new(p.y, p.x));
        let s = solve(&[a, b], &[(1, 0)], &Weights::default(), 0.02).unwrap();
        assert!(s.constraints > 0 && s.active > 0);
        // Centres: index 5 of each.
        let gap = s.z[11 + 5] - s.z[5];
        assert!(gap >= 0.42 - 1e-6, "{gap}");
        // Ends relax towards the plane.
        assert!(s.z[0].abs() < s.z[5].abs() + 1e-9);
    }

    #[test]
    fn weight_ratio_is_checked() {
        let w = Weights {
            curvature: 1.0,
            orientation: 1e-4,
            distance: 1.0,
        };
        assert!(w.check().is_err());
    }
}
