//! Crease polylines and corner points: what [`super::crease_mesh`] and [`super::crease_cloud`]
//! find, in one form, and the finishing steps both share (corners merged when they are one,
//! polyline ends joined to the corner they stop short of, local planes and where they meet).

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use serde::Serialize;

/// One sharp edge of the input: a polyline along the crease between two smooth regions.
#[derive(Debug, Clone, Serialize)]
pub struct Crease {
    /// Vertices in order along the crease; a closed crease repeats its first point at the end.
    pub points: Vec<[f64; 3]>,
    /// Mean angle between the two sides' normals across the crease, degrees (0 flat, 90 a
    /// right-angled edge).
    pub angle_deg: f64,
    /// The two regions it separates (ids as in the per-point labels).
    pub regions: [u32; 2],
    /// True when the crease is a loop (the rim of a hole, a circular edge).
    pub closed: bool,
}

impl Crease {
    /// Length of the polyline.
    pub fn length(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| (Point3::from(w[1]) - Point3::from(w[0])).norm())
            .sum()
    }
}

/// Greedy clustering of points within `radius` of a cluster's first point, in input order
/// (deterministic); returns the clusters' means.
pub fn cluster(points: &[Point3<f64>], radius: f64) -> Vec<Point3<f64>> {
    let mut taken = vec![false; points.len()];
    let mut out = Vec::new();
    for i in 0..points.len() {
        if taken[i] {
            continue;
        }
        let mut sum = Vector3::zeros();
        let mut n = 0.0;
        for j in i..points.len() {
            if !taken[j] && (points[j] - points[i]).norm() <= radius {
                taken[j] = true;
                sum += points[j].coords;
                n += 1.0;
            }
        }
        out.push(Point3::from(sum / n));
    }
    out
}

/// Joins every open crease end within `reach` of a corner to the nearest such corner: the
/// crease samples of a cloud stop where a third face begins, a neighbourhood short of the
/// corner they run into.
pub fn join_ends_to_corners(creases: &mut [Crease], corners: &[Point3<f64>], reach: f64) {
    let nearest = |p: &[f64; 3]| {
        let p = Point3::from(*p);
        corners
            .iter()
            .map(|c| (c, (c - p).norm()))
            .filter(|(_, d)| *d <= reach && *d > 0.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(c, _)| [c.x, c.y, c.z])
    };
    for c in creases
        .iter_mut()
        .filter(|c| !c.closed && !c.points.is_empty())
    {
        if let Some(q) = nearest(&c.points[c.points.len() - 1]) {
            c.points.push(q);
        }
        if let Some(q) = nearest(&c.points[0]) {
            c.points.insert(0, q);
        }
    }
}

/// Corners where crease ends meet: the open crease ends within `reach` of each other are
/// grouped (greedily, in order), and a group whose creases separate three or more regions (a
/// corner of three faces, whose creases stop short of it) gives the point nearest, in least
/// squares, to the lines the creases run along at their ends:
///
///   sum_k (I - d_k d_k^T) x = sum_k (I - d_k d_k^T) e_k,
///
/// e_k an end, d_k the unit direction of its last `reach` of polyline. Kept when the lines are
/// not near parallel (smallest eigenvalue of the sum at least 0.1) and the point lies within
/// `reach` of every end of the group.
pub fn corners_from_ends(creases: &[Crease], reach: f64) -> Vec<Point3<f64>> {
    // (end point, direction out of the crease, regions).
    let mut ends: Vec<(Point3<f64>, Vector3<f64>, [u32; 2])> = Vec::new();
    for c in creases.iter().filter(|c| !c.closed && c.points.len() >= 2) {
        let pts: Vec<Point3<f64>> = c.points.iter().map(|p| Point3::from(*p)).collect();
        for fwd in [true, false] {
            let seq: Vec<Point3<f64>> = if fwd {
                pts.iter().rev().copied().collect()
            } else {
                pts.clone()
            };
            // The point `reach` back from the end (or the far end of a short crease).
            let end = seq[0];
            let back = seq
                .iter()
                .find(|p| (*p - end).norm() >= reach)
                .copied()
                .unwrap_or(seq[seq.len() - 1]);
            if let Some(d) = (end - back).try_normalize(1e-300) {
                ends.push((end, d, c.regions));
            }
        }
    }
    let mut taken = vec![false; ends.len()];
    let mut out = Vec::new();
    for i in 0..ends.len() {
        if taken[i] {
            continue;
        }
        let group: Vec<usize> = (i..ends.len())
            .filter(|&j| !taken[j] && (ends[j].0 - ends[i].0).norm() <= reach)
            .collect();
        let mut regions: Vec<u32> = group.iter().flat_map(|&j| ends[j].2).collect();
        regions.sort_unstable();
        regions.dedup();
        if regions.len() < 3 {
            continue;
        }
        let (mut a, mut b) = (Matrix3::zeros(), Vector3::zeros());
        for &j in &group {
            let (e, d, _) = ends[j];
            let p = Matrix3::identity() - d * d.transpose();
            a += p;
            b += p * e.coords;
        }
        let eig = SymmetricEigen::new(a);
        if eig.eigenvalues.min() < 0.1 {
            continue;
        }
        let Some(x) = a.lu().solve(&b).map(Point3::from) else {
            continue;
        };
        if group.iter().all(|&j| (ends[j].0 - x).norm() <= reach) {
            for &j in &group {
                taken[j] = true;
            }
            out.push(x);
        }
    }
    out
}

