//! The points of a crease domain given to the side whose face they lie on, and the sides
//! fitted again: a point's region comes from its estimated normal, which beside a crease (and
//! across all of a face narrower than the normal's neighbourhood, as a chamfer) is the other
//! face's as often as its own.
//!
//! With the sides f_i fitted once, a point x whose own side misses it (|f_own(x)| > 2 flat)
//! while another passes within 2 flat is given the region of the side nearest to it (smallest
//! |f_i(x)|); the sides are fitted again from the new groups, and the fit kept when its sum of
//! F(x)^2 over the domain's points is smaller, for up to [`ROUNDS`] rounds. A point near no side
//! (another face's, or noise) keeps its label; near the crease, where both sides pass within 2
//! flat, nothing moves.
//!
//! make_parts' block from its cloud: crease distance max 9.0e-4 -> 7.7e-4 of the diagonal;
//! over the 22 inputs of make_parts and `scripts/extra_parts.py` the crease p95 is smaller on
//! 18, and on freshly sampled clouds (seed 11) the max on 6 of 11 (flange 7.5e-4 -> 3.7e-4)
//! and the p95 on 9, none worse (docs/BENCHMARKS.md).
//!
//! Not yet: a side that bent to the other face's points passes near them, so they are not
//! moved (make_parts' block beside its 1.5 mm chamfer, two chamfer points with the top's
//! label at the far edge of its 0.76 mm strip: the top's quadratic bends 0.07 over the
//! chamfer).

use super::{improve, scored, Scored, SharpFunction};
use nalgebra::Point3;

/// Most relabelling rounds.
const ROUNDS: usize = 3;

/// The fit of `first` improved by relabelling (module doc), for up to [`ROUNDS`] rounds while
/// labels change and the fit improves; `fit` fits a sharp function from new labels. Returns
/// the fit, with its sum of F(x)^2 over `points`, and the labels it was fitted from.
pub(super) fn refit(
    first: SharpFunction,
    points: &[Point3<f64>],
    labels: &[u32],
    flat: f64,
    fit: impl Fn(&[u32]) -> Option<SharpFunction>,
) -> (Scored, Vec<u32>) {
    improve(
        scored(first, points),
        labels.to_vec(),
        points,
        ROUNDS,
        |f, labels| {
            let new = relabelled(f, points, labels, 2.0 * flat)?;
            let next = fit(&new)?;
            Some((new, next))
        },
    )
}

/// The labels with every point off its own side but near another given the nearest side's
/// region (module doc); `None` when none changes.
fn relabelled(
    f: &SharpFunction,
    points: &[Point3<f64>],
    labels: &[u32],
    near: f64,
) -> Option<Vec<u32>> {
    let mut out = labels.to_vec();
    let mut changed = false;
    for (x, l) in points.iter().zip(out.iter_mut()) {
        let Some(own) = f.sides.iter().position(|s| s.region == *l) else {
            continue;
        };
        let v = f.side_values(x).map(f64::abs);
        let v = &v[..f.sides.len()];
        if v[own] <= near {
            continue;
        }
        let mut k = own;
        for (i, &vi) in v.iter().enumerate() {
            if vi < v[k] {
                k = i;
            }
        }
        if v[k] <= near {
            *l = f.sides[k].region;
            changed = true;
        }
    }
    changed.then_some(out)
}

#[cfg(test)]
mod tests {
    use super::super::Combine;
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn points_of_one_face_labelled_as_the_other_s_are_given_back() {
        // A convex edge along z, the solid x <= 0, y <= 0: face x = 0 (region 0) over y < 0,
        // 1.5 wide, and a narrow face y = 0 (region 1) over x < 0, 0.5 wide, points 0.1 apart.
        // Face 0's points up to 0.4 from the edge carry region 1 (their normals estimated
        // across the narrow face), too many for side 1's residual cut: fitted once, the sharp
        // function misses the points by up to 0.5 and takes the edge for concave.
        let (mut p, mut n, mut l) = (Vec::new(), Vec::new(), Vec::new());
        for i in 1..=15 {
            for j in 0..6 {
                let (a, z) = (0.1 * i as f64, 0.2 * j as f64);
                p.push(Point3::new(0.0, -a, z));
                n.push(Vector3::x());
                l.push(if i <= 4 { 1 } else { 0 });
                if i <= 5 {
                    p.push(Point3::new(-a, 0.0, z));
                    n.push(Vector3::y());
                    l.push(1);
                }
            }
        }
        let flat = 0.005;
        let worst = |f: &SharpFunction| p.iter().map(|x| f.value(x).abs()).fold(0.0, f64::max);
        let once = SharpFunction::fit_labelled(&p, &n, &l, 1.5, 0.3, flat, &[]).unwrap();
        let f = SharpFunction::fit(&p, &n, &l, 1.5, 0.3, flat).unwrap();
        assert_eq!(f.combination().0, Combine::Max);
        assert!(worst(&f) < 1e-9, "{} (once: {})", worst(&f), worst(&once));
    }
}
