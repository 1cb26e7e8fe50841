//! Uniform subsampling of a point set on a voxel grid, to at most a given number of points.
//!
//! Space is cut into cubes of edge `h` anchored at the bounding box's minimum corner; a point
//! `p` falls in voxel `floor((p - min) / h)`. Each occupied voxel keeps one representative: the
//! point closest to the centroid of the voxel's points (ties to the lower input index), so the
//! result is a subset of the input (no averaged, off-surface points) and is deterministic.
//!
//! The number of occupied voxels `N(h)` falls as `h` grows (not strictly: grid alignment makes
//! it wobble a little), so `h` is found by bisection (on a log scale) keeping the invariant
//! `N(lo) > max_points >= N(hi)`, from `hi` just above the box's largest extent (one voxel)
//! and `lo` = that extent / 2^20. It stops once `N(hi)` is within 2% of `max_points` or the
//! bracket is tight, and keeps `hi`, so the result never exceeds `max_points`.
//!
//! Voxel keys are packed into a `u64` (21 bits per axis) and counted by a parallel sort, which
//! is deterministic regardless of the thread count.

use crate::error::{Error, Result};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Which input points a voxel-grid subsample keeps, and at what voxel size.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelSample {
    /// Indices of the kept points, increasing.
    pub indices: Vec<usize>,
    /// Edge length of the voxels (0 when every point was kept without a grid).
    pub voxel_size: f64,
}

/// Bits per axis in a packed voxel key.
const KEY_BITS: u32 = 21;
/// Finest grid the bisection considers, in voxels per largest extent.
const FINEST: f64 = (1u64 << (KEY_BITS - 1)) as f64;

/// Chooses the voxel size and the kept points; see the module documentation.
pub fn voxel_grid_indices(points: &[Point3<f64>], max_points: usize) -> Result<VoxelSample> {
    if max_points == 0 {
        return Err(Error::InvalidOption(
            "--max-points must be at least 1".into(),
        ));
    }
    if points.is_empty() {
        return Err(Error::Degenerate("no points to subsample".into()));
    }
    if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(Error::Degenerate(format!(
            "point {} has a non-finite coordinate",
            i + 1
        )));
    }
    if points.len() <= max_points {
        return Ok(VoxelSample {
            indices: (0..points.len()).collect(),
            voxel_size: 0.0,
        });
    }
    let min = points.iter().fold(points[0], |m, p| m.inf(p));
    let max = points.iter().fold(points[0], |m, p| m.sup(p));
    let extent = (max - min).max();
    if extent <= 0.0 {
        // All points coincide: one voxel.
        return Ok(VoxelSample {
            indices: vec![0],
            voxel_size: 0.0,
        });
    }
    let count = |h: f64| -> usize {
        let mut keys: Vec<u64> = points.par_iter().map(|p| key(p, &min, h)).collect();
        keys.par_sort_unstable();
        if keys.is_empty() {
            return 0;
        }
        1 + keys.windows(2).filter(|w| w[0] != w[1]).count()
    };
    // A voxel a little larger than the largest extent holds every point: N(hi) = 1.
    let mut hi = extent * 1.0001;
    let mut lo = extent / FINEST;
    if count(lo) <= max_points {
        // Even the finest grid merges enough duplicates.
        hi = lo;
    } else {
        let target = (max_points as f64 * 0.98).floor() as usize;
        for _ in 0..60 {
            if hi / lo < 1.0 + 1e-9 {
                break;
            }
            let mid = (lo * hi).sqrt();
            let n = count(mid);
            if n <= max_points {
                hi = mid;
                if n >= target {
                    break;
                }
            } else {
                lo = mid;
            }
        }
    }
    Ok(VoxelSample {
        indices: representatives(points, &min, hi),
        voxel_size: hi,
    })
}

/// Points with their normals, when they have them.
pub type PointsAndNormals = (Vec<Point3<f64>>, Option<Vec<Vector3<f64>>>);

/// Subsamples points (and their normals, when given) to at most `max_points` on a voxel grid.
pub fn voxel_grid(
    points: &[Point3<f64>],
    normals: Option<&[Vector3<f64>]>,
    max_points: usize,
) -> Result<PointsAndNormals> {
    if let Some(n) = normals {
        if n.len() != points.len() {
            return Err(Error::InvalidOption(format!(
                "{} normals for {} points",
                n.len(),
                points.len()
            )));
        }
    }
    let s = voxel_grid_indices(points, max_points)?;
    let pts = s.indices.iter().map(|&i| points[i]).collect();
    let nrm = normals.map(|n| s.indices.iter().map(|&i| n[i]).collect());
    Ok((pts, nrm))
}

