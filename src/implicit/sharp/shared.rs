//! Points on a crease given to both its sides: a point that its own side fits but that F
//! misses, because the other side wins the max or min there, lies where that side cuts into
//! the point's face; the other side is fitted again with the point as one of its own.
//!
//! A crease is the curve where two faces meet, so a point sampled on it (a mesh's vertex on a
//! hole's rim) lies on both. The features give it one region, and the other side, fitted to
//! its own points only, extrapolates to the crease: a quadratic on a few points of a hole's
//! wall misses the rim by several tolerances, and F = max(f_a, f_b) takes the wall's value
//! there (make_parts' corner block from its mesh, the bore in the oblique face: rim vertices 6
//! tolerances off, the crease 1.5e-3 of the diagonal away).
//!
//! With the function fitted, a point x of region a with |f_a(x)| <= 2 flat and |F(x)| > 2 flat
//! is *shared* with the side b that gives F(x): b is fitted again from its points and x (the
//! inequality f_b(x) <= 0 at a convex edge, >= 0 at a concave one, that F(x) = f_a(x) needs,
//! taken as active: f_b(x) = 0). Only a point whose normal is not its own face's (more than
//! [`OWN_NORMAL_COS`] off its side's gradient) is shared: a point on the crease has the mean
//! normal of the two faces, a mesh's vertex as a cloud's estimate, while a point of face a
//! away from the crease has a's normal, and a side b that cuts into face a there is bent
//! (make_parts' block from its cloud beside its 1.5 mm chamfer: sharing such points bent the
//! top face's side further over the chamfer, crease max 7.7e-4 -> 8.2e-4 of the diagonal).
//! Repeated while points are added and the sum of F(x)^2 over the domain drops, for up to
//! [`ROUNDS`] rounds.
//!
//! Edges only, not corners: at a corner the third face's side often stands on a few points
//! (five on make_parts' bracket from its cloud), and the points shared with it outweigh them
//! (its corner 4.3e-4 -> 9.6e-4 of the diagonal off).

use super::{improve, Scored, SharpFunction};
use nalgebra::{Point3, Vector3};

/// Most rounds of sharing.
const ROUNDS: usize = 3;

/// A point whose normal is within this cosine (15 degrees) of its own side's gradient is its
/// face's, not the crease's, and is not shared.
const OWN_NORMAL_COS: f64 = 0.966;

/// The fit `first` (from `labels`, with its sum of F(x)^2 over `points`) with crease points
/// shared (module doc); `fit` fits a sharp function with the given (region, point index) pairs
/// added to the sides.
pub(super) fn refit(
    first: Scored,
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    labels: &[u32],
    flat: f64,
    fit: impl Fn(&[(u32, usize)]) -> Option<SharpFunction>,
) -> Scored {
    if first.1.sides.len() > 2 {
        return first;
    }
    let step = |f: &SharpFunction, extra: &Vec<(u32, usize)>| {
        let mut more = extra.clone();
        for e in cut_in(f, points, normals, labels, 2.0 * flat) {
            if !more.contains(&e) {
                more.push(e);
            }
        }
        if more.len() == extra.len() {
            return None;
        }
        let next = fit(&more)?;
        Some((more, next))
    };
    improve(first, Vec::new(), points, ROUNDS, step).0
}