/// A plane through points: (centroid, unit normal along `orient`'s side), by principal
/// components (the normal is the direction of least spread). `None` for fewer than three
/// points or a degenerate spread.
pub fn fit_plane(
    points: &[Point3<f64>],
    orient: &Vector3<f64>,
) -> Option<(Point3<f64>, Vector3<f64>)> {
    if points.len() < 3 {
        return None;
    }
    let c = points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / points.len() as f64;
    let mut m = Matrix3::zeros();
    for p in points {
        let d = p.coords - c;
        m += d * d.transpose();
    }
    let eig = SymmetricEigen::new(m);
    let (mut k, mut low) = (0, f64::INFINITY);
    for (i, &v) in eig.eigenvalues.iter().enumerate() {
        if v < low {
            (k, low) = (i, v);
        }
    }
    let n: Vector3<f64> = eig.eigenvectors.column(k).into_owned();
    let n = n.try_normalize(1e-300)?;
    Some((Point3::from(c), if n.dot(orient) < 0.0 { -n } else { n }))
}

/// The point where planes (point, unit normal) meet, with a third condition `extra`
/// (normal, offset) when only two are given: the 3x3 system n_k . x = n_k . c_k. `None` when
/// the planes are near parallel (|det| under `min_det`).
pub fn meet(planes: &[(Point3<f64>, Vector3<f64>)], min_det: f64) -> Option<Point3<f64>> {
    if planes.len() != 3 {
        return None;
    }
    let m = Matrix3::from_rows(&[
        planes[0].1.transpose(),
        planes[1].1.transpose(),
        planes[2].1.transpose(),
    ]);
    if m.determinant().abs() < min_det {
        return None;
    }
    let rhs = Vector3::new(
        planes[0].1.dot(&planes[0].0.coords),
        planes[1].1.dot(&planes[1].0.coords),
        planes[2].1.dot(&planes[2].0.coords),
    );
    m.lu().solve(&rhs).map(Point3::from)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_planes_meet_at_the_box_corner() {
        let planes = [
            (Point3::new(1.0, 5.0, 7.0), Vector3::x()),
            (Point3::new(3.0, 2.0, -1.0), Vector3::y()),
            (Point3::new(0.0, 0.0, 4.0), Vector3::z()),
        ];
        let p = meet(&planes, 0.1).unwrap();
        assert!((p - Point3::new(1.0, 2.0, 4.0)).norm() < 1e-12);
        // Two parallel planes have no corner.
        let par = [
            planes[0],
            (Point3::new(2.0, 0.0, 0.0), Vector3::x()),
            planes[2],
        ];
        assert!(meet(&par, 0.1).is_none());
    }

    #[test]
    fn plane_fit_recovers_a_tilted_plane_and_its_side() {
        let n = Vector3::new(1.0, 2.0, 2.0).normalize();
        let (u, v) = (
            Vector3::new(2.0, -1.0, 0.0).normalize(),
            n.cross(&Vector3::new(2.0, -1.0, 0.0).normalize()),
        );
        let pts: Vec<Point3<f64>> = (0..25)
            .map(|k| Point3::from(u * (k % 5) as f64 + v * (k / 5) as f64 + n * 3.0))
            .collect();
        let (c, m) = fit_plane(&pts, &(-n)).unwrap();
        assert!((m + n).norm() < 1e-9, "{m}");
        assert!((c.coords.dot(&n) - 3.0).abs() < 1e-9);
    }

    #[test]
    fn ends_join_the_nearest_corner_within_reach() {
        let mut c = vec![Crease {
            points: vec![[0.1, 0.0, 0.0], [5.0, 0.0, 0.0]],
            angle_deg: 90.0,
            regions: [0, 1],
            closed: false,
        }];
        join_ends_to_corners(&mut c, &[Point3::origin(), Point3::new(9.0, 0.0, 0.0)], 0.5);
        assert_eq!(c[0].points.first(), Some(&[0.0, 0.0, 0.0]));
        assert_eq!(c[0].points.last(), Some(&[5.0, 0.0, 0.0]));
        assert!((c[0].length() - 5.0).abs() < 1e-12);
        // Three creases stopping short of the corner of a box meet there.
        let stub = |a: [f64; 3], b: [f64; 3], r: [u32; 2]| Crease {
            points: vec![a, b],
            angle_deg: 90.0,
            regions: r,
            closed: false,
        };
        let three = [
            stub([5.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0, 1]),
            stub([0.0, 5.0, 0.0], [0.0, 0.2, 0.0], [1, 2]),
            stub([0.0, 0.0, 5.0], [0.0, 0.0, 0.4], [0, 2]),
        ];
        let found = corners_from_ends(&three, 1.0);
        assert_eq!(found.len(), 1);
        assert!(found[0].coords.norm() < 1e-9, "{}", found[0]);
        // Two creases of one pair are no corner.
        assert!(corners_from_ends(&three[..1], 1.0).is_empty());
        let clusters = cluster(
            &[
                Point3::origin(),
                Point3::new(0.1, 0.0, 0.0),
                Point3::new(3.0, 0.0, 0.0),
            ],
            0.5,
        );
        assert_eq!(clusters.len(), 2);
        assert!((clusters[0].x - 0.05).abs() < 1e-12);
    }
}
