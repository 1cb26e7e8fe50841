//! Interpolation parameters of one direction of a patch (the ū_k / v̄_k of seed 004 eq. 9 and
//! 12) and the cubic knot vector built from them.
//!
//! Seed 004 computes square-root chord parameters separately for every row,
//! `ū_k = ū_{k-1} + sqrt|Q_k - Q_{k-1}| / d` with `d = Σ sqrt|Q_k - Q_{k-1}|` (eq. 9). A
//! tensor-product surface has one knot vector per direction, and a watertight network needs the
//! boundary curve of an edge to depend on that edge's data only, so scansurf lets the caller pick
//! the parameters: [`Params::sqrt_chord`] computes the paper's values from one row of points
//! (typically a shared edge), [`Params::average_sqrt_chord`] averages them over several rows (the
//! usual tensor-product compromise), and [`Params::uniform`] gives equal spacing. The caller
//! passes the same vector (or its [`reversed`](Params::reversed) form) to every patch that meets
//! the edge.
//!
//! **Reversal symmetry.** Every value is rounded to a multiple of 2^-40. For such t in [0, 1],
//! `1 - t` is exact in binary floating point, so reversing a parameter vector twice gives back
//! the same bits. The curve interpolation relies on that to give bit-identical control points to
//! two patches that traverse a shared edge in opposite directions. The rounding moves a
//! parameter by at most 2^-41 ≈ 4.5e-13, far below anything that matters for the fit.

use crate::{Error, Result};
use nalgebra::Point3;

/// Grid on which parameters are snapped: multiples of 2^-40.
const SNAP: f64 = (1u64 << 40) as f64;

/// Rounds t in [0, 1] to a multiple of 2^-40 (exact for values already on that grid).
fn snap(t: f64) -> f64 {
    (t * SNAP).round() / SNAP
}

/// Strictly increasing parameters `0 = t_0 < t_1 < ... < t_n = 1`, each a multiple of 2^-40.
#[derive(Debug, Clone, PartialEq)]
pub struct Params(Vec<f64>);

