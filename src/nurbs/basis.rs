//! B-spline basis functions by the Cox-de Boor recursion (seed 004 eq. 5-8; Piegl & Tiller,
//! "The NURBS Book", algorithms A2.1-A2.3).
//!
//! For a knot vector U = {u_0, ..., u_m} (eq. 7-8: clamped, the first and last values repeated
//! p+1 times) the degree-p basis functions are
//!
//! ```text
//! N_{i,0}(u) = 1 if u_i <= u < u_{i+1} else 0
//! N_{i,p}(u) = (u - u_i) / (u_{i+p} - u_i) N_{i,p-1}(u)
//!            + (u_{i+p+1} - u) / (u_{i+p+1} - u_{i+1}) N_{i+1,p-1}(u)      (eq. 5-6)
//! ```
//!
//! with 0/0 taken as 0. Only p+1 of them are non-zero at any u: N_{s-p..=s,p} where s is the knot
//! span with u_s <= u < u_{s+1} ([`find_span`]). The kernels here are allocation-free: they work
//! on fixed arrays of size [`MAX_DEGREE`]` + 1`, which is why they are written out rather than
//! taken from truck-geometry (whose evaluation allocates per call and has no span-local API).

/// The highest degree the kernels support. Curves and surfaces check it on construction.
pub const MAX_DEGREE: usize = 7;
const M: usize = MAX_DEGREE + 1;

/// Knot span index s with `knots[s] <= t < knots[s+1]`, clamped to the valid range
/// `degree ..= n` where `n = n_ctrl - 1` (so t = u_max falls in the last non-empty span).
/// Algorithm A2.1 (binary search). `t` outside the domain is clamped.
pub fn find_span(n_ctrl: usize, degree: usize, t: f64, knots: &[f64]) -> usize {
    let n = n_ctrl - 1;
    if t >= knots[n + 1] {
        return n;
    }
    if t <= knots[degree] {
        return degree;
    }
    let (mut low, mut high) = (degree, n + 1);
    let mut mid = (low + high) / 2;
    while t < knots[mid] || t >= knots[mid + 1] {
        if t < knots[mid] {
            high = mid;
        } else {
            low = mid;
        }
        mid = (low + high) / 2;
    }
    mid
}

