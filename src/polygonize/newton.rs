//! Newton projection onto f(x) = 0, the small projector the quad net and the patch samples need.
//!
//! Two forms (seed 004 section 3, "normal projection"; the same iteration as seed 000
//! eq. 8-12, with the direction taken from the gradient instead of a plane normal):
//! - [`project`]: x <- x - f(x) grad f(x) / |grad f(x)|^2, a Newton step along the gradient,
//!   re-evaluated at every iterate;
//! - [`solve_on_line`]: the root s of f(o + s w) = 0 on a fixed line, s <- s - f / (grad f . w),
//!   with a bracketing fallback (Illinois regula falsi) when Newton leaves the neighbourhood.
//!
//! Both stop when the first-order distance |f| / |grad f| is below `tol` and return the gradient
//! at the final point (the surface normal, up to length); a stalled iteration is accepted when
//! within `accept` (an implicit evaluated with round-off noise cannot always reach `tol`). Steps are capped at `max_step` and
//! halved while |f| grows, so a start a voxel away from the surface cannot jump to another sheet.
//! Hand-written because the iteration is five lines; the implicit engineer's `implicit/project.rs`
//! can replace [`project`] once merged.

use crate::implicit::project::backtrack;
use crate::implicit::Implicit;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// Iteration controls.
#[derive(Debug, Clone, Copy)]
pub struct NewtonOptions {
    /// Stop when |f| / |grad f| <= tol (a length).
    pub tol: f64,
    /// When the iteration stalls (an implicit with noise or tiny jumps below `tol`), accept the
    /// iterate if |f| / |grad f| <= accept; otherwise fail.
    pub accept: f64,
    /// Longest single step (a length).
    pub max_step: f64,
    /// Iteration cap.
    pub max_iter: usize,
}

impl NewtonOptions {
    /// Tolerance 1e-12 of the length scale, steps up to `max_step`.
    pub fn new(scale: f64, max_step: f64) -> Self {
        NewtonOptions {
            tol: 1e-12 * scale,
            accept: 1e-9 * scale,
            max_step,
            max_iter: 60,
        }
    }
}

fn finite_vec(v: &Vector3<f64>) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Projects `x` onto f = 0 along the gradient. Returns the point and grad f there.
pub fn project<I: Implicit + ?Sized>(
    f: &I,
    x: Point3<f64>,
    opt: &NewtonOptions,
) -> Result<(Point3<f64>, Vector3<f64>)> {
    let mut p = x;
    let (mut v, mut g) = f.value_and_gradient(&p);
    for _ in 0..opt.max_iter {
        let g2 = g.norm_squared();
        if !v.is_finite() || !finite_vec(&g) || g2 <= 0.0 {
            break;
        }
        if v.abs() <= opt.tol * g2.sqrt() {
            return Ok((p, g));
        }
        let mut step = g * (-v / g2);
        let len = step.norm();
        if len > opt.max_step {
            step *= opt.max_step / len;
        }
        // Damped: halve while |f| does not decrease.
        let Some(next) = backtrack(v, 20, |s| {
            let q = p + step * s;
            let (vq, gq) = f.value_and_gradient(&q);
            Some((vq, (q, gq)))
        }) else {
            break;
        };
        (v, (p, g)) = next;
    }
    if v.is_finite() && finite_vec(&g) && v.abs() <= opt.accept.max(opt.tol) * g.norm() {
        return Ok((p, g));
    }
    Err(Error::Numerical(format!(
        "projection onto the implicit from ({:.6}, {:.6}, {:.6}) did not converge (|f| = {v:.3e})",
        x.x, x.y, x.z
    )))
}

/// Root of f(o + s w) = 0 for s in [-s_max, s_max], the one nearest s = 0 when Newton from 0
/// fails. `w` need not be unit; `tol` applies to |f| / |grad f| (a stalled Newton iterate within
/// 1000 tol is accepted; where f jumps across zero, the located sign change is returned even
/// though |f| is not small there). Returns (s, grad f).
pub fn solve_on_line<I: Implicit + ?Sized>(
    f: &I,
    o: Point3<f64>,
    w: Vector3<f64>,
    s_max: f64,
    tol: f64,
) -> Result<(f64, Vector3<f64>)> {
    solve_on_line_valued(f, o, w, s_max, tol).map(|(s, g, _)| (s, g))
}

