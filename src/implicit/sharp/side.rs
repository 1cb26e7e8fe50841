//! One side of a sharp function: the height polynomial of one region's points in a crease
//! cell ([`super::SharpFunction::fit`]), a plane or a quadratic, fitted robustly against the
//! few points of the other face that carry this region's label beside the crease.

use super::MIN_SIDE;
use crate::implicit::poly::{Degree, Frame, HeightPoly};
use nalgebra::{Point3, Vector3};

/// Fewest points for a quadratic side (a plane below; [`HeightPoly::fit`] needs 9).
const QUADRATIC_FROM: usize = 9;

/// One side's height polynomial: a plane when it leaves no point farther than `flat` or when a
/// quadratic does not follow the points significantly better ([`plane_suffices`]), else a
/// quadratic (from [`QUADRATIC_FROM`] points), chosen for the points within three median
/// residuals of the side's plane; fitted, then fitted again without the points farther than
/// three times the median residual and than `flat` (a few points of the other face given to
/// this region beside the crease tilt it otherwise), the degree chosen again.
pub(super) fn fit_side(
    p: &[Point3<f64>],
    n: &[Vector3<f64>],
    scale: f64,
    min_normal_cos: f64,
    flat: f64,
) -> Option<HeightPoly> {
    let frame = side_frame(p, n, scale, min_normal_cos)?;
    let plane = HeightPoly::fit(p, frame, Degree::Linear).ok()?;
    let pr: Vec<f64> = p.iter().map(|x| plane.value(x).abs()).collect();
    if pr.iter().all(|&r| r <= flat) {
        return Some(plane);
    }
    // Points far off the side's plane are the other face's, labelled as this side's beside
    // the crease: they are left out before the degree is chosen, or the quadratic bends to
    // them (make_parts' block from its cloud: three points of its chamfer in the top face's
    // group bent the top side 0.2 mm down at the chamfer).
    let pcut = (3.0 * median(pr.iter().copied())).max(flat);
    let near = within(p, &pr, pcut);
    // Not when that leaves too few points for the quadratic a curved side needs (as for the
    // second fit below; the stepped shaft of `scripts/extra_parts.py` from its mesh: crease
    // distance 8.4e-4 of the diagonal at its end face's rim with the cut made, 7.0e-4 without).
    let enough =
        near.len() >= QUADRATIC_FROM || (p.len() < QUADRATIC_FROM && near.len() >= MIN_SIDE);
    // The plane through the points fitted again only when some were set aside.
    let plane = if enough && near.len() < p.len() {
        HeightPoly::fit(&near, frame, Degree::Linear).ok()?
    } else {
        plane
    };
    let p: &[Point3<f64>] = if enough { &near } else { p };
    let first = side_poly(p, plane, flat)?;
    let r: Vec<f64> = p.iter().map(|x| first.value(x).abs()).collect();
    let cut = (3.0 * median(r.iter().copied())).max(flat);
    let kept = within(p, &r, cut);
    if kept.len() == p.len() || kept.len() < MIN_SIDE {
        return Some(first);
    }
    let Some(second) = HeightPoly::fit(&kept, frame, Degree::Linear)
        .ok()
        .and_then(|plane| side_poly(&kept, plane, flat))
    else {
        return Some(first);
    };
    // A second fit of a lower degree because too few points are left for a quadratic is kept
    // only when it follows the kept points at least as well as the first: a plane through a
    // curved strip (nine points on a cylinder of radius 7 over 35 degrees, one of them cut)
    // misses it by a third of a millimetre, while a flat side rid of the other face's point
    // is exact.
    if first.degree == Degree::Quadratic && kept.len() < QUADRATIC_FROM {
        let worst = |h: &HeightPoly| kept.iter().map(|x| h.value(x).abs()).fold(0.0, f64::max);
        if worst(&second) > worst(&first) {
            return Some(first);
        }
    }
    Some(second)
}

/// The points of `p` whose residual (`r`, in the same order) is at most `cut`.
fn within(p: &[Point3<f64>], r: &[f64], cut: f64) -> Vec<Point3<f64>> {
    p.iter()
        .zip(r)
        .filter(|(_, &ri)| ri <= cut)
        .map(|(x, _)| *x)
        .collect()
}

/// `plane` (the plane through `p`) when it is flat within `flat`, when there are too few
/// points for a quadratic, or when [`plane_suffices`]; else the quadratic in its frame.
fn side_poly(p: &[Point3<f64>], plane: HeightPoly, flat: f64) -> Option<HeightPoly> {
    let frame = plane.frame;
    if p.len() < QUADRATIC_FROM || p.iter().all(|x| plane.value(x).abs() <= flat) {
        return Some(plane);
    }
    let Ok(quad) = HeightPoly::fit(p, frame, Degree::Quadratic) else {
        return Some(plane);
    };
    Some(if plane_suffices(p, &plane, &quad) {
        plane
    } else {
        quad
    })
}

