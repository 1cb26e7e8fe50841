//! Restriction of a clamped B-spline surface to a parameter sub-rectangle, by knot insertion.
//!
//! A STEP face bounded by iso-curves u = u_a, u = u_b, v = v_a, v = v_b of its surface (a
//! trimmed region of a larger surface, e.g. the extended surfaces of
//! [`super::extend`]) is the untrimmed surface of the restriction. Inserting each cut value
//! until its multiplicity is the degree p (Boehm's algorithm, Piegl & Tiller A5.1: inserting
//! t in [t_k, t_{k+1}) replaces P_{k-p+1} .. P_k by
//! Q_i = alpha_i P_i + (1 - alpha_i) P_{i-1}, alpha_i = (t - t_i) / (t_{i+p} - t_i)) does not
//! change the surface; then the control points and knots between the cuts, with one more copy
//! of each cut value to clamp the ends, are a surface equal to the original on the
//! rectangle.

use super::surface::BSplineSurface;
use crate::{Error, Result};
use nalgebra::Point3;

/// Inserts `t` once into the clamped curve (`knots`, `ctrl`) of degree `p`.
fn insert_once(knots: &mut Vec<f64>, ctrl: &mut Vec<Point3<f64>>, p: usize, t: f64) {
    let n = ctrl.len();
    // Span k with knots[k] <= t < knots[k + 1], inside the domain.
    let k = (p..n)
        .rev()
        .find(|&k| knots[k] <= t)
        .unwrap_or(p)
        .min(n - 1);
    let mut q = Vec::with_capacity(n + 1);
    q.extend_from_slice(&ctrl[..=k - p]);
    for i in k - p + 1..=k {
        let denom = knots[i + p] - knots[i];
        let alpha = if denom > 0.0 {
            (t - knots[i]) / denom
        } else {
            0.0
        };
        q.push(ctrl[i] + (ctrl[i - 1] - ctrl[i]) * (1.0 - alpha));
    }
    q.extend_from_slice(&ctrl[k..]);
    knots.insert(k + 1, t);
    *ctrl = q;
}

/// The sub-range [a, b] of one clamped control polygon with its knots.
fn restrict_polygon(
    knots: &[f64],
    ctrl: &[Point3<f64>],
    p: usize,
    a: f64,
    b: f64,
) -> (Vec<f64>, Vec<Point3<f64>>) {
    let mut k = knots.to_vec();
    let mut c = ctrl.to_vec();
    let (lo, hi) = (knots[p], knots[ctrl.len()]);
    for t in [a, b] {
        if t > lo && t < hi {
            let have = k.iter().filter(|&&x| x == t).count();
            for _ in have..p {
                insert_once(&mut k, &mut c, p, t);
            }
        }
    }
    // Control points whose basis functions are non-zero somewhere on [a, b]: with p copies of
    // a ending at index ia (k[ia] = a, k[ia + 1] > a) the first is ia - p; likewise for b.
    let ia = k
        .iter()
        .rposition(|&x| x <= a)
        .unwrap_or(p)
        .min(c.len() - 1);
    let ib = k.iter().position(|&x| x >= b).unwrap_or(c.len());
    let first = ia + 1 - p - 1;
    let last = ib - 1;
    let ctrl: Vec<Point3<f64>> = c[first..=last].to_vec();
    let mut knots = vec![a; p + 1];
    knots.extend(k[ia + 1..ib].iter().copied());
    knots.extend(std::iter::repeat_n(b, p + 1));
    (knots, ctrl)
}

impl BSplineSurface {
    /// The surface on [u.0, u.1] x [v.0, v.1] (inside the domain, non-empty) as a clamped
    /// surface of its own, equal to this one there (module documentation). Errors for a
    /// rectangle outside the domain or an empty one.
    pub fn restricted(&self, u: (f64, f64), v: (f64, f64)) -> Result<BSplineSurface> {
        let (du, dv) = (self.domain_u(), self.domain_v());
        let inside = |(a, b): (f64, f64), (lo, hi): (f64, f64)| a >= lo && b <= hi && a < b;
        if !inside(u, du) || !inside(v, dv) {
            return Err(Error::Degenerate(format!(
                "sub-rectangle {u:?} x {v:?} is not a non-empty part of the domain {du:?} x {dv:?}"
            )));
        }
        if u == du && v == dv {
            return Ok(self.clone());
        }
        let (p, q) = (self.degree_u, self.degree_v);
        // Along v, row by row.
        let mut knots_v = self.knots_v.clone();
        let rows: Vec<Vec<Point3<f64>>> = self
            .ctrl
            .iter()
            .map(|row| {
                let (k, c) = restrict_polygon(&self.knots_v, row, q, v.0, v.1);
                knots_v = k;
                c
            })
            .collect();
        // Along u, column by column.
        let nv = rows.first().map_or(0, Vec::len);
        let mut knots_u = self.knots_u.clone();
        let cols: Vec<Vec<Point3<f64>>> = (0..nv)
            .map(|j| {
                let col: Vec<Point3<f64>> = rows.iter().map(|r| r[j]).collect();
                let (k, c) = restrict_polygon(&self.knots_u, &col, p, u.0, u.1);
                knots_u = k;
                c
            })
            .collect();
        let nu = cols.first().map_or(0, Vec::len);
        let ctrl = (0..nu)
            .map(|i| cols.iter().map(|c| c[i]).collect())
            .collect();
        BSplineSurface::new(p, q, knots_u, knots_v, ctrl)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nurbs::extend::tests::wavy;

    fn same_on(a: &BSplineSurface, b: &BSplineSurface, u: (f64, f64), v: (f64, f64)) -> f64 {
        let mut worst: f64 = 0.0;
        for i in 0..=12 {
            for j in 0..=12 {
                let uu = u.0 + (u.1 - u.0) * i as f64 / 12.0;
                let vv = v.0 + (v.1 - v.0) * j as f64 / 12.0;
                worst = worst.max((a.evaluate(uu, vv) - b.evaluate(uu, vv)).norm());
            }
        }
        worst
    }

    #[test]
    fn restriction_matches_the_surface_on_any_rectangle() {
        let s = wavy();
        for (u, v) in [
            ((0.1, 0.9), (2.2, 2.7)),
            ((0.3, 0.6), (2.0, 3.0)),
            ((0.0, 0.45), (2.5, 3.0)),
            ((0.31, 0.32), (2.61, 2.99)),
        ] {
            let r = s.restricted(u, v).unwrap();
            assert_eq!(r.domain_u(), u);
            assert_eq!(r.domain_v(), v);
            assert!(same_on(&s, &r, u, v) < 1e-12, "{u:?} {v:?}");
        }
        assert_eq!(s.restricted((0.0, 1.0), (2.0, 3.0)).unwrap(), s);
        assert!(s.restricted((0.5, 0.5), (2.0, 3.0)).is_err());
        assert!(s.restricted((-0.1, 0.5), (2.0, 3.0)).is_err());
    }

    #[test]
    fn restricting_an_extension_gives_the_original_back() {
        let s = wavy();
        let x = s.extended(0.7, 1.5);
        let r = x.restricted((0.0, 1.0), (2.0, 3.0)).unwrap();
        assert_eq!(r.knots_u, s.knots_u);
        assert_eq!(r.knots_v, s.knots_v);
        for (ra, sa) in r.ctrl.iter().zip(&s.ctrl) {
            for (a, b) in ra.iter().zip(sa) {
                assert!((a - b).norm() < 1e-14);
            }
        }
    }
}
