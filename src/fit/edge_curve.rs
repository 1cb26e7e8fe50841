//! Samples and tangents of one net edge, computed from that edge's data alone (its two end
//! nodes and the implicit), so that both patches meeting at the edge get bit-identical
//! boundary data: the network is watertight by construction.
//!
//! **The section plane.** For the edge from node A to node B (A the lower node index: the
//! canonical direction), let e = B - A, L = |e|, and w the unit component orthogonal to e of
//! n_A + n_B + n_Q (n the unit gradient at the nodes, n_Q the net's unit normal at the edge, the
//! sum of its two quads' normals: it decides when n_A + n_B cancels, on an edge wrapping the rim
//! of a plate thinner than a voxel). The edge curve C is the section of f = 0 by the plane
//! through A spanned by e and w.
//!
//! **The parameterization.** C(t), t in [0, 1], is the point of f = 0 on a line of a family
//! o(t) + s dir(t) of the plane. Let phi be the turning of the in-plane normal from A to B
//! (angles of n_A, n_B measured from w toward e). If |phi| < 1e-3, chord stations:
//! o = A + t e, dir = w (C(t) lies over the chord point t). Otherwise polar: the circle through
//! A and B whose normal turns by phi has centre O = M - w (L/2) / tan(phi/2) (M the chord
//! midpoint) and radius R = (L/2) / sin(|phi|/2); the lines are the rays from O at angles
//! interpolated linearly from A's to B's, and the root is taken nearest the circle. For a
//! circular arc this is exactly the arc-length parameterization; a quarter turn or a half turn
//! (a rim) is as well conditioned as a flat edge, where chord stations would have tangents
//! parallel to their lines. Sample k of n is C(k / n): equally spaced samples, which is why
//! uniform parameters fit them (seed 004 eq. 9's square-root chord parameters of equally spaced
//! points are uniform).
//!
//! **Fallback: tracing.** When a line of the family misses the surface, meets it at a grazing
//! angle, or the samples come out of order (a hairpin around the rim of a part thinner than the
//! edge is long, like the bunny's ears at 1,500 patches), the section curve is traced instead:
//! steps of L / 32 along the curve tangent (plane normal x grad f), each corrected onto f = 0 by
//! Newton inside the plane, until B is reached; the polyline is resampled at equal arc lengths
//! and each sample corrected again. Tangents are then the unit tangent times the traced length.
//!
//! **Last resort.** If tracing fails too (an implicit with a near-zero plateau or a jump in the
//! plane), the chord points are projected along the gradient and the tangents are the chord
//! projected onto the tangent plane: still shared by both patches (watertight), not a plane
//! curve, counted in the sampling report.
//!
//! **Tangents.** Differentiating f(o + s dir) = 0 along the family:
//!
//!   s' = -grad f . (o' + s dir') / (grad f . dir),   dC/dt = o' + s' dir + s dir',
//!
//! exact for the curve above, in the tangent plane of f at C(t) by construction, and a
//! derivative with respect to the edge's unit parameter, which is also the patch parameter along
//! that side. The patch that walks the edge from B to A reverses the arrays and negates the
//! tangents (exact in floating point).

use crate::implicit::Implicit;
use crate::polygonize::newton::{solve_on_line, solve_on_line_valued};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// How an edge's samples were found (module doc), best first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EdgeMethod {
    /// Roots on a family of lines of the section plane (chord stations or polar).
    Lines,
    /// Tracing of the section curve.
    Traced,
    /// Last resort: chord points projected along the gradient (not a plane curve).
    ProjectedChord,
}

/// The samples of one edge, in its canonical direction (lower node to higher node).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeSamples {
    /// n + 1 points on f = 0; the first and last are the end nodes exactly.
    pub points: Vec<Point3<f64>>,
    /// dC/dt at each point (t the edge parameter in [0, 1], sample k at t = k / n).
    pub tangents: Vec<Vector3<f64>>,
    /// Unit normals grad f / |grad f| at each point.
    pub normals: Vec<Vector3<f64>>,
    /// |f| / |grad f| at each point, as the root finder left it ([`residual`]).
    pub residuals: Vec<f64>,
    pub method: EdgeMethod,
    /// Unit in-plane normal w of the section plane (orthogonal to the chord; the plane is
    /// spanned by the chord and w), independent of the direction the edge is walked.
    pub plane_w: Vector3<f64>,
}

