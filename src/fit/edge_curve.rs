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
//! **Tangents.** Differentiating f(o + s dir) = 0 along the family:
//!
//!   s' = -grad f . (o' + s dir') / (grad f . dir),   dC/dt = o' + s' dir + s dir',
//!
//! exact for the curve above, in the tangent plane of f at C(t) by construction, and a
//! derivative with respect to the edge's unit parameter, which is also the patch parameter along
//! that side. The patch that walks the edge from B to A reverses the arrays and negates the
//! tangents (exact in floating point).

use crate::implicit::Implicit;
use crate::polygonize::newton::solve_on_line;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// The samples of one edge, in its canonical direction (lower node to higher node).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeSamples {
    /// n + 1 points on f = 0; the first and last are the end nodes exactly.
    pub points: Vec<Point3<f64>>,
    /// dC/dt at each point (t the edge parameter in [0, 1], sample k at t = k / n).
    pub tangents: Vec<Vector3<f64>>,
    /// Unit normals grad f / |grad f| at each point.
    pub normals: Vec<Vector3<f64>>,
}

impl EdgeSamples {
    /// Number of intervals.
    pub fn intervals(&self) -> usize {
        self.points.len() - 1
    }
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
    let ga = f.gradient(&a);
    let gb = f.gradient(&b);
    let (Some(na), Some(nb)) = (unit(ga), unit(gb)) else {
        return Err(Error::Numerical(format!(
            "{}: the implicit's gradient vanishes at an end",
            where_()
        )));
    };
    let m = na + nb + unit(net_normal).unwrap_or_else(Vector3::zeros);
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
    let mut points = Vec::with_capacity(n + 1);
    let mut tangents = Vec::with_capacity(n + 1);
    let mut normals = Vec::with_capacity(n + 1);
    for k in 0..=n {
        let t = k as f64 / n as f64;
        let (o, d_o, dir, d_dir) = fam.line(t);
        let (p, s, g) = if k == 0 || k == n {
            let p = if k == 0 { a } else { b };
            (p, (p - o).dot(&dir), if k == 0 { ga } else { gb })
        } else {
            let (s0, window) = match fam {
                Family::Chord { .. } => (0.0, len),
                Family::Polar { r, .. } => (r, r.min(len)),
            };
            let (ds, g) = solve_on_line(f, o + dir * s0, dir, window, tol)
                .map_err(|err| Error::Numerical(format!("{}: {err}", where_())))?;
            let s = s0 + ds;
            (o + dir * s, s, g)
        };
        let gd = g.dot(&dir);
        if gd.abs() <= 1e-9 * g.norm() || gd.is_nan() {
            return Err(Error::Numerical(format!(
                "{}: section line tangent to the surface",
                where_()
            )));
        }
        let ds = -g.dot(&(d_o + d_dir * s)) / gd;
        points.push(p);
        tangents.push(d_o + dir * ds + d_dir * s);
        normals.push(unit(g).ok_or_else(|| {
            Error::Numerical(format!("{}: the implicit's gradient vanishes", where_()))
        })?);
    }
    Ok(EdgeSamples {
        points,
        tangents,
        normals,
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
        }
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