/// [`solve_on_line`], also returning f at the root found (what its last evaluation gave, so
/// callers that report |f| / |grad f| need not evaluate again): (s, grad f, f).
pub fn solve_on_line_valued<I: Implicit + ?Sized>(
    f: &I,
    o: Point3<f64>,
    w: Vector3<f64>,
    s_max: f64,
    tol: f64,
) -> Result<(f64, Vector3<f64>, f64)> {
    let at = |s: f64| f.value_and_gradient(&(o + w * s));
    // Newton from s = 0.
    let mut s = 0.0;
    let (mut v, mut g) = at(s);
    for _ in 0..40 {
        if !v.is_finite() || !finite_vec(&g) {
            break;
        }
        if v.abs() <= tol * g.norm() {
            return Ok((s, g, v));
        }
        let d = g.dot(&w);
        if d == 0.0 || !d.is_finite() {
            break;
        }
        let step = (-v / d).clamp(-0.25 * s_max, 0.25 * s_max);
        let Some(next) = backtrack(v, 20, |k| {
            let t = s + step * k;
            (t.abs() <= s_max).then(|| {
                let (vt, gt) = at(t);
                (vt, (t, gt))
            })
        }) else {
            break;
        };
        (v, (s, g)) = next;
    }
    // Stalled close enough (noise below tol): accept within 1000 tol.
    if v.is_finite() && v.abs() <= 1e3 * tol * g.norm() {
        return Ok((s, g, v));
    }
    // Fallback: nearest sign change on a grid of 32 steps each way, then Illinois.
    scan_and_refine(
        &at,
        o,
        s_max,
        tol,
        32,
        &|lo, hi| (lo <= 0.0) != (hi <= 0.0),
        "surface point",
    )
}

/// Root of f(o + s w) = 0 nearest s = 0 in [-s_max, s_max] at which f *increases* along w
/// (grad f . w > 0): the surface crossed from inside to outside when walking along w. On a
/// sheet thinner than the search window (a plate, a thin ear) a line meets two roots of
/// opposite orientation; a net node whose outward direction is w belongs on this one. Newton
/// from s = 0 is tried first and kept when its root faces w; otherwise the line is scanned in
/// 64 steps each way for the nearest such bracket.
pub fn solve_on_line_facing<I: Implicit + ?Sized>(
    f: &I,
    o: Point3<f64>,
    w: Vector3<f64>,
    s_max: f64,
    tol: f64,
) -> Result<(f64, Vector3<f64>)> {
    if let Ok((s, g)) = solve_on_line(f, o, w, s_max, tol) {
        if g.dot(&w) > 0.0 {
            return Ok((s, g));
        }
    }
    let at = |s: f64| f.value_and_gradient(&(o + w * s));
    // f <= 0 at the lower end and > 0 at the upper: increasing along w.
    scan_and_refine(
        &at,
        o,
        s_max,
        tol,
        64,
        &|lo, hi| lo <= 0.0 && hi > 0.0,
        "outward-facing surface point",
    )
    .map(|(s, g, _)| (s, g))
}

/// The bracketing fallback of both line solvers: the nearest bracket `accept`s
/// ([`nearest_bracket`], `n` steps each way), refined by Illinois ([`refine_bracket`]).
/// `what` names the root sought in the error when no bracket is found.
fn scan_and_refine(
    at: &dyn Fn(f64) -> (f64, Vector3<f64>),
    o: Point3<f64>,
    s_max: f64,
    tol: f64,
    n: usize,
    accept: &dyn Fn(f64, f64) -> bool,
    what: &str,
) -> Result<(f64, Vector3<f64>, f64)> {
    let Some((a, fa, b, fb)) = nearest_bracket(&|s| at(s).0, s_max, n, accept) else {
        return Err(Error::Numerical(format!(
            "no {what} on the line through ({:.6}, {:.6}, {:.6}) within {s_max:.3e}",
            o.x, o.y, o.z
        )));
    };
    refine_bracket(at, (a, fa), (b, fb), s_max, tol).ok_or_else(|| {
        Error::Numerical(format!(
            "root finding on the line through ({:.6}, {:.6}, {:.6}) did not converge",
            o.x, o.y, o.z
        ))
    })
}