impl EdgeSamples {
    /// Number of intervals.
    pub fn intervals(&self) -> usize {
        self.points.len() - 1
    }
}

/// |f| / |grad f|, the first-order distance from f = 0 (infinite where it is not finite).
pub fn residual(v: f64, g: &Vector3<f64>) -> f64 {
    let r = v.abs() / g.norm();
    if r.is_finite() {
        r
    } else {
        f64::INFINITY
    }
}

/// [`residual`] at p, evaluated.
fn residual_at<I: Implicit + ?Sized>(f: &I, p: &Point3<f64>) -> f64 {
    let (v, g) = f.value_and_gradient(p);
    residual(v, &g)
}

fn unit(g: Vector3<f64>) -> Option<Vector3<f64>> {
    let n = g.norm();
    (n > 0.0 && n.is_finite()).then(|| g / n)
}

/// The line family of an edge (module doc).
enum Family {
    /// o = a + t e, dir = w.
    Chord {
        a: Point3<f64>,
        e: Vector3<f64>,
        w: Vector3<f64>,
    },
    /// o = centre, dir = cos(th) x + sin(th) w, th = th0 + t dth; roots near radius r.
    Polar {
        centre: Point3<f64>,
        x: Vector3<f64>,
        w: Vector3<f64>,
        th0: f64,
        dth: f64,
        r: f64,
    },
}

impl Family {
    /// (o, o', dir, dir') at t.
    fn line(&self, t: f64) -> (Point3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        match *self {
            Family::Chord { a, e, w } => (a + e * t, e, w, Vector3::zeros()),
            Family::Polar {
                centre,
                x,
                w,
                th0,
                dth,
                ..
            } => {
                let th = th0 + t * dth;
                let (sn, cs) = th.sin_cos();
                (
                    centre,
                    Vector3::zeros(),
                    x * cs + w * sn,
                    (w * cs - x * sn) * dth,
                )
            }
        }
    }
}

/// Samples the edge from `a` (lower node) to `b` (higher node) at `n` intervals. `net_normal`
/// is the net's normal at the edge (any length; it only breaks ties when the end normals
/// cancel), `tol` the distance tolerance of the root finding. Errors: n = 0, coincident nodes,
/// a vanishing gradient, no usable section plane, a line that misses the surface.
pub fn sample_edge<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    b: Point3<f64>,
    net_normal: Vector3<f64>,
    n: usize,
    tol: f64,
) -> Result<EdgeSamples> {
    sample_curve(f, a, b, Plane::FromNormals(net_normal), n, tol)
}

/// Samples the section of f = 0 from `a` to `b` in the plane through a and b containing the
/// direction `w` (its component orthogonal to b - a), as [`sample_edge`] does for a net edge.
/// The patch sampler uses it for interior rows, with w blended from the two boundary edges'
/// [`EdgeSamples::plane_w`] so that the rows continue the boundaries.
pub fn sample_section<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    b: Point3<f64>,
    w: Vector3<f64>,
    n: usize,
    tol: f64,
) -> Result<EdgeSamples> {
    sample_curve(f, a, b, Plane::Given(w), n, tol)
}

/// How the section plane is chosen.
enum Plane {
    /// From the end normals, the net's normal breaking ties.
    FromNormals(Vector3<f64>),
    /// Containing this direction.
    Given(Vector3<f64>),
}