/// The p+1 non-vanishing basis functions N_{span-p..=span, p}(t) (algorithm A2.2, the
/// triangular form of eq. 5). Returns them in `out[0..=p]`.
pub fn basis_funs(span: usize, t: f64, degree: usize, knots: &[f64]) -> [f64; M] {
    let mut n = [0.0; M];
    let mut left = [0.0; M];
    let mut right = [0.0; M];
    n[0] = 1.0;
    for j in 1..=degree {
        left[j] = t - knots[span + 1 - j];
        right[j] = knots[span + j] - t;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom != 0.0 { n[r] / denom } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

/// The non-vanishing basis functions and their derivatives up to order `n_ders` (at most
/// `degree`; higher derivatives of a degree-p polynomial vanish and are returned as 0):
/// `ders[k][r]` = d^k/dt^k N_{span-p+r, p}(t). Algorithm A2.3.
pub fn ders_basis_funs(
    span: usize,
    t: f64,
    degree: usize,
    n_ders: usize,
    knots: &[f64],
) -> [[f64; M]; M] {
    let p = degree;
    let mut ndu = [[0.0; M]; M];
    let mut left = [0.0; M];
    let mut right = [0.0; M];
    ndu[0][0] = 1.0;
    for j in 1..=p {
        left[j] = t - knots[span + 1 - j];
        right[j] = knots[span + j] - t;
        let mut saved = 0.0;
        for r in 0..j {
            // Lower triangle: knot differences; upper triangle: basis values.
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = if ndu[j][r] != 0.0 {
                ndu[r][j - 1] / ndu[j][r]
            } else {
                0.0
            };
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    let mut ders = [[0.0; M]; M];
    for j in 0..=p {
        ders[0][j] = ndu[j][p];
    }
    let nd = n_ders.min(p);
    let mut a = [[0.0; M]; 2];
    for r in 0..=p {
        let (mut s1, mut s2) = (0usize, 1usize);
        a[0][0] = 1.0;
        for k in 1..=nd {
            let mut d = 0.0;
            let rk = r as isize - k as isize;
            let pk = p - k;
            if r >= k {
                let den = ndu[pk + 1][rk as usize];
                a[s2][0] = if den != 0.0 { a[s1][0] / den } else { 0.0 };
                d = a[s2][0] * ndu[rk as usize][pk];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if r as isize - 1 <= pk as isize {
                k - 1
            } else {
                p - r
            };
            for j in j1..=j2 {
                let idx = (rk + j as isize) as usize;
                let den = ndu[pk + 1][idx];
                a[s2][j] = if den != 0.0 {
                    (a[s1][j] - a[s1][j - 1]) / den
                } else {
                    0.0
                };
                d += a[s2][j] * ndu[idx][pk];
            }
            if r <= pk {
                let den = ndu[pk + 1][r];
                a[s2][k] = if den != 0.0 { -a[s1][k - 1] / den } else { 0.0 };
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut factor = p as f64;
    for (k, row) in ders.iter_mut().enumerate().take(nd + 1).skip(1) {
        for d in row.iter_mut().take(p + 1) {
            *d *= factor;
        }
        factor *= (p - k) as f64;
    }
    ders
}

/// Checks a clamped knot vector for `n_ctrl` control points of degree `degree`: finite,
/// non-decreasing, `n_ctrl + degree + 1` values, end values repeated `degree + 1` times, interior
/// multiplicities at most `degree`, and a non-empty domain. Returns a message on failure.
pub fn check_clamped_knots(
    knots: &[f64],
    degree: usize,
    n_ctrl: usize,
) -> std::result::Result<(), String> {
    if degree == 0 || degree > MAX_DEGREE {
        return Err(format!("degree {degree} outside 1..={MAX_DEGREE}"));
    }
    if n_ctrl < degree + 1 {
        return Err(format!(
            "{n_ctrl} control points are too few for degree {degree}"
        ));
    }
    if knots.len() != n_ctrl + degree + 1 {
        return Err(format!(
            "{} knots for {n_ctrl} control points of degree {degree} (need {})",
            knots.len(),
            n_ctrl + degree + 1
        ));
    }
    if knots.iter().any(|k| !k.is_finite()) {
        return Err("non-finite knot".into());
    }
    if knots.windows(2).any(|w| w[1] < w[0]) {
        return Err("knots decrease".into());
    }
    let (a, b) = (knots[0], knots[knots.len() - 1]);
    if b <= a {
        return Err("empty knot domain".into());
    }
    if knots[..=degree].iter().any(|&k| k != a) || knots[n_ctrl..].iter().any(|&k| k != b) {
        return Err("knot vector is not clamped (end knots must repeat degree + 1 times)".into());
    }
    for (value, mult) in multiplicities(knots) {
        if value != a && value != b && mult > degree {
            return Err(format!(
                "interior knot {value} has multiplicity {mult} > degree"
            ));
        }
    }
    Ok(())
}

/// Distinct knot values with their multiplicities, in order (the form STEP and IGES readers
/// use: `(knots, multiplicities)`).
pub fn multiplicities(knots: &[f64]) -> Vec<(f64, usize)> {
    let mut out: Vec<(f64, usize)> = Vec::new();
    for &k in knots {
        match out.last_mut() {
            Some((v, m)) if *v == k => *m += 1,
            _ => out.push((k, 1)),
        }
    }
    out
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // index loops mirror the formulas being checked
mod tests {
    use super::*;

    const U: [f64; 11] = [0.0, 0.0, 0.0, 0.0, 0.2, 0.5, 0.7, 1.0, 1.0, 1.0, 1.0];

    /// Direct recursive Cox-de Boor (eq. 5) as an independent reference.
    fn n_rec(i: usize, p: usize, t: f64, u: &[f64]) -> f64 {
        if p == 0 {
            let last = u[u.len() - 1];
            // Right-closed last span so that t = u_max has value.
            return if (u[i] <= t && t < u[i + 1]) || (t == last && u[i] < t && u[i + 1] == last) {
                1.0
            } else {
                0.0
            };
        }
        let mut v = 0.0;
        if u[i + p] != u[i] {
            v += (t - u[i]) / (u[i + p] - u[i]) * n_rec(i, p - 1, t, u);
        }
        if u[i + p + 1] != u[i + 1] {
            v += (u[i + p + 1] - t) / (u[i + p + 1] - u[i + 1]) * n_rec(i + 1, p - 1, t, u);
        }
        v
    }

    #[test]
    fn span_search_matches_definition() {
        let n_ctrl = U.len() - 4;
        assert_eq!(find_span(n_ctrl, 3, 0.0, &U), 3);
        assert_eq!(find_span(n_ctrl, 3, 0.1, &U), 3);
        assert_eq!(find_span(n_ctrl, 3, 0.2, &U), 4);
        assert_eq!(find_span(n_ctrl, 3, 0.69, &U), 5);
        assert_eq!(find_span(n_ctrl, 3, 0.7, &U), 6);
        assert_eq!(find_span(n_ctrl, 3, 1.0, &U), 6);
        assert_eq!(find_span(n_ctrl, 3, 1.5, &U), 6);
        assert_eq!(find_span(n_ctrl, 3, -1.0, &U), 3);
    }

    #[test]
    fn basis_matches_recursion_and_partitions_unity() {
        let n_ctrl = U.len() - 4;
        for k in 0..=50 {
            let t = k as f64 / 50.0;
            let s = find_span(n_ctrl, 3, t, &U);
            let n = basis_funs(s, t, 3, &U);
            let sum: f64 = n[..4].iter().sum();
            assert!((sum - 1.0).abs() < 1e-14, "sum {sum} at {t}");
            for r in 0..4 {
                let i = s - 3 + r;
                let want = n_rec(i, 3, t, &U);
                assert!(
                    (n[r] - want).abs() < 1e-14,
                    "N_{i}({t}) = {} want {want}",
                    n[r]
                );
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let n_ctrl = U.len() - 4;
        let h = 1e-6;
        for &t in &[0.05, 0.3, 0.55, 0.9] {
            let s = find_span(n_ctrl, 3, t, &U);
            let d = ders_basis_funs(s, t, 3, 3, &U);
            let n = basis_funs(s, t, 3, &U);
            let np = basis_funs(s, t + h, 3, &U);
            let nm = basis_funs(s, t - h, 3, &U);
            for r in 0..4 {
                assert!((d[0][r] - n[r]).abs() < 1e-14);
                let fd1 = (np[r] - nm[r]) / (2.0 * h);
                let fd2 = (np[r] - 2.0 * n[r] + nm[r]) / (h * h);
                assert!((d[1][r] - fd1).abs() < 1e-6, "d1 {} vs {fd1}", d[1][r]);
                assert!((d[2][r] - fd2).abs() < 1e-3, "d2 {} vs {fd2}", d[2][r]);
            }
            // Derivatives of a partition of unity sum to zero.
            for k in 1..=3 {
                let s: f64 = d[k][..4].iter().sum();
                assert!(s.abs() < 1e-10, "sum of order-{k} derivatives {s}");
            }
        }
    }

    #[test]
    fn knot_checks() {
        assert!(check_clamped_knots(&U, 3, 7).is_ok());
        assert!(check_clamped_knots(&U, 3, 6).is_err());
        let mut bad = U;
        bad[5] = 0.1;
        assert!(check_clamped_knots(&bad, 3, 7).is_err());
        let mut nan = U;
        nan[4] = f64::NAN;
        assert!(check_clamped_knots(&nan, 3, 7).is_err());
        let unclamped = [0.0, 0.0, 0.0, 0.1, 0.2, 0.5, 0.7, 1.0, 1.0, 1.0, 1.0];
        assert!(check_clamped_knots(&unclamped, 3, 7).is_err());
        assert_eq!(
            multiplicities(&U),
            vec![(0.0, 4), (0.2, 1), (0.5, 1), (0.7, 1), (1.0, 4)]
        );
    }
}
