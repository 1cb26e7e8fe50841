//! Least squares with linear equality and inequality constraints (seed 001 eq. 1):
//! min ||A x - b|| subject to E x = 0 and G x >= h.
//!
//! The paper uses the LSIE package of Lawson and Hanson; this is the same method written out on
//! nalgebra, because no maintained Rust crate solves LSI/LSEI (the optimisation crates on
//! crates.io cover LP/QP with their own sparse formats, or unconstrained least squares):
//! 1. equality constraints are eliminated through a basis Z of the null space of E
//!    (eigenvectors of E^T E with zero eigenvalue): x = Z y;
//! 2. the inequality-constrained problem in y is turned into a least-distance problem
//!    (Lawson & Hanson ch. 23: A Z = Q R, u = R y - Q^T b);
//! 3. the least-distance problem min ||u|| s.t. G' u >= h' is solved through the dual
//!    non-negative least squares problem (Lawson & Hanson ch. 23.4), by the active-set NNLS
//!    algorithm (ch. 23.3).

use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// Non-negative least squares min ||A x - b|| s.t. x >= 0: Lawson-Hanson active set, and when
/// round-off makes that cycle, projected Gauss-Seidel on the normal equations (monotone,
/// converges for any A with non-zero columns).
pub fn nnls(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>> {
    nnls_active_set(a, b).or_else(|_| nnls_gauss_seidel(a, b))
}

/// Projected Gauss-Seidel: x_i <- max(0, x_i - (A^T A x - A^T b)_i / (A^T A)_ii).
fn nnls_gauss_seidel(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>> {
    let q = a.transpose() * a;
    let c = a.transpose() * b;
    let n = a.ncols();
    let mut x = DVector::zeros(n);
    for _ in 0..5000 {
        let mut change = 0.0f64;
        let mut size = 0.0f64;
        for i in 0..n {
            if q[(i, i)] <= 0.0 {
                continue;
            }
            let g = q.row(i).dot(&x.transpose()) - c[i];
            let v = (x[i] - g / q[(i, i)]).max(0.0);
            change = change.max((v - x[i]).abs());
            x[i] = v;
            size = size.max(v.abs());
        }
        if change <= 1e-12 * size.max(1e-300) {
            return Ok(x);
        }
    }
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(Error::Numerical(
            "non-negative least squares did not converge".into(),
        ))
    }
}

fn nnls_active_set(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>> {
    let n = a.ncols();
    let mut x = DVector::zeros(n);
    let mut passive = vec![false; n];
    let scale = a.amax().max(1e-300) * b.amax().max(1.0);
    let tol = 1e-12 * scale * (a.nrows().max(n) as f64);
    // An index whose sub-problem solution comes out non-positive right after it entered is
    // banned until x changes (round-off would otherwise make the method cycle on it).
    let mut banned = vec![false; n];
    for _outer in 0..(5 * n + 50) {
        let w = a.transpose() * (b - a * &x);
        let t = (0..n)
            .filter(|&j| !passive[j] && !banned[j] && w[j] > tol)
            .max_by(|&i, &j| w[i].total_cmp(&w[j]));
        let Some(t) = t else {
            return Ok(x);
        };
        passive[t] = true;
        for inner in 0..(3 * n + 10) {
            let idx: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
            let ap = DMatrix::from_fn(a.nrows(), idx.len(), |r, c| a[(r, idx[c])]);
            let sp = ap
                .svd(true, true)
                .solve(b, 1e-13 * scale)
                .map_err(|e| Error::Numerical(format!("NNLS sub-problem: {e}")))?;
            let mut s = DVector::zeros(n);
            for (k, &j) in idx.iter().enumerate() {
                s[j] = sp[k];
            }
            if inner == 0 && s[t] <= 0.0 {
                passive[t] = false;
                banned[t] = true;
                break;
            }
            if idx.iter().all(|&j| s[j] > 0.0) {
                x = s;
                banned.iter_mut().for_each(|b| *b = false);
                break;
            }
            let mut alpha = 1.0f64;
            for &j in &idx {
                if s[j] <= 0.0 {
                    let d = x[j] - s[j];
                    if d > 0.0 {
                        alpha = alpha.min(x[j] / d);
                    }
                }
            }
            x += (&s - &x) * alpha;
            if alpha > 0.0 {
                banned.iter_mut().for_each(|b| *b = false);
            }
            for &j in &idx {
                if x[j] <= 1e-14 * scale || (s[j] <= 0.0 && x[j] <= 0.0) {
                    passive[j] = false;
                    x[j] = 0.0;
                }
            }
        }
    }
    Err(Error::Numerical(
        "non-negative least squares did not converge".into(),
    ))
}

/// Least distance programming: min ||u|| s.t. G u >= h (Lawson-Hanson ch. 23.4).
pub fn ldp(g: &DMatrix<f64>, h: &DVector<f64>) -> Result<DVector<f64>> {
    let n = g.ncols();
    if g.nrows() == 0 || h.iter().all(|&v| v <= 0.0) {
        return Ok(DVector::zeros(n));
    }
    let mut e = DMatrix::zeros(n + 1, g.nrows());
    for r in 0..g.nrows() {
        for c in 0..n {
            e[(c, r)] = g[(r, c)];
        }
        e[(n, r)] = h[r];
    }
    let mut f = DVector::zeros(n + 1);
    f[n] = 1.0;
    let u = nnls(&e, &f)?;
    let r = &e * u - f;
    if r.norm() < 1e-10 || r[n].abs() < 1e-12 {
        return Err(Error::Degenerate(
            "the depth constraints of the overlapping parts cannot all hold (cyclic order?)".into(),
        ));
    }
    Ok(DVector::from_fn(n, |i, _| -r[i] / r[n]))
}

/// Orthonormal basis (columns) of the null space of `e`.
pub fn null_space(e: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    if e.nrows() == 0 {
        return DMatrix::identity(n, n);
    }
    let ete = e.transpose() * e;
    let eig = ete.symmetric_eigen();
    let max = eig.eigenvalues.amax().max(1e-300);
    let cols: Vec<usize> = (0..n)
        .filter(|&i| eig.eigenvalues[i] <= 1e-10 * max)
        .collect();
    DMatrix::from_fn(n, cols.len(), |r, c| eig.eigenvectors[(r, cols[c])])
}

/// min ||A x - b|| s.t. E x = 0, G x >= h. `A Z` must have full column rank (every unknown
/// carries a positive-weight energy term).
pub fn lsei(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    e: &DMatrix<f64>,
    g: &DMatrix<f64>,
    h: &DVector<f64>,
) -> Result<DVector<f64>> {
    let n = a.ncols();
    let z = null_space(e, n);
    let az = a * &z;
    let k = az.ncols();
    if k == 0 {
        return Ok(DVector::zeros(n));
    }
    let qr = az.qr();
    let r = qr.r();
    let c = qr.q().transpose() * b;
    let rmax = r.diagonal().amax();
    if (0..k).any(|i| r[(i, i)].abs() <= 1e-12 * rmax) {
        return Err(Error::Numerical(
            "the skeleton energy is singular (a weight is zero?)".into(),
        ));
    }
    // x = Z R^-1 (u + c); G Z R^-1 u >= h - G Z R^-1 c.
    let gz = g * &z;
    // (G Z R^-1)^T = R^-T (G Z)^T.
    let gzr_t = r
        .transpose()
        .solve_lower_triangular(&gz.transpose())
        .ok_or_else(|| Error::Numerical("triangular solve failed".into()))?;
    let gzr = gzr_t.transpose();
    let h2 = h - &gzr * &c;
    let u = ldp(&gzr, &h2)?;
    let y = r
        .solve_upper_triangular(&(u + c))
        .ok_or_else(|| Error::Numerical("triangular solve failed".into()))?;
    Ok(z * y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nnls_clamps_negative_components() {
        // Unconstrained solution (1, -1); with x >= 0 the optimum is (1, 0).
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, -1.0]);
        let b = DVector::from_vec(vec![0.0, 2.0]);
        let x = nnls(&a, &b).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-12 && x[1].abs() < 1e-12, "{x}");
    }

    #[test]
    fn lsei_meets_equalities_and_active_inequalities() {
        // min x^2 + y^2 + z^2 s.t. x - y = 0, x + z >= 3: x = y, z free; optimum at
        // x = y = 1, z = 2 (minimise 2x^2 + (3-x)^2 -> x = 1).
        let a = DMatrix::identity(3, 3);
        let b = DVector::zeros(3);
        let e = DMatrix::from_row_slice(1, 3, &[1.0, -1.0, 0.0]);
        let g = DMatrix::from_row_slice(1, 3, &[1.0, 0.0, 1.0]);
        let h = DVector::from_vec(vec![3.0]);
        let x = lsei(&a, &b, &e, &g, &h).unwrap();
        assert!(
            (x[0] - 1.0).abs() < 1e-9 && (x[1] - 1.0).abs() < 1e-9,
            "{x}"
        );
        assert!((x[2] - 2.0).abs() < 1e-9, "{x}");
        // Inactive inequality: unconstrained optimum.
        let h = DVector::from_vec(vec![-1.0]);
        let x = lsei(&a, &b, &e, &g, &h).unwrap();
        assert!(x.norm() < 1e-12);
        // Infeasible: x + z >= 1 and -x - z >= 1.
        let g = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 1.0, -1.0, 0.0, -1.0]);
        let h = DVector::from_vec(vec![1.0, 1.0]);
        assert!(lsei(&a, &b, &e, &g, &h).is_err());
    }
}