fn sample_curve<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    b: Point3<f64>,
    plane: Plane,
    n: usize,
    tol: f64,
) -> Result<EdgeSamples> {
    let e = b - a;
    let len = e.norm();
    let where_ = || {
        format!(
            "edge ({:.6}, {:.6}, {:.6})-({:.6}, {:.6}, {:.6})",
            a.x, a.y, a.z, b.x, b.y, b.z
        )
    };
    if n == 0 || !(len > 0.0 && len.is_finite()) {
        return Err(Error::Degenerate(format!(
            "{} has zero length or no samples",
            where_()
        )));
    }
    let x = e / len;
    let (va, ga) = f.value_and_gradient(&a);
    let (vb, gb) = f.value_and_gradient(&b);
    let ends = [residual(va, &ga), residual(vb, &gb)];
    let (Some(na), Some(nb)) = (unit(ga), unit(gb)) else {
        return Err(Error::Numerical(format!(
            "{}: the implicit's gradient vanishes at an end",
            where_()
        )));
    };
    let m = match plane {
        Plane::FromNormals(hint) => na + nb + unit(hint).unwrap_or_else(Vector3::zeros),
        Plane::Given(w) => w,
    };
    let w = m - x * m.dot(&x);
    let Some(w) = unit(w).filter(|_| w.norm() > 1e-6) else {
        return Err(Error::Numerical(format!(
            "{}: no section plane (normals cancel or run along the edge)",
            where_()
        )));
    };
    let angle = |nn: &Vector3<f64>| nn.dot(&x).atan2(nn.dot(&w));
    let mut phi = angle(&nb) - angle(&na);
    if phi > std::f64::consts::PI {
        phi -= 2.0 * std::f64::consts::PI;
    } else if phi < -std::f64::consts::PI {
        phi += 2.0 * std::f64::consts::PI;
    }
    let fam = if phi.abs() < 1e-3 {
        Family::Chord { a, e, w }
    } else {
        let half = 0.5 * phi;
        let centre = nalgebra::center(&a, &b) - w * (0.5 * len / half.tan());
        let r = 0.5 * len / half.sin().abs();
        let polar = |p: &Point3<f64>| {
            let d = p - centre;
            d.dot(&w).atan2(d.dot(&x))
        };
        let th0 = polar(&a);
        let mut dth = polar(&b) - th0;
        // Convex (phi > 0): the angle decreases from A to B through +w; concave: increases.
        let two_pi = 2.0 * std::f64::consts::PI;
        if phi > 0.0 && dth > 0.0 {
            dth -= two_pi;
        } else if phi < 0.0 && dth < 0.0 {
            dth += two_pi;
        }
        Family::Polar {
            centre,
            x,
            w,
            th0,
            dth,
            r,
        }
    };
    let family = sample_family(f, &fam, a, b, ga, gb, ends, n, tol, len).filter(ordered);
    if let Some(mut es) = family {
        es.plane_w = w;
        return Ok(es);
    }
    // The family missed (a hairpin around the rim of a part thinner than the edge, a second
    // sheet crossing a line): trace the section curve instead.
    let (o, d_o, dir, d_dir) = fam.line(0.0);
    let s0 = (a - o).dot(&dir);
    let start = d_o + dir * (-ga.dot(&(d_o + d_dir * s0)) / ga.dot(&dir)) + d_dir * s0;
    let start = if start.iter().all(|v| v.is_finite()) {
        start
    } else {
        e
    };
    trace_section(f, a, b, ga, gb, x.cross(&w), start, n, tol, len)
        .or_else(|_| projected_chord(f, a, b, ga, gb, n, tol))
        .map(|mut es| {
            es.plane_w = w;
            // These rarer methods resample or fall back: their residuals are evaluated.
            es.residuals = es.points.iter().map(|p| residual_at(f, p)).collect();
            es
        })
        .map_err(|err| Error::Numerical(format!("{}: {err}", where_())))
}

/// The chord points at t = k / n projected onto f = 0 along the gradient (what
/// [`sample_edge`] falls back to last), for a caller that rejects the section curve: in an
/// open fit a section that ran out into the implicit's extrapolation, far from every point
/// (see [`crate::fit::samples::NearData`]). The samples stay within half an edge length of
/// the chord (the projection's step bound), so the edge cannot wander off.
pub fn sample_projected_chord<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    b: Point3<f64>,
    n: usize,
    tol: f64,
) -> Result<EdgeSamples> {
    let ga = f.gradient(&a);
    let gb = f.gradient(&b);
    if n == 0 || unit(ga).is_none() || unit(gb).is_none() {
        return Err(Error::Numerical(
            "projected chord: no samples or a vanishing gradient at an end".into(),
        ));
    }
    let mut es = projected_chord(f, a, b, ga, gb, n, tol)?;
    es.residuals = es.points.iter().map(|p| residual_at(f, p)).collect();
    Ok(es)
}