/// The 1 % point of F(3, dof), for dof = 1 to 30 (the F distribution's quantile, as tabulated
/// by `scipy.stats.f.ppf(0.99, 3, dof)`).
const F3_1PCT: [f64; 30] = [
    5403.35, 99.17, 29.46, 16.69, 12.06, 9.78, 8.45, 7.59, 6.99, 6.55, 6.22, 5.95, 5.74, 5.56,
    5.42, 5.29, 5.19, 5.09, 5.01, 4.94, 4.87, 4.82, 4.77, 4.72, 4.68, 4.64, 4.60, 4.57, 4.54, 4.51,
];

/// The 1 % point of F(3, dof) beyond the table: at 30, 40, 60, 120 and infinitely many degrees
/// of freedom, interpolated linearly in 1/dof (the usual reading of an F table between its
/// rows).
const F3_1PCT_TAIL: [(f64, f64); 5] = [
    (30.0, 4.51),
    (40.0, 4.31),
    (60.0, 4.13),
    (120.0, 3.95),
    (f64::INFINITY, 3.78),
];

/// The F statistic under which a side's plane is kept over its quadratic ([`plane_suffices`]):
/// the 1 % point of F(3, dof). Few points need a large F to call the quadratic's bend real: a
/// plane's nine points (dof 3) need 29.5, thirty-six need 4.5.
fn plane_f(dof: usize) -> f64 {
    if dof == 0 {
        return f64::INFINITY;
    }
    if let Some(f) = F3_1PCT.get(dof - 1) {
        return *f;
    }
    let x = 1.0 / dof as f64;
    F3_1PCT_TAIL
        .windows(2)
        .find(|w| dof as f64 <= w[1].0)
        .map(|w| {
            let (x0, x1) = (1.0 / w[0].0, 1.0 / w[1].0);
            w[0].1 + (w[1].1 - w[0].1) * (x0 - x) / (x0 - x1)
        })
        .unwrap_or(F3_1PCT_TAIL[F3_1PCT_TAIL.len() - 1].1)
}

/// True when the quadratic's three extra terms do not explain significantly more of the points
/// than the plane (the F test of nested least-squares models):
///
/// ```text
/// F = ((RSS_plane - RSS_quad) / 3) / (RSS_quad / (n - 6)) < plane_f(n - 6)
/// ```
///
/// On a noisy cloud the points of a flat face scatter a tolerance or so (the tolerance is three
/// times the noise), so a plane rarely passes within a fraction of it: the quadratic then bent
/// to the noise of the strip of points beside the crease, and extended to the crease it missed
/// it (make_parts' block from its cloud: crease distance p95 3.0e-4 of the diagonal, 2.0e-4
/// with the test; over the eleven clouds of `scripts/extra_parts.py` and make_parts 1.6e-4 to
/// 4.9e-4 before, 1.0e-4 to 3.4e-4 after).
fn plane_suffices(p: &[Point3<f64>], plane: &HeightPoly, quad: &HeightPoly) -> bool {
    let rss = |h: &HeightPoly| p.iter().map(|x| h.value(x).powi(2)).sum::<f64>();
    let (rp, rq) = (rss(plane), rss(quad));
    let Some(dof) = p.len().checked_sub(6).filter(|&d| d >= 1) else {
        return true;
    };
    if rq <= 0.0 {
        return rp <= 0.0;
    }
    ((rp - rq) / 3.0) / (rq / dof as f64) < plane_f(dof)
}

/// The height frame of one side's points: along their mean normal, when every normal is within
/// `min_normal_cos` of it. Failing that, the frame of the points whose normals are within it of
/// the mean of the unit normals, the others left out (a normal estimated across the crease, or
/// a point of the other face given this region's label: one in twenty beside the crease of a
/// noisy cloud), as long as at least [`MIN_SIDE`] points and [`SIDE_KEEP`] of the side remain.
/// The left-out points are still fitted (the residual cut of [`fit_side`] drops the other
/// face's) and still count in the cell's assessment.
fn side_frame(
    p: &[Point3<f64>],
    n: &[Vector3<f64>],
    scale: f64,
    min_normal_cos: f64,
) -> Option<Frame> {
    if let Some(f) = Frame::from_normals(p, n, scale, min_normal_cos) {
        return Some(f);
    }
    let mean: Vector3<f64> = n.iter().map(|m| m.try_normalize(1e-12).unwrap_or(*m)).sum();
    let mean = mean.try_normalize(1e-12)?;
    let (kp, kn): (Vec<Point3<f64>>, Vec<Vector3<f64>>) = p
        .iter()
        .zip(n)
        .filter(|(_, m)| m.dot(&mean) >= min_normal_cos * m.norm())
        .map(|(x, m)| (*x, *m))
        .unzip();
    if kp.len() < MIN_SIDE || (kp.len() as f64) < SIDE_KEEP * p.len() as f64 {
        return None;
    }
    Frame::from_normals(&kp, &kn, scale, min_normal_cos)
}

