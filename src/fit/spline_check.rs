//! The complete (clamped) cubic spline through a row of samples, evaluated at the interval
//! midpoints: the tolerance test of the patch sampler.
//!
//! Seed 004 eq. 9-11 interpolate each row of S + 1 points Q_k at parameters t_k with a cubic
//! B-spline whose knots are the parameters (S + 3 control points) and whose end derivatives are
//! given. That spline is the unique C2 piecewise cubic through the points with those end
//! derivatives (the "complete" cubic spline), and the iso-curves of the final tensor-product
//! patch through sample rows are exactly these row splines. So the distance of their midpoints
//! from f = 0 measures the patch's deviation along every sample row and column.
//!
//! In Hermite form with slopes m_k and spacings d_k = t_{k+1} - t_k, C2 continuity gives the
//! tridiagonal system (de Boor, "A Practical Guide to Splines", ch. IV)
//!
//!   d_k m_{k-1} + 2 (d_{k-1} + d_k) m_k + d_{k-1} m_{k+1}
//!       = 3 (d_k (Q_k - Q_{k-1}) / d_{k-1} + d_{k-1} (Q_{k+1} - Q_k) / d_k),  k = 1..S-1,
//!
//! with m_0, m_S the given end derivatives; the midpoint of interval k is
//! (Q_k + Q_{k+1}) / 2 + d_k (m_k - m_{k+1}) / 8. Hand-written (a 3-vector Thomas solve) because
//! it runs for every row of every patch and needs no allocation beyond the slopes.

use nalgebra::Vector3;

/// Slopes m_0..m_S of the complete cubic spline through `q` at `t` with end derivatives `d0`,
/// `d1`. `q` and `t` have the same length (at least 2), `t` strictly increasing. Points are
/// passed as vectors (position vectors, or tangent vectors when a row of derivatives is
/// interpolated).
pub fn spline_slopes(
    q: &[Vector3<f64>],
    t: &[f64],
    d0: &Vector3<f64>,
    d1: &Vector3<f64>,
) -> Vec<Vector3<f64>> {
    let s = q.len() - 1;
    let mut m = vec![Vector3::zeros(); s + 1];
    m[0] = *d0;
    m[s] = *d1;
    if s < 2 {
        return m;
    }
    let d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    // Thomas algorithm on the unknowns m_1..m_{S-1}.
    let n = s - 1;
    let mut cp = vec![0.0; n];
    let mut rp = vec![Vector3::zeros(); n];
    for i in 0..n {
        let k = i + 1;
        let a = d[k];
        let b = 2.0 * (d[k - 1] + d[k]);
        let c = d[k - 1];
        let mut r =
            ((q[k] - q[k - 1]) * (d[k] / d[k - 1]) + (q[k + 1] - q[k]) * (d[k - 1] / d[k])) * 3.0;
        if k == 1 {
            r -= m[0] * a;
        }
        if k == s - 1 {
            r -= m[s] * c;
        }
        let (a, c) = (
            if k == 1 { 0.0 } else { a },
            if k == s - 1 { 0.0 } else { c },
        );
        let denom = if i == 0 { b } else { b - a * cp[i - 1] };
        cp[i] = c / denom;
        rp[i] = if i == 0 {
            r / denom
        } else {
            (r - rp[i - 1] * a) / denom
        };
    }
    for i in (0..n).rev() {
        m[i + 1] = if i + 1 == n {
            rp[i]
        } else {
            rp[i] - m[i + 2] * cp[i]
        };
    }
    m
}

/// Midpoints (in parameter) of the S intervals of the complete cubic spline (see
/// [`spline_slopes`]).
pub fn spline_midpoints(
    q: &[Vector3<f64>],
    t: &[f64],
    d0: &Vector3<f64>,
    d1: &Vector3<f64>,
) -> Vec<Vector3<f64>> {
    let m = spline_slopes(q, t, d0, d1);
    (0..q.len() - 1)
        .map(|k| {
            let dk = t[k + 1] - t[k];
            (q[k] + q[k + 1]) * 0.5 + (m[k] - m[k + 1]) * (dk / 8.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic polynomial curve is reproduced exactly, on uneven parameters too.
    #[test]
    fn reproduces_cubics() {
        let c = |t: f64| Vector3::new(t * t * t - 2.0 * t, 0.5 * t * t + 1.0, 3.0 * t - t * t * t);
        let dc = |t: f64| Vector3::new(3.0 * t * t - 2.0, t, 3.0 - 3.0 * t * t);
        for t in [
            vec![0.0, 1.0],
            vec![0.0, 0.5, 1.0],
            vec![0.0, 0.1, 0.35, 0.4, 0.8, 1.0],
            (0..=9).map(|k| k as f64 / 9.0).collect(),
        ] {
            let q: Vec<_> = t.iter().map(|&x| c(x)).collect();
            let last = *t.last().unwrap();
            let m = spline_slopes(&q, &t, &dc(0.0), &dc(last));
            for (k, &x) in t.iter().enumerate() {
                assert!((m[k] - dc(x)).norm() < 1e-12, "{t:?} k {k}");
            }
            let mid = spline_midpoints(&q, &t, &dc(0.0), &dc(last));
            for k in 0..t.len() - 1 {
                assert!((mid[k] - c(0.5 * (t[k] + t[k + 1]))).norm() < 1e-12);
            }
        }
    }

    /// On a circle the midpoint error falls like (spacing)^4.
    #[test]
    fn circle_error_is_fourth_order() {
        let err = |s: usize| {
            let t: Vec<f64> = (0..=s).map(|k| k as f64 / s as f64).collect();
            let ang = std::f64::consts::FRAC_PI_2;
            let q: Vec<_> = t
                .iter()
                .map(|&x| Vector3::new((ang * x).cos(), (ang * x).sin(), 0.0))
                .collect();
            let d0 = Vector3::new(0.0, ang, 0.0);
            let d1 = Vector3::new(-ang, 0.0, 0.0);
            spline_midpoints(&q, &t, &d0, &d1)
                .iter()
                .map(|p| (p.norm() - 1.0).abs())
                .fold(0.0, f64::max)
        };
        let (e2, e4) = (err(2), err(4));
        let ratio = e2 / e4;
        assert!((10.0..24.0).contains(&ratio), "{e2} {e4} {ratio}");
    }
}