/// Last resort: the chord points at t = k / n projected onto f = 0 along the gradient; the
/// tangents are the chord projected onto the tangent plane (an approximation of d/dt).
fn projected_chord<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    b: Point3<f64>,
    ga: Vector3<f64>,
    gb: Vector3<f64>,
    n: usize,
    tol: f64,
) -> Result<EdgeSamples> {
    let e = b - a;
    let opt = crate::polygonize::newton::NewtonOptions {
        tol,
        accept: 1e3 * tol,
        max_step: 0.5 * e.norm(),
        max_iter: 60,
    };
    let mut es = EdgeSamples {
        points: Vec::with_capacity(n + 1),
        tangents: Vec::with_capacity(n + 1),
        normals: Vec::with_capacity(n + 1),
        residuals: Vec::new(),
        method: EdgeMethod::ProjectedChord,
        plane_w: Vector3::zeros(),
    };
    for k in 0..=n {
        let (p, g) = if k == 0 {
            (a, ga)
        } else if k == n {
            (b, gb)
        } else {
            let x = a + e * (k as f64 / n as f64);
            match crate::polygonize::newton::project(f, x, &opt) {
                Ok(r) => r,
                // Where Newton along the gradient wanders (a plateau or a jump of the
                // implicit), the root on the line along the mean end normal; failing that the
                // chord point itself, left off the surface: the edge stays shared by both
                // patches (watertight) and its residual shows in the sampling report.
                Err(_) => {
                    let w = ga.normalize() + gb.normalize();
                    let w = if w.norm() > 1e-9 {
                        w.normalize()
                    } else {
                        ga.normalize()
                    };
                    match solve_on_line(f, x, w, 0.5 * e.norm(), tol) {
                        Ok((s, g)) => (x + w * s, g),
                        Err(_) => (x, w),
                    }
                }
            }
        };
        let nn =
            unit(g).ok_or_else(|| Error::Numerical("the implicit's gradient vanishes".into()))?;
        es.points.push(p);
        es.tangents.push(e - nn * nn.dot(&e));
        es.normals.push(nn);
    }
    Ok(es)
}

/// Samples at t = k / n on the lines of the family; None when a line misses the surface or
/// meets it at a grazing angle.
#[allow(clippy::too_many_arguments)]
fn sample_family<I: Implicit + ?Sized>(
    f: &I,
    fam: &Family,
    a: Point3<f64>,
    b: Point3<f64>,
    ga: Vector3<f64>,
    gb: Vector3<f64>,
    ends: [f64; 2],
    n: usize,
    tol: f64,
    len: f64,
) -> Option<EdgeSamples> {
    let mut points = Vec::with_capacity(n + 1);
    let mut tangents = Vec::with_capacity(n + 1);
    let mut normals = Vec::with_capacity(n + 1);
    let mut residuals = Vec::with_capacity(n + 1);
    for k in 0..=n {
        let t = k as f64 / n as f64;
        let (o, d_o, dir, d_dir) = fam.line(t);
        let (p, s, g, res) = if k == 0 || k == n {
            let p = if k == 0 { a } else { b };
            let end = if k == 0 { 0 } else { 1 };
            (
                p,
                (p - o).dot(&dir),
                if k == 0 { ga } else { gb },
                ends[end],
            )
        } else {
            let (s0, window) = match *fam {
                Family::Chord { .. } => (0.0, len),
                Family::Polar { r, .. } => (r, r.min(len)),
            };
            let (ds, g, v) = solve_on_line_valued(f, o + dir * s0, dir, window, tol).ok()?;
            let s = s0 + ds;
            (o + dir * s, s, g, residual(v, &g))
        };
        let gd = g.dot(&dir);
        if gd.abs() <= 0.05 * g.norm() || gd.is_nan() {
            return None;
        }
        let ds = -g.dot(&(d_o + d_dir * s)) / gd;
        points.push(p);
        tangents.push(d_o + dir * ds + d_dir * s);
        normals.push(unit(g)?);
        residuals.push(res);
    }
    Some(EdgeSamples {
        points,
        tangents,
        normals,
        residuals,
        method: EdgeMethod::Lines,
        plane_w: Vector3::zeros(),
    })
}

/// True when the samples run along one curve: consecutive gaps within 2.5 times their mean and
/// consecutive tangents pointing the same way and along the gaps.
fn ordered(es: &EdgeSamples) -> bool {
    let n = es.intervals();
    let gaps: Vec<f64> = es.points.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    let mean = gaps.iter().sum::<f64>() / n as f64;
    gaps.iter().all(|&g| g <= 2.5 * mean)
        && (0..n).all(|k| {
            let d = es.points[k + 1] - es.points[k];
            es.tangents[k].dot(&es.tangents[k + 1]) > 0.0
                && es.tangents[k].dot(&d) > 0.0
                && es.tangents[k + 1].dot(&d) > 0.0
        })
}