/// `--max-points`: a point cloud with more than `max_points` points is voxel-subsampled to at
/// most that many; a cloud within the limit and any mesh with faces are returned unchanged
/// (thinning a triangle mesh's vertices would break its faces).
pub fn limit_points(mesh: crate::mesh::Mesh, max_points: usize) -> Result<crate::mesh::Mesh> {
    if max_points == 0 {
        return Err(Error::InvalidOption(
            "--max-points must be at least 1".into(),
        ));
    }
    if !mesh.is_point_cloud() || mesh.positions.len() <= max_points {
        return Ok(mesh);
    }
    let (p, n) = voxel_grid(&mesh.positions, mesh.normals.as_deref(), max_points)?;
    Ok(crate::mesh::Mesh::from_points(p, n))
}

fn key(p: &Point3<f64>, min: &Point3<f64>, h: f64) -> u64 {
    let m = (1u64 << KEY_BITS) - 1;
    let c = |v: f64, lo: f64| ((((v - lo) / h).floor()).max(0.0) as u64).min(m);
    (c(p.x, min.x) << (2 * KEY_BITS)) | (c(p.y, min.y) << KEY_BITS) | c(p.z, min.z)
}

/// One point per occupied voxel: the one closest to its voxel's centroid.
fn representatives(points: &[Point3<f64>], min: &Point3<f64>, h: f64) -> Vec<usize> {
    let mut keyed: Vec<(u64, usize)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| (key(p, min, h), i))
        .collect();
    // Sorting by (key, index) makes each voxel's run ordered by index: the centroid sum below
    // runs in a fixed order and ties go to the lowest index.
    keyed.par_sort_unstable();
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..=keyed.len() {
        if i == keyed.len() || keyed[i].0 != keyed[start].0 {
            runs.push(start..i);
            start = i;
        }
    }
    let mut out: Vec<usize> = runs
        .into_par_iter()
        .map(|r| {
            let run = &keyed[r];
            let c = run
                .iter()
                .fold(Vector3::zeros(), |s, &(_, i)| s + points[i].coords)
                / run.len() as f64;
            let mut best = run[0].1;
            let mut best_d = f64::INFINITY;
            for &(_, i) in run {
                let d = (points[i].coords - c).norm_squared();
                if d < best_d {
                    best_d = d;
                    best = i;
                }
            }
            best
        })
        .collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_points(n: usize) -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                // A wavy sheet, like a scan of a surface.
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                v.push(Point3::new(x, y, 0.1 * (6.0 * x).sin() * (4.0 * y).cos()));
            }
        }
        v
    }

    #[test]
    fn respects_the_limit_and_gets_close_to_it() {
        let pts = grid_points(200); // 40,000 points
        for max in [1usize, 10, 500, 5000, 39_999] {
            let s = voxel_grid_indices(&pts, max).unwrap();
            assert!(s.indices.len() <= max, "{} > {max}", s.indices.len());
            if max >= 500 {
                assert!(
                    s.indices.len() as f64 >= 0.8 * max as f64,
                    "{} points for a limit of {max}",
                    s.indices.len()
                );
            }
            assert!(s.indices.windows(2).all(|w| w[0] < w[1]));
        }
    }

    #[test]
    fn is_uniform_over_the_sheet() {
        // Every quarter of the sheet gets about a quarter of the kept points.
        let pts = grid_points(200);
        let s = voxel_grid_indices(&pts, 2000).unwrap();
        let mut q = [0usize; 4];
        for &i in &s.indices {
            let p = pts[i];
            q[(p.x >= 0.5) as usize * 2 + (p.y >= 0.5) as usize] += 1;
        }
        let n = s.indices.len() as f64;
        for c in q {
            assert!((c as f64 / n - 0.25).abs() < 0.05, "{q:?}");
        }
    }

    #[test]
    fn keeps_everything_under_the_limit_and_carries_normals() {
        let pts = grid_points(10);
        let nrm: Vec<Vector3<f64>> = (0..pts.len())
            .map(|i| Vector3::new(i as f64, 0.0, 1.0))
            .collect();
        let (p, n) = voxel_grid(&pts, Some(&nrm), 1000).unwrap();
        assert_eq!(p, pts);
        assert_eq!(n.unwrap(), nrm);
        let (p, n) = voxel_grid(&pts, Some(&nrm), 30).unwrap();
        let n = n.unwrap();
        for (pp, nn) in p.iter().zip(&n) {
            assert_eq!(pts[nn.x as usize], *pp);
        }
    }

    #[test]
    fn deterministic() {
        let pts = grid_points(150);
        let a = voxel_grid_indices(&pts, 3000).unwrap();
        let b = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| voxel_grid_indices(&pts, 3000).unwrap());
        assert_eq!(a, b);
    }

    #[test]
    fn bad_input() {
        assert!(voxel_grid_indices(&[], 10).is_err());
        assert!(voxel_grid_indices(&[Point3::origin()], 0).is_err());
        assert!(voxel_grid_indices(&[Point3::new(f64::NAN, 0.0, 0.0); 3], 1).is_err());
        let same = vec![Point3::new(1.0, 2.0, 3.0); 50];
        assert_eq!(voxel_grid_indices(&same, 5).unwrap().indices, vec![0]);
        assert!(voxel_grid(&same, Some(&[Vector3::zeros()]), 5).is_err());
    }
}