/// The interval of the grid of `n` steps each way from s = 0 nearest to 0 (outward, the
/// positive side first at each distance) whose end values f(lo), f(hi), lo < hi, are finite
/// and satisfy `accept`: (lo, f(lo), hi, f(hi)). One scan for both line solvers, which differ
/// only in what they accept (any sign change, or an increasing one).
fn nearest_bracket(
    value: &dyn Fn(f64) -> f64,
    s_max: f64,
    n: usize,
    accept: &dyn Fn(f64, f64) -> bool,
) -> Option<(f64, f64, f64, f64)> {
    let at_step = |k: usize| s_max * k as f64 / n as f64;
    let f0 = value(0.0);
    for k in 0..n {
        let (near, far) = (at_step(k), at_step(k + 1));
        for (lo, hi) in [(near, far), (-far, -near)] {
            let f_lo = if lo == 0.0 { f0 } else { value(lo) };
            let f_hi = if hi == 0.0 { f0 } else { value(hi) };
            if f_lo.is_finite() && f_hi.is_finite() && accept(f_lo, f_hi) {
                return Some((lo, f_lo, hi, f_hi));
            }
        }
    }
    None
}

/// Illinois (modified regula falsi) on a bracket (a, f(a)), (b, f(b)) of opposite signs.
/// Returns (s, grad f, f) at the root, or None when the iteration fails.
fn refine_bracket(
    at: &dyn Fn(f64) -> (f64, Vector3<f64>),
    (mut a, mut fa): (f64, f64),
    (mut b, mut fb): (f64, f64),
    s_max: f64,
    tol: f64,
) -> Option<(f64, Vector3<f64>, f64)> {
    let mut side = 0i8;
    for _ in 0..200 {
        let c = (a * fb - b * fa) / (fb - fa);
        let (fc, gc) = at(c);
        if !fc.is_finite() {
            break;
        }
        if fc.abs() <= tol * gc.norm() {
            return Some((c, gc, fc));
        }
        if (b - a).abs() <= 1e-15 * s_max {
            // The bracket closed: f changes sign here. If |f| is not small, f jumps across
            // zero (a defect of the implicit); the sign change is still where its zero set
            // is, so it is returned and callers measure |f| / |grad f| to report it.
            return Some((c, gc, fc));
        }
        if (fc <= 0.0) == (fb <= 0.0) {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sphere(f64);
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - self.0
        }
        fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
            x.coords.normalize()
        }
    }

    #[test]
    fn projects_onto_a_sphere() {
        let s = Sphere(2.0);
        let opt = NewtonOptions::new(4.0, 0.5);
        let (p, g) = project(&s, Point3::new(0.3, 2.9, -0.2), &opt).unwrap();
        assert!((p.coords.norm() - 2.0).abs() < 1e-11);
        assert!((g.normalize() - p.coords / 2.0).norm() < 1e-12);
        // Starting at the centre (zero gradient) must fail, not loop or panic.
        assert!(project(&s, Point3::origin(), &opt).is_err());
    }

    #[test]
    fn solves_on_a_line_and_falls_back_to_brackets() {
        let s = Sphere(1.0);
        let (t, _) = solve_on_line(
            &s,
            Point3::new(0.5, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            2.0,
            1e-13,
        )
        .unwrap();
        assert!((t - 0.75f64.sqrt()).abs() < 1e-12);
        // Tangent start: Newton has zero derivative at s = 0 along w.
        let (t, _) = solve_on_line(
            &s,
            Point3::new(0.0, 0.0, 1.0),
            Vector3::new(1.0, 0.0, 0.0),
            0.5,
            1e-13,
        )
        .unwrap();
        assert!(t.abs() < 1e-6);
        assert!(solve_on_line(&s, Point3::new(5.0, 0.0, 0.0), Vector3::x(), 1.0, 1e-13).is_err());
    }
}