/// Traces the section of f = 0 by the plane through `a` with unit normal `m` from a to b
/// (first step along `start`), in steps of L / 32 with Newton corrections inside the plane,
/// then resamples it at n + 1 equal arc lengths. Tangents: unit curve tangent times the traced
/// length (the derivative for the arc-length parameter on [0, 1]).
#[allow(clippy::too_many_arguments)]
fn trace_section<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    b: Point3<f64>,
    ga: Vector3<f64>,
    gb: Vector3<f64>,
    m: Vector3<f64>,
    start: Vector3<f64>,
    n: usize,
    tol: f64,
    len: f64,
) -> Result<EdgeSamples> {
    let step = len / 32.0;
    let in_plane = |g: &Vector3<f64>| g - m * m.dot(g);
    let along = |g: &Vector3<f64>| unit(m.cross(g));
    let correct = |mut p: Point3<f64>| -> Result<(Point3<f64>, Vector3<f64>)> {
        for _ in 0..30 {
            let (v, g) = f.value_and_gradient(&p);
            let gp = in_plane(&g);
            let gp2 = gp.norm_squared();
            if !(v.is_finite() && gp2 > 0.0 && gp2.is_finite()) {
                break;
            }
            if v.abs() <= 1e3 * tol * gp2.sqrt() {
                return Ok((p, g));
            }
            let mut d = gp * (-v / gp2);
            let dn = d.norm();
            if dn > step {
                d *= step / dn;
            }
            p += d;
        }
        Err(Error::Numerical("tracing lost the surface".into()))
    };
    let mut t =
        along(&ga).ok_or_else(|| Error::Numerical("gradient along the section normal".into()))?;
    if t.dot(&start) < 0.0 {
        t = -t;
    }
    let mut poly = vec![a];
    let (mut p, mut travelled) = (a, 0.0);
    loop {
        if (b - p).norm() <= 1.5 * step && (b - p).dot(&t) > 0.0 {
            poly.push(b);
            break;
        }
        if travelled > 24.0 * len || poly.len() > 24 * 32 {
            return Err(Error::Numerical(
                "the section curve does not reach the edge's end".into(),
            ));
        }
        let (q, gq) = correct(p + t * step)?;
        let mut tq = along(&gq)
            .ok_or_else(|| Error::Numerical("gradient along the section normal".into()))?;
        if tq.dot(&t) < 0.0 {
            tq = -tq;
        }
        travelled += (q - p).norm();
        poly.push(q);
        p = q;
        t = tq;
    }
    // Resample at equal arc lengths.
    let mut cum = vec![0.0];
    for w in poly.windows(2) {
        cum.push(cum.last().copied().unwrap_or(0.0) + (w[1] - w[0]).norm());
    }
    let total = cum.last().copied().unwrap_or(0.0);
    let mut points = Vec::with_capacity(n + 1);
    let mut tangents = Vec::with_capacity(n + 1);
    let mut normals = Vec::with_capacity(n + 1);
    let mut seg = 0;
    for k in 0..=n {
        let target = total * k as f64 / n as f64;
        while seg + 2 < poly.len() && cum[seg + 1] < target {
            seg += 1;
        }
        let d = poly[seg + 1] - poly[seg];
        let (p, g) = if k == 0 {
            (a, ga)
        } else if k == n {
            (b, gb)
        } else {
            let u = ((target - cum[seg]) / (cum[seg + 1] - cum[seg]).max(1e-300)).clamp(0.0, 1.0);
            correct(poly[seg] + d * u)?
        };
        let mut tk = along(&g)
            .ok_or_else(|| Error::Numerical("gradient along the section normal".into()))?;
        if tk.dot(&d) < 0.0 {
            tk = -tk;
        }
        points.push(p);
        tangents.push(tk * total);
        normals.push(
            unit(g).ok_or_else(|| Error::Numerical("the implicit's gradient vanishes".into()))?,
        );
    }
    Ok(EdgeSamples {
        points,
        tangents,
        normals,
        residuals: Vec::new(),
        method: EdgeMethod::Traced,
        plane_w: Vector3::zeros(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::Implicit;
    use crate::polygonize::test_shapes::Sphere;

    #[test]
    fn quarter_circle_on_a_sphere() {
        let s = Sphere {
            c: Point3::origin(),
            r: 1.0,
        };
        let (a, b) = (Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0));
        let ed = sample_edge(&s, a, b, Vector3::zeros(), 8, 1e-14).unwrap();
        assert_eq!(ed.intervals(), 8);
        assert_eq!(ed.points[0], a);
        assert_eq!(ed.points[8], b);
        for k in 0..=8 {
            let p = ed.points[k];
            // On the great circle z = 0 (the normal section through the centre).
            assert!((p.coords.norm() - 1.0).abs() < 1e-13);
            assert!(p.z.abs() < 1e-13);
            // Equal arc lengths: the polar family about the sphere's centre.
            let ang = p.y.atan2(p.x);
            assert!((ang - std::f64::consts::FRAC_PI_2 * k as f64 / 8.0).abs() < 1e-12);
            // Tangent: in the tangent plane, d/dt of the arc, length pi/2.
            assert!(ed.tangents[k].dot(&ed.normals[k]).abs() < 1e-12);
            assert!((ed.tangents[k].norm() - std::f64::consts::FRAC_PI_2).abs() < 1e-10);
            // The residual the solver reports is the one an evaluation at the point gives.
            let (v, g) = s.value_and_gradient(&p);
            assert!((ed.residuals[k] - residual(v, &g)).abs() < 1e-15, "{k}");
        }
        assert_eq!(ed.residuals.len(), 9);
        // Degenerate edges are errors.
        let z = Vector3::zeros();
        assert!(sample_edge(&s, a, a, z, 4, 1e-12).is_err());
        assert!(sample_edge(&s, a, b, z, 0, 1e-12).is_err());
        // Antipodal ends: the normals cancel and no net normal decides.
        assert!(sample_edge(&s, a, Point3::new(-1.0, 0.0, 0.0), z, 4, 1e-12).is_err());
    }

    /// Tangents are the derivative of the sampled curve: compare with finite differences of
    /// the same family, on a flat-ish edge (chord stations) and across a plate's rim (a half
    /// turn, polar family around the rim's centre).
    #[test]
    fn tangents_match_finite_differences() {
        let blob = crate::polygonize::test_shapes::Blob {
            r: 0.8,
            amp: 0.03,
            w: 7.0,
        };
        let opt = crate::polygonize::newton::NewtonOptions::new(2.0, 0.1);
        let p = |x: Point3<f64>| {
            crate::polygonize::newton::project(&blob, x, &opt)
                .unwrap()
                .0
        };
        let slab = crate::polygonize::test_shapes::RoundedBox {
            b: Vector3::new(0.6, 0.45, 0.0),
            r: 0.03,
        };
        let cases = [
            (
                &blob as &dyn Implicit,
                p(Point3::new(0.8, 0.0, 0.0)),
                p(Point3::new(0.78, 0.12, 0.05)),
                Vector3::zeros(),
            ),
            (
                &slab as &dyn Implicit,
                Point3::new(-0.58, -0.4, -0.03),
                Point3::new(-0.6, -0.403, 0.03),
                Vector3::new(-1.0, 0.0, 0.0),
            ),
        ];
        for (f, a, b, hint) in cases {
            let coarse = sample_edge(f, a, b, hint, 4, 1e-14).unwrap();
            for k in 0..=4 {
                assert!(
                    coarse.tangents[k].dot(&coarse.normals[k]).abs()
                        < 1e-10 * coarse.tangents[k].norm()
                );
            }
            // Finite differences from a dense sampling with 4 x 1024 intervals.
            let dense = sample_edge(f, a, b, hint, 4096, 1e-14).unwrap();
            for k in 1..4 {
                let j = k * 1024;
                let fd = (dense.points[j + 1] - dense.points[j - 1]) * (4096.0 / 2.0);
                assert_eq!(dense.points[j], coarse.points[k]);
                let err = (fd - coarse.tangents[k]).norm() / coarse.tangents[k].norm();
                assert!(err < 1e-5, "k {k}: {fd} vs {}", coarse.tangents[k]);
            }
        }
    }
}
