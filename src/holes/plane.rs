//! Projection of a hole's ring onto a plane, and the check that the projection does not fold.
//!
//! Seed 000 eq. 6-7 (mean plane): centre `P_c = sum P_i / n`, normal `N_u = sum N_i / |sum N_i|`
//! (the mean of the ring's vertex normals). Seed 002 section 3.2 lists the same mean loop normal,
//! the scanning direction, and a user-chosen direction for loops that fold under the first two.
//! Here the candidates are tried in order: a user direction (when given), the mean normal
//! (eq. 7), the ring's area vector (Newell's sum of cross products, which follows the ring even
//! when the normals scatter), and the least-squares plane of the ring points. The first one under
//! which the ring is a simple counter-clockwise polygon, and toward which every ring normal
//! points (so that the surface across the hole can be a height field over the plane), is used.

use nalgebra::{Matrix3, Point2, Point3, Vector3};

/// Which plane a ring was projected onto.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlaneKind {
    /// The user's `direction`.
    Direction,
    /// Mean of the ring's vertex normals (seed 000 eq. 7, seed 002 section 3.2).
    MeanNormal,
    /// The ring's area vector (Newell).
    AreaNormal,
    /// Least-squares plane of the ring points.
    BestFit,
}

/// An orthonormal frame: `origin + u e1 + v e2 + w normal`.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    pub origin: Point3<f64>,
    pub e1: Vector3<f64>,
    pub e2: Vector3<f64>,
    pub normal: Vector3<f64>,
    pub kind: PlaneKind,
}

impl Frame {
    /// The frame with the given unit normal at `origin` (e1 x e2 = normal).
    pub fn new(origin: Point3<f64>, normal: Vector3<f64>, kind: PlaneKind) -> Frame {
        let a = if normal.x.abs() < 0.6 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = (a - normal * normal.dot(&a)).normalize();
        let e2 = normal.cross(&e1);
        Frame {
            origin,
            e1,
            e2,
            normal,
            kind,
        }
    }
    /// Plane coordinates of `p`.
    pub fn to_2d(&self, p: &Point3<f64>) -> Point2<f64> {
        let d = p - self.origin;
        Point2::new(d.dot(&self.e1), d.dot(&self.e2))
    }
    /// The point of the plane with coordinates `q`.
    pub fn to_3d(&self, q: &Point2<f64>) -> Point3<f64> {
        self.origin + self.e1 * q.x + self.e2 * q.y
    }
}

/// Smallest cosine allowed between a ring normal and the projection direction (about 87
/// degrees): a surface leaving the ring at a right angle to the plane or beyond would fold over
/// it.
pub const MIN_NORMAL_COS: f64 = 0.05;

/// Projects `ring` (in fill order) onto the first candidate plane under which it is a simple
/// counter-clockwise polygon. `normals` are the ring's vertex normals. `None` when every
/// candidate folds it.
pub fn project_ring(
    ring: &[Point3<f64>],
    normals: &[Vector3<f64>],
    direction: Option<Vector3<f64>>,
) -> Option<(Frame, Vec<Point2<f64>>)> {
    if ring.len() < 3 {
        return None;
    }
    let centre =
        Point3::from(ring.iter().map(|p| p.coords).sum::<Vector3<f64>>() / ring.len() as f64);
    let mut candidates: Vec<(Vector3<f64>, PlaneKind)> = Vec::with_capacity(4);
    if let Some(d) = direction {
        candidates.push((d, PlaneKind::Direction));
    }
    candidates.push((normals.iter().sum(), PlaneKind::MeanNormal));
    let newell: Vector3<f64> = (0..ring.len())
        .map(|i| (ring[i] - centre).cross(&(ring[(i + 1) % ring.len()] - centre)))
        .sum();
    candidates.push((newell, PlaneKind::AreaNormal));
    if let Some(n) = best_fit_normal(ring, &centre) {
        // Orient like the area vector.
        let n = if n.dot(&newell) < 0.0 { -n } else { n };
        candidates.push((n, PlaneKind::BestFit));
    }
    for (n, kind) in candidates {
        let len = n.norm();
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        let frame = Frame::new(centre, n / len, kind);
        if normals
            .iter()
            .any(|m| !(m.dot(&frame.normal) > MIN_NORMAL_COS))
        {
            continue;
        }
        let poly: Vec<Point2<f64>> = ring.iter().map(|p| frame.to_2d(p)).collect();
        if is_simple_ccw(&poly) {
            return Some((frame, poly));
        }
    }
    None
}

/// Normal of the least-squares plane through `pts` (smallest eigenvector of the covariance).
fn best_fit_normal(pts: &[Point3<f64>], centre: &Point3<f64>) -> Option<Vector3<f64>> {
    let mut c = Matrix3::zeros();
    for p in pts {
        let d = p - centre;
        c += d * d.transpose();
    }
    let eig = c.symmetric_eigen();
    let (k, _) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    let n = eig.eigenvectors.column(k).into_owned();
    (n.norm() > 0.5).then_some(n)
}