impl Params {
    /// Parameters from caller values: they are normalised affinely to [0, 1] (first value 0, last
    /// 1), snapped to multiples of 2^-40, and must stay strictly increasing. At least two values.
    pub fn new(values: &[f64]) -> Result<Params> {
        if values.len() < 2 {
            return Err(Error::Degenerate(format!(
                "interpolation needs at least 2 parameters, got {}",
                values.len()
            )));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(Error::Degenerate("non-finite parameter".into()));
        }
        let (a, b) = (values[0], values[values.len() - 1]);
        if b <= a {
            return Err(Error::Degenerate(
                "parameters must increase from first to last".into(),
            ));
        }
        let n = values.len() - 1;
        let out: Vec<f64> = values
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                if k == 0 {
                    0.0
                } else if k == n {
                    1.0
                } else {
                    snap(((v - a) / (b - a)).clamp(0.0, 1.0))
                }
            })
            .collect();
        if out.windows(2).any(|w| w[1] <= w[0]) {
            return Err(Error::Degenerate(
                "interpolation parameters are not strictly increasing (coincident samples?)".into(),
            ));
        }
        Ok(Params(out))
    }

    /// `n + 1` equally spaced parameters k / n.
    pub fn uniform(n: usize) -> Result<Params> {
        if n == 0 {
            return Err(Error::Degenerate(
                "uniform parameters need at least one interval".into(),
            ));
        }
        let v: Vec<f64> = (0..=n).map(|k| k as f64 / n as f64).collect();
        Params::new(&v)
    }

    /// Square-root chord-length parameters of one row of points (seed 004 eq. 9):
    /// `t_k = t_{k-1} + sqrt|Q_k - Q_{k-1}| / d`, `d = Σ_k sqrt|Q_k - Q_{k-1}|`.
    /// Coincident consecutive points give an error (the parameters would not increase).
    pub fn sqrt_chord(points: &[Point3<f64>]) -> Result<Params> {
        Params::average_sqrt_chord(&[points])
    }

    /// The average over several rows of their square-root chord parameters: one parameter vector
    /// for a whole tensor-product direction (seed 004 uses per-row parameters in eq. 9 and 12,
    /// which a tensor-product surface cannot represent). Every row must have the same length.
    pub fn average_sqrt_chord(rows: &[&[Point3<f64>]]) -> Result<Params> {
        let Some(first) = rows.first() else {
            return Err(Error::Degenerate("no rows to parameterise".into()));
        };
        let n = first.len();
        if n < 2 {
            return Err(Error::Degenerate(format!(
                "a row of {n} points cannot be parameterised"
            )));
        }
        let mut acc = vec![0.0; n];
        for row in rows {
            if row.len() != n {
                return Err(Error::Degenerate(
                    "rows of different lengths cannot share parameters".into(),
                ));
            }
            let steps: Vec<f64> = row
                .windows(2)
                .map(|w| (w[1] - w[0]).norm().sqrt())
                .collect();
            let d: f64 = steps.iter().sum();
            if !(d.is_finite() && d > 0.0) {
                return Err(Error::Degenerate(
                    "row of coincident or non-finite points".into(),
                ));
            }
            let mut t = 0.0;
            for (k, s) in steps.iter().enumerate() {
                t += s / d;
                acc[k + 1] += t;
            }
        }
        let m = rows.len() as f64;
        let values: Vec<f64> = acc.iter().map(|a| a / m).collect();
        Params::new(&values)
    }

    /// The parameters of the same row traversed backwards: `1 - t_{n-k}` (exact, see the module
    /// documentation), so `p.reversed().reversed() == p` bit for bit.
    pub fn reversed(&self) -> Params {
        Params(self.0.iter().rev().map(|t| 1.0 - t).collect())
    }

    /// The values t_0..=t_n.
    pub fn as_slice(&self) -> &[f64] {
        &self.0
    }

    /// Number of values (samples), n + 1.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Always false (a parameter vector has at least two values); present for API symmetry.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The clamped cubic knot vector for interpolation with end tangents (seed 004, after
    /// eq. 14): `{0,0,0,0, t_1, ..., t_{n-1}, 1,1,1,1}`, n + 7 knots for n + 3 control points.
    pub fn cubic_knots(&self) -> Vec<f64> {
        let n = self.0.len() - 1;
        let mut k = Vec::with_capacity(n + 7);
        k.extend_from_slice(&[0.0; 4]);
        k.extend_from_slice(&self.0[1..n]);
        k.extend_from_slice(&[1.0; 4]);
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sqrt_chord_follows_eq_9() {
        let pts = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 4.0, 0.0),
            Point3::new(1.0, 4.0, 9.0),
        ];
        let p = Params::sqrt_chord(&pts).unwrap();
        // sqrt of chords 1, 4, 9 -> 1, 2, 3, d = 6.
        let want = [0.0, 1.0 / 6.0, 0.5, 1.0];
        for (a, b) in p.as_slice().iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        assert_eq!(p.cubic_knots().len(), 3 + 7);
    }

    #[test]
    fn reversal_is_an_exact_involution() {
        let pts: Vec<Point3<f64>> = (0..9)
            .map(|k| {
                let t = k as f64 * 0.37;
                Point3::new(t.cos() * 3.1, t.sin() * 1.7, t * t * 0.3)
            })
            .collect();
        let p = Params::sqrt_chord(&pts).unwrap();
        let r = p.reversed();
        assert_eq!(r.reversed(), p);
        assert_eq!(r.as_slice()[0], 0.0);
        assert_eq!(r.as_slice()[8], 1.0);
        // Reversing the points gives the reversed parameters up to the snapping grid.
        let mut back = pts.clone();
        back.reverse();
        let q = Params::sqrt_chord(&back).unwrap();
        for (a, b) in q.as_slice().iter().zip(r.as_slice()) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        let p = Point3::new(1.0, 2.0, 3.0);
        assert!(Params::sqrt_chord(&[p, p, Point3::new(2.0, 2.0, 3.0)]).is_err());
        assert!(Params::sqrt_chord(&[p]).is_err());
        assert!(Params::sqrt_chord(&[p, Point3::new(f64::NAN, 0.0, 0.0)]).is_err());
        assert!(Params::new(&[0.0, 0.5, 0.5, 1.0]).is_err());
        assert!(Params::new(&[1.0, 0.0]).is_err());
        assert!(Params::uniform(0).is_err());
        let a = [p, Point3::new(2.0, 2.0, 3.0)];
        let b = [p, Point3::new(2.0, 2.0, 3.0), Point3::new(3.0, 2.0, 3.0)];
        assert!(Params::average_sqrt_chord(&[&a, &b]).is_err());
    }

    #[test]
    fn new_normalises_to_unit_interval() {
        let p = Params::new(&[2.0, 3.0, 6.0]).unwrap();
        assert_eq!(p.as_slice(), &[0.0, 0.25, 1.0]);
        assert_eq!(Params::uniform(4).unwrap().as_slice()[2], 0.5);
    }
}