/// (region of the side that gives F, point index) for every point on the crease (its normal
/// off its own side's gradient) that its own side fits within `near` and F misses by more.
fn cut_in(
    f: &SharpFunction,
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    labels: &[u32],
    near: f64,
) -> Vec<(u32, usize)> {
    let mut out = Vec::new();
    for (i, ((x, n), l)) in points.iter().zip(normals).zip(labels).enumerate() {
        let Some(own) = f.sides.iter().position(|s| s.region == *l) else {
            continue;
        };
        let v = f.side_values(x);
        let (value, k) = f.pick(&v[..f.sides.len()]);
        if k == own || v[own].abs() > near || value.abs() <= near {
            continue;
        }
        let g = f.sides[own].poly.value_and_gradient(x).1;
        if n.dot(&g) < OWN_NORMAL_COS * n.norm() * g.norm() {
            out.push((f.sides[k].region, i));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bore_s_rim_points_are_fitted_by_the_wall_s_side_too() {
        // One crease cell of make_parts' corner block from its mesh (tolerance 0.01655),
        // where the bore meets the oblique face (region 3): points (x, y, z), normals and
        // labels as the features gave them. The rim's vertices carry the face's label and the
        // mean of the two faces' normals; the bore's side, fitted to its nine points of the
        // wall alone, passed 0.1 outside them, and F took its value there.
        let cell = [
            (50.17332, 41.10603, 26.46909, 0.3006, -0.8059, 0.5101, 4),
            (50.46305, 41.29581, 26.58053, 0.4217, -0.4961, 0.7590, 4),
            (51.48117, 41.34825, 26.42014, 0.3357, -0.1888, 0.9229, 3),
            (49.80911, 41.52522, 27.46475, 0.6472, 0.0321, 0.7617, 3),
            (50.79130, 41.25328, 26.38247, 0.3535, -0.4953, 0.7935, 4),
            (49.84003, 41.18060, 26.77094, 0.3765, -0.8074, 0.4542, 4),
            (50.50662, 41.03146, 26.16724, 0.2220, -0.7972, 0.5614, 4),
            (50.10166, 40.88251, 26.14135, 0.2660, -0.8024, 0.5343, 4),
            (51.07596, 41.15390, 26.20121, 0.2475, -0.4724, 0.8459, 4),
            (51.48115, 41.02704, 26.02365, 0.1392, -0.5329, 0.8346, 4),
            (50.02212, 42.60894, 26.33602, 0.4719, 0.5898, 0.6553, 3),
            (52.53643, 40.90328, 26.06082, 0.2192, 0.0569, 0.9740, 4),
            (49.77880, 42.27182, 26.81462, 0.4719, 0.5898, 0.6553, 3),
            (49.73606, 43.02345, 26.16893, 0.4719, 0.5898, 0.6553, 3),
            (51.88635, 41.22139, 26.24257, 0.2387, -0.2618, 0.9351, 3),
            (50.43550, 42.16463, 26.43826, 0.4719, 0.5898, 0.6553, 3),
            (50.41948, 41.56015, 26.99383, 0.5499, -0.1109, 0.8279, 3),
            (50.47700, 42.48907, 26.11639, 0.4718, 0.5898, 0.6553, 3),
            (49.79396, 41.89852, 27.13969, 0.5860, 0.3256, 0.7420, 3),
            (50.12728, 42.91848, 25.98173, 0.4719, 0.5898, 0.6553, 3),
            (50.75575, 41.81987, 26.51798, 0.4846, 0.2569, 0.8362, 3),
            (50.09914, 41.91599, 26.90423, 0.5482, 0.2570, 0.7959, 3),
            (51.35004, 41.61109, 26.27798, 0.4845, 0.2569, 0.8362, 3),
            (51.13572, 42.00378, 26.07888, 0.4718, 0.5898, 0.6553, 3),
            (51.07599, 41.47510, 26.59770, 0.4276, -0.1130, 0.8969, 3),
        ];
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        for &(x, y, z, a, b, c, r) in &cell {
            p.push(Point3::new(x, y, z));
            n.push(Vector3::new(a, b, c));
            l.push(r);
        }
        let (tol, h) = (0.01655, 1.655);
        let flat = 0.5 * tol;
        let fit =
            |extra: &[(u32, usize)]| SharpFunction::fit_labelled(&p, &n, &l, h, 0.3, flat, extra);
        let worst = |f: &SharpFunction| p.iter().map(|x| f.value(x).abs()).fold(0.0, f64::max);
        let (once, labels) = super::super::relabel::refit(fit(&[]).unwrap(), &p, &l, flat, |l| {
            SharpFunction::fit_labelled(&p, &n, l, h, 0.3, flat, &[])
        });
        let once = once.1;
        assert!(worst(&once) > 4.0 * tol, "{}", worst(&once));
        let (_, f) = refit(
            super::super::scored(once.clone(), &p),
            &p,
            &n,
            &labels,
            flat,
            |extra| SharpFunction::fit_labelled(&p, &n, &labels, h, 0.3, flat, extra),
        );
        assert!(
            worst(&f) < 2.0 * tol,
            "{} (once: {})",
            worst(&f),
            worst(&once)
        );
        // The same through the public fit.
        let g = SharpFunction::fit(&p, &n, &l, h, 0.3, flat).unwrap();
        assert!(worst(&g) < 2.0 * tol, "{}", worst(&g));
    }

    #[test]
    fn only_points_off_their_own_face_s_normal_are_shared() {
        // A convex edge along y, the solid x <= 0, z <= 0: face z = 0 (region 0) over x < 0,
        // and face 1 sampled 0.05 inside its true place x = 0 at the edge and tilted 6
        // degrees, x = -0.05 + 0.1 z, so that its side cuts into face 0 over -0.05 < x < 0:
        // F misses those points of face 0 by up to 0.04. With face 0's normal they are
        // face 0's and not shared; with the mean of the two faces' normals they are.
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..5 {
            let y = 0.1 * j as f64;
            for i in 1..=20 {
                p.push(Point3::new(-0.01 * i as f64, y, 0.0));
                n.push(Vector3::z());
                l.push(0);
            }
            for i in 1..=10 {
                let z = -0.05 * i as f64;
                p.push(Point3::new(-0.05 + 0.1 * z, y, z));
                n.push(Vector3::new(1.0, 0.0, -0.1).normalize());
                l.push(1);
            }
        }
        let flat = 0.002;
        let f = SharpFunction::fit_labelled(&p, &n, &l, 1.0, 0.3, flat, &[]).unwrap();
        let missed = p.iter().filter(|x| f.value(x).abs() > 2.0 * flat).count();
        assert_eq!(missed, 20, "four points of face 0 in each of five rows");
        assert!(cut_in(&f, &p, &n, &l, 2.0 * flat).is_empty());
        let blend = (Vector3::z() + Vector3::x()).normalize();
        for (x, ni) in p.iter().zip(n.iter_mut()) {
            if x.z == 0.0 && x.x > -0.05 {
                *ni = blend;
            }
        }
        let shared = cut_in(&f, &p, &n, &l, 2.0 * flat);
        assert_eq!(shared.len(), 20);
        assert!(shared.iter().all(|e| e.0 == 1));
    }
}