/// Twice the signed area (positive counter-clockwise).
pub fn signed_area2(poly: &[Point2<f64>]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a.x * b.y - a.y * b.x
        })
        .sum()
}

/// 2D cross product of (b - a) and (c - a).
pub fn orient(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// True when the closed polygon is simple (no two non-adjacent edges meet, no vertex on another
/// edge, within a tolerance of 1e-9 of its size) and counter-clockwise. Edges are swept in order
/// of their lowest x so that only edges overlapping in x are compared.
pub fn is_simple_ccw(poly: &[Point2<f64>]) -> bool {
    let n = poly.len();
    if n < 3 || poly.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
        return false;
    }
    let area2 = signed_area2(poly);
    let (mut lo, mut hi) = (poly[0], poly[0]);
    for p in poly {
        lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    let size = (hi - lo).norm();
    if !(area2 > 1e-12 * size * size) {
        return false;
    }
    let eps = 1e-9 * size;
    let mut order: Vec<usize> = (0..n).collect();
    let xmin = |i: usize| poly[i].x.min(poly[(i + 1) % n].x);
    let xmax = |i: usize| poly[i].x.max(poly[(i + 1) % n].x);
    order.sort_by(|&a, &b| xmin(a).total_cmp(&xmin(b)).then(a.cmp(&b)));
    for (k, &i) in order.iter().enumerate() {
        let limit = xmax(i) + eps;
        for &j in &order[k + 1..] {
            if xmin(j) > limit {
                break;
            }
            let adjacent = (i + 1) % n == j || (j + 1) % n == i;
            if adjacent {
                // Adjacent edges share a vertex; they must not fold back onto each other.
                let (s, m, e) = if (i + 1) % n == j {
                    (i, j, (j + 1) % n)
                } else {
                    (j, i, (i + 1) % n)
                };
                if n > 3 && collinear_overlap(&poly[s], &poly[m], &poly[e], eps) {
                    return false;
                }
                continue;
            }
            if segments_meet(
                &poly[i],
                &poly[(i + 1) % n],
                &poly[j],
                &poly[(j + 1) % n],
                eps,
            ) {
                return false;
            }
        }
    }
    true
}

/// True when the path s -> m -> e turns back on itself (e lies on the segment m-s side).
fn collinear_overlap(s: &Point2<f64>, m: &Point2<f64>, e: &Point2<f64>, eps: f64) -> bool {
    let a = s - m;
    let b = e - m;
    let cross = a.x * b.y - a.y * b.x;
    cross.abs() <= eps * (a.norm() + b.norm()) && a.dot(&b) > 0.0
}

/// Distance from `p` to the segment a-b.
pub fn point_segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// True when segments a-b and c-d intersect or come within `eps` of each other.
pub fn segments_meet(
    a: &Point2<f64>,
    b: &Point2<f64>,
    c: &Point2<f64>,
    d: &Point2<f64>,
    eps: f64,
) -> bool {
    let d1 = orient(a, b, c);
    let d2 = orient(a, b, d);
    let d3 = orient(c, d, a);
    let d4 = orient(c, d, b);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    point_segment_distance(c, a, b) <= eps
        || point_segment_distance(d, a, b) <= eps
        || point_segment_distance(a, c, d) <= eps
        || point_segment_distance(b, c, d) <= eps
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_and_bowtie() {
        let sq = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
        ];
        assert!(is_simple_ccw(&sq));
        let mut cw = sq;
        cw.reverse();
        assert!(!is_simple_ccw(&cw));
        let bow = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 1.0),
        ];
        assert!(!is_simple_ccw(&bow));
        // A vertex touching a non-adjacent edge.
        let touch = [
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 0.0),
            Point2::new(2.0, 2.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 2.0),
        ];
        assert!(!is_simple_ccw(&touch));
    }

    #[test]
    fn ring_on_a_cylinder_side_projects_with_the_mean_normal() {
        // A ring around the x axis direction on the side of a cylinder y^2+z^2=1, z > 0.
        let mut ring = Vec::new();
        let mut normals = Vec::new();
        for k in 0..24 {
            let t = std::f64::consts::TAU * k as f64 / 24.0;
            let x = 0.3 * t.cos();
            let a = 0.3 * t.sin();
            let p = Point3::new(x, a.sin(), a.cos());
            ring.push(p);
            normals.push(Vector3::new(0.0, a.sin(), a.cos()));
        }
        let (frame, poly) = project_ring(&ring, &normals, None).unwrap();
        assert_eq!(frame.kind, PlaneKind::MeanNormal);
        assert!(frame.normal.z > 0.99);
        assert!(is_simple_ccw(&poly));
        // The user direction wins when it works, and a folding one is skipped.
        let (f2, _) = project_ring(&ring, &normals, Some(Vector3::new(0.0, 0.3, 1.0))).unwrap();
        assert_eq!(f2.kind, PlaneKind::Direction);
        let (f3, _) = project_ring(&ring, &normals, Some(Vector3::new(0.0, 1.0, 0.0))).unwrap();
        assert_eq!(f3.kind, PlaneKind::MeanNormal);
    }
}
