//! Local quadratic height functions around one point (seed 004 eq. 1 in the frame of a normal),
//! the measuring stick of the segmentation: how far a point lies from a smooth surface through
//! its neighbours, and that surface's normal.
//!
//! In the frame (origin c, axis w along the given normal, lengths divided by the neighbourhood
//! radius L) the points are fitted by W = h(U, V), a quadratic (6 coefficients) when there are at
//! least 9 points, else a plane. A smooth surface sampled densely is described by it up to its
//! cubic terms, far below a scanner's noise; a neighbourhood straddling a crease is not, by
//! about the depth of the kink across it.

use crate::implicit::poly::{Degree, Frame, HeightPoly};
use nalgebra::{Point3, Vector3};

/// Fewest labelled points of one region among a point's neighbours for that region to be
/// fitted there (below a plane fit is not trustworthy).
pub const MIN_SUPPORT: usize = 6;

/// A quadratic (or planar) height function fitted around a point.
#[derive(Debug, Clone)]
pub struct LocalQuadric {
    poly: HeightPoly,
    /// Number of points fitted and of coefficients.
    n: usize,
    terms: usize,
}

impl LocalQuadric {
    /// Fits `points` in the frame at `centre` with axis `normal`. `None` when there are fewer
    /// than 3 points, they all coincide, or the fit is singular.
    pub fn fit(centre: Point3<f64>, normal: Vector3<f64>, points: &[Point3<f64>]) -> Option<Self> {
        Self::fit_with(centre, normal, points, 9)
    }

    /// [`LocalQuadric::fit`] with a plane below `quadratic_from` points (a quadratic fitted to
    /// few points on one side of where it is evaluated extrapolates with several times their
    /// scatter).
    pub fn fit_with(
        centre: Point3<f64>,
        normal: Vector3<f64>,
        points: &[Point3<f64>],
        quadratic_from: usize,
    ) -> Option<Self> {
        let radius = points
            .iter()
            .map(|p| (p - centre).norm())
            .fold(0.0, f64::max);
        let frame = Frame::new(centre, normal, radius)?;
        let degree = if points.len() >= quadratic_from.max(9) {
            Degree::Quadratic
        } else {
            Degree::Linear
        };
        let poly = HeightPoly::fit(points, frame, degree).ok()?;
        Some(LocalQuadric {
            poly,
            n: points.len(),
            terms: degree.terms(),
        })
    }

    /// Approximate signed distance of `x` from the fitted surface (positive along the normal).
    pub fn distance(&self, x: &Point3<f64>) -> f64 {
        self.poly.value(x)
    }

    /// The approximate signed distance and its gradient at `x`.
    pub fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        self.poly.value_and_gradient(x)
    }

    /// Unit normal of the fitted surface above `x`, on the side of the frame's normal.
    pub fn normal(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.poly
            .value_and_gradient(x)
            .1
            .try_normalize(0.0)
            .unwrap_or(self.poly.frame.w)
    }

    /// Root-mean-square distance of `points` (those fitted) from the surface, with the fitted
    /// coefficients' degrees of freedom taken out.
    pub fn rms(&self, points: &[Point3<f64>]) -> f64 {
        let ss: f64 = points.iter().map(|p| self.distance(p).powi(2)).sum();
        (ss / (self.n as f64 - self.terms as f64).max(1.0)).sqrt()
    }
}

/// Fits a quadratic to the points of `idx` carrying label `l` (at least [`MIN_SUPPORT`]),
/// centred at `centre`, its axis the mean of their normals.
pub fn region_fit(
    centre: Point3<f64>,
    idx: &[usize],
    label: &[u32],
    l: u32,
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    need: Support,
) -> Option<LocalQuadric> {
    let mut pts = Vec::with_capacity(idx.len());
    let mut axis = Vector3::zeros();
    for &j in idx {
        if label[j] == l {
            pts.push(points[j]);
            // Normals summed on one side, so that any flipped by the estimate cannot cancel
            // the axis (a guard: no flipped normals were seen on the test parts).
            let n = normals[j];
            axis += if axis.dot(&n) < 0.0 { -n } else { n };
        }
    }
    if pts.len() < need.points {
        return None;
    }
    if need.spread > 0.0 && spread(&pts, &axis) < need.spread {
        return None;
    }
    LocalQuadric::fit_with(centre, axis, &pts, need.quadratic_from)
}