/// The share of a side's points whose normals must agree for [`side_frame`] to drop the rest.
const SIDE_KEEP: f64 = 0.8;

/// Median of the values (0 for none).
pub(super) fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.collect();
    if v.is_empty() {
        return 0.0;
    }
    let m = v.len() / 2;
    *v.select_nth_unstable_by(m, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_curved_side_of_nine_points_stays_quadratic_when_one_is_cut() {
        // Nine points on a cylinder of radius 7 (axis x) over 35 degrees, in two rows 0.75
        // apart (a mesh's strip beside a shoulder), one pushed 0.05 off: the second fit leaves
        // it out and has eight points, too few for a quadratic; a plane through the strip
        // missed the others by 0.3.
        let r = 7.0;
        let (mut p, n) = strip(|x, t| {
            let a = (-17.5 + 35.0 * t).to_radians();
            let m = Vector3::new(0.0, a.sin(), a.cos());
            (Point3::new(x, 0.0, 0.0) + m * r, m)
        });
        p[2] += n[2] * 0.05;
        let h = fit_side(&p, &n, 2.4, 0.3, 0.01).unwrap();
        let worst = worst_but(&h, &p, 2);
        assert!(worst < 0.03, "{worst}");
    }

    #[test]
    fn a_curved_side_sampled_unevenly_stays_quadratic() {
        // Nine points on a cylinder of radius 7 in two rows, seven near the middle line (a
        // mesh's samples cluster) and two 8 degrees out: the plane's residuals are uneven, and
        // none of the side's own points may be cut from it before its degree is chosen.
        let (p, n) = cylinder_rows(&[
            (0.0, &[-8.0, -0.3, -0.1, 0.1, 0.3, 8.0]),
            (0.75, &[-0.4, 0.0, 0.4]),
        ]);
        let h = fit_side(&p, &n, 2.4, 0.3, 0.001).unwrap();
        let worst = p.iter().map(|x| h.value(x).abs()).fold(0.0, f64::max);
        assert!(worst < 0.003, "{worst} {:?}", h.degree);
    }

    #[test]
    fn a_curved_side_keeps_its_points_off_its_plane_when_too_few_would_remain() {
        // Ten points on a cylinder of radius 7 (axis x), eight in two rows within half a degree
        // of the middle line and two 10 degrees out between them (a mesh's staggered strip):
        // the two are beyond three median residuals of the side's plane, and setting them
        // aside would leave eight, too few for the quadratic the side needs (the plane through
        // the eight misses them by 0.1).
        let (p, n) = cylinder_rows(&[
            (0.0, &[-0.4, -0.15, 0.15, 0.4]),
            (0.375, &[-10.0, 10.0]),
            (0.75, &[-0.4, -0.15, 0.15, 0.4]),
        ]);
        let h = fit_side(&p, &n, 2.4, 0.3, 0.001).unwrap();
        let worst = p.iter().map(|x| h.value(x).abs()).fold(0.0, f64::max);
        assert!(worst < 0.003, "{worst} {:?}", h.degree);
    }

    #[test]
    fn a_flat_side_of_nine_points_drops_the_other_face_s_point() {
        // Nine points of the plane z = 0 in two rows (as above, flattened), one of them
        // 0.05 off it (a point of the other face given this region): the second fit, on the
        // eight others, is a plane, and exact; the quadratic through all nine is not.
        let (mut p, n) = strip(|x, t| (Point3::new(x, -2.0 + 4.0 * t, 0.0), Vector3::z()));
        p[2].z += 0.05;
        let h = fit_side(&p, &n, 2.4, 0.3, 0.01).unwrap();
        let worst = worst_but(&h, &p, 2);
        assert!(worst < 1e-9, "{worst}");
    }

    #[test]
    fn the_plane_s_f_threshold_is_the_one_percent_point_of_f_3_dof() {
        assert_eq!(plane_f(3), 29.46);
        assert_eq!(plane_f(30), 4.51);
        assert!((plane_f(48) - 4.22).abs() < 0.01, "{}", plane_f(48));
        assert!((plane_f(1000) - 3.80).abs() < 0.01, "{}", plane_f(1000));
        let f: Vec<f64> = (1..2000).map(plane_f).collect();
        assert!(f.windows(2).all(|w| w[1] <= w[0]));
        assert!(plane_f(usize::MAX) >= 3.78 && plane_f(0).is_infinite());
    }

    /// A 6 x 6 grid over [-1, 1]^2 placed by `at(u, v, e)`, `e` a deterministic noise in
    /// [-1, 1].
    fn noisy_patch(
        at: impl Fn(f64, f64, f64) -> (Point3<f64>, Vector3<f64>),
    ) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let mut seed = 12345u64;
        let mut noise = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        (0..36)
            .map(|k| {
                let (u, v) = ((k % 6) as f64 / 2.5 - 1.0, (k / 6) as f64 / 2.5 - 1.0);
                at(u, v, noise())
            })
            .unzip()
    }

    #[test]
    fn a_noisy_flat_side_stays_a_plane() {
        // A flat face scattered by +-0.01 (a tolerance of a noisy cloud), `flat` half of that:
        // no plane passes within it, but a quadratic follows the noise no better than chance,
        // and bent to it would miss the face where it is extended to a crease.
        let (p, n) = noisy_patch(|u, v, e| (Point3::new(u, v, 0.01 * e), Vector3::z()));
        let h = fit_side(&p, &n, 1.0, 0.3, 0.005).unwrap();
        assert_eq!(h.degree, Degree::Linear);
        let far = h.value(&Point3::new(2.0, 2.0, 0.0)).abs();
        assert!(far < 0.01, "{far}");
    }

    #[test]
    fn a_noisy_flat_side_leaves_out_the_other_face_s_points_before_its_degree() {
        // A strip of the flat face as above, 0.5 wide beside its edge v = 0.5, and three points
        // 0.15 to 0.22 past the edge on a 45-degree chamfer (the other face's points with this
        // face's label, as beside make_parts' block's chamfer): the plane through all of them
        // tilts, and the quadratic through all bends to them and keeps them in its trimmed fit.
        let (p, n) =
            noisy_patch(|u, v, e| (Point3::new(u, 0.25 + v / 4.0, 0.01 * e), Vector3::z()));
        let (mut p, mut n): (Vec<_>, Vec<_>) =
            p.into_iter().zip(n).filter(|(x, _)| x.y <= 0.5).unzip();
        let own = p.len();
        for (u, d) in [(-0.5, 0.15), (0.1, 0.2), (0.7, 0.22)] {
            p.push(Point3::new(u, 0.5 + d, -d));
            n.push(Vector3::z());
        }
        let h = fit_side(&p, &n, 1.0, 0.3, 0.005).unwrap();
        let worst = p[..own]
            .iter()
            .map(|x| h.value(x).abs())
            .fold(0.0, f64::max);
        let past = h.value(&Point3::new(0.0, 0.6, 0.0)).abs();
        assert!(
            worst < 0.015 && past < 0.015,
            "{worst} {past} {:?}",
            h.degree
        );
    }

    #[test]
    fn a_curved_noisy_side_stays_quadratic() {
        // A cylinder of radius 7 (sagitta 0.07 over the patch) with the same noise, ten times
        // smaller: the quadratic follows it significantly better than a plane.
        let (p, n) = noisy_patch(|u, v, e| {
            let m = Vector3::new(0.0, (v / 7.0).sin(), (v / 7.0).cos());
            (Point3::new(u, 0.0, -7.0) + m * (7.0 + 0.001 * e), m)
        });
        let h = fit_side(&p, &n, 1.0, 0.3, 0.0005).unwrap();
        assert_eq!(h.degree, Degree::Quadratic);
        let worst = p.iter().map(|x| h.value(x).abs()).fold(0.0, f64::max);
        assert!(worst < 0.003, "{worst}");
    }

    /// Points on the cylinder of radius 7 about the x axis with their normals: rows at x, each
    /// at the given angles (degrees) from the top line (z = 7).
    fn cylinder_rows(rows: &[(f64, &[f64])]) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        rows.iter()
            .flat_map(|&(x, d)| d.iter().map(move |d| (x, d.to_radians())))
            .map(|(x, a)| {
                let m = Vector3::new(0.0, a.sin(), a.cos());
                (Point3::new(x, 0.0, 0.0) + m * 7.0, m)
            })
            .unzip()
    }

    /// Nine points in two rows, five at x = 0 and four at x = 0.75, placed by `at(x, t)`
    /// (t from 0 to 1 along each row), with their normals.
    fn strip(
        at: impl Fn(f64, f64) -> (Point3<f64>, Vector3<f64>),
    ) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        [(0.0, 5), (0.75, 4)]
            .into_iter()
            .flat_map(|(x, k)| (0..k).map(move |j| (x, j as f64 / (k - 1) as f64)))
            .map(|(x, t)| at(x, t))
            .unzip()
    }

    /// The largest |h| over `p` but its point `skip`.
    fn worst_but(h: &HeightPoly, p: &[Point3<f64>], skip: usize) -> f64 {
        p.iter()
            .enumerate()
            .filter(|&(i, _)| i != skip)
            .map(|(_, x)| h.value(x).abs())
            .fold(0.0, f64::max)
    }
}