/// [`region_fit`] fitted twice: the second time without the points farther than `trim` from
/// the first fit, so that a handful of points carried past a crease into the region does not
/// tilt its surface toward them.
#[allow(clippy::too_many_arguments)]
pub fn region_fit_trimmed(
    centre: Point3<f64>,
    idx: &[usize],
    label: &[u32],
    l: u32,
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    need: Support,
    trim: f64,
) -> Option<LocalQuadric> {
    let first = region_fit(centre, idx, label, l, points, normals, need)?;
    let kept: Vec<usize> = idx
        .iter()
        .copied()
        .filter(|&j| label[j] == l && first.distance(&points[j]).abs() <= trim)
        .collect();
    if kept.len() < need.points {
        return Some(first);
    }
    region_fit(centre, &kept, label, l, points, normals, need).or(Some(first))
}

/// What a region's points around a candidate must offer for a fit there.
#[derive(Debug, Clone, Copy)]
pub struct Support {
    /// Fewest points.
    pub points: usize,
    /// Fewest points for a quadratic (a plane below).
    pub quadratic_from: usize,
    /// Smallest ratio of the points' narrower to wider extent across `axis` (0: any): points
    /// strung along a line (a crease the region crept along) leave a plane free to turn about
    /// that line.
    pub spread: f64,
}

/// Band assignment, merge test and normals: a quadratic from [`MIN_SUPPORT`] points.
pub const FIT: Support = Support {
    points: MIN_SUPPORT,
    quadratic_from: 9,
    spread: 0.0,
};

/// The principal spreads of `pts` about their centroid: the eigenvalues of their scatter
/// matrix, smallest first, with the unit axes (`None` for no points or a non-finite scatter).
pub fn principal_axes(pts: &[Point3<f64>]) -> Option<([f64; 3], [Vector3<f64>; 3])> {
    if pts.is_empty() {
        return None;
    }
    let c = pts.iter().map(|p| p.coords).sum::<Vector3<f64>>() / pts.len() as f64;
    let mut m = nalgebra::Matrix3::zeros();
    for p in pts {
        let d = p.coords - c;
        m += d * d.transpose();
    }
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let e = nalgebra::SymmetricEigen::new(m);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
    Some((
        idx.map(|k| e.eigenvalues[k]),
        idx.map(|k| e.eigenvectors.column(k).into_owned()),
    ))
}

/// Ratio of the smaller to the larger standard deviation of `pts` across `axis`.
pub fn spread(pts: &[Point3<f64>], axis: &Vector3<f64>) -> f64 {
    let Some(frame) = Frame::new(pts[0], *axis, 1.0) else {
        return 0.0;
    };
    let (mut su, mut sv, mut suu, mut suv, mut svv) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let l = frame.local(p);
        su += l.x;
        sv += l.y;
        suu += l.x * l.x;
        suv += l.x * l.y;
        svv += l.y * l.y;
    }
    let n = pts.len() as f64;
    let (cuu, cuv, cvv) = (
        suu / n - (su / n).powi(2),
        suv / n - su * sv / (n * n),
        svv / n - (sv / n).powi(2),
    );
    let tr = 0.5 * (cuu + cvv);
    let disc = (0.25 * (cuu - cvv).powi(2) + cuv * cuv).sqrt();
    let (hi, lo) = (tr + disc, (tr - disc).max(0.0));
    if hi <= 0.0 {
        return 0.0;
    }
    (lo / hi).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch(f: impl Fn(f64, f64) -> f64) -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        for i in -3..=3 {
            for j in -3..=3 {
                let (x, y) = (i as f64 * 0.1, j as f64 * 0.1);
                v.push(Point3::new(x, y, f(x, y)));
            }
        }
        v
    }

    #[test]
    fn smooth_surface_fits_a_kink_does_not() {
        let smooth = patch(|x, y| 0.5 * x * x - 0.2 * y * y);
        let q = LocalQuadric::fit(Point3::origin(), Vector3::z(), &smooth).unwrap();
        // Exact up to the fit's tiny ridge on the quadratic terms.
        assert!(q.rms(&smooth) < 1e-6, "{}", q.rms(&smooth));
        let n = q.normal(&Point3::new(0.1, 0.0, 0.005));
        assert!((n - Vector3::new(-0.1, 0.0, 1.0).normalize()).norm() < 1e-5);
        let kink = patch(|x, _| x.abs());
        let q = LocalQuadric::fit(Point3::origin(), Vector3::z(), &kink).unwrap();
        assert!(q.rms(&kink) > 0.01, "{}", q.rms(&kink));
    }
}
