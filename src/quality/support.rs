//! How much of a fitted surface the data backs: the area of the patch sample grids farther
//! than a threshold from every input point.
//!
//! The deviation of the input points from the patches is one-sided: a patch that wanders where
//! there are no points (an implicit closing a large opening by extrapolation, a spurious
//! sheet) does not raise it. This measure is the other side, on the sample grids every patch
//! interpolates: each grid cell (four neighbouring samples on f = 0) counts with its area
//! A = |d1 x d2| / 2 (d1, d2 its diagonals), and is *unsupported* when its centre lies
//! farther than the threshold from the nearest input point. The fraction of unsupported area
//! is what `fit` reports and warns about.

use crate::spatial::KdTree;
use nalgebra::Point3;
use rayon::prelude::*;
use serde::Serialize;

/// Support of a surface by the data.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct SupportReport {
    /// Distance beyond which a cell is unsupported (model units).
    pub threshold: f64,
    /// Total area of the sample-grid cells (model units squared).
    pub area: f64,
    /// Area of the unsupported cells, and its fraction of `area`.
    pub unsupported_area: f64,
    pub unsupported_fraction: f64,
}

/// Area |d1 x d2| / 2 (d1, d2 its diagonals) and centre of the grid cell with corners
/// `p00`, `p10`, `p01`, `p11` (p_ij at grid position (i, j)).
pub fn grid_cell(
    p00: Point3<f64>,
    p10: Point3<f64>,
    p01: Point3<f64>,
    p11: Point3<f64>,
) -> (f64, Point3<f64>) {
    let area = 0.5 * (p11 - p00).cross(&(p01 - p10)).norm();
    let centre = Point3::from((p00.coords + p10.coords + p01.coords + p11.coords) / 4.0);
    (area, centre)
}

/// Measures the support of the surfaces sampled by `grids` (each `points[i][j]`, i along u,
/// j along v) by the points in `data`.
pub fn surface_support(
    grids: &[&Vec<Vec<Point3<f64>>>],
    data: &KdTree,
    threshold: f64,
) -> SupportReport {
    let [r] = surface_support_at(grids, data, [threshold]);
    r
}

/// [`surface_support`] at several thresholds, one nearest-point query per grid cell for all
/// (`fit` reports two).
pub fn surface_support_at<const N: usize>(
    grids: &[&Vec<Vec<Point3<f64>>>],
    data: &KdTree,
    thresholds: [f64; N],
) -> [SupportReport; N] {
    // Per-grid sums collected, then added in grid order: the same bits at any thread count.
    // Entry 0 is the area, entry 1 + t the area beyond threshold t.
    let per_grid: Vec<Vec<f64>> = grids
        .par_iter()
        .map(|g| {
            let mut a = vec![0.0; 1 + N];
            for i in 0..g.len().saturating_sub(1) {
                for j in 0..g[i]
                    .len()
                    .saturating_sub(1)
                    .min(g[i + 1].len().saturating_sub(1))
                {
                    let (cell, c) = grid_cell(g[i][j], g[i + 1][j], g[i][j + 1], g[i + 1][j + 1]);
                    if !cell.is_finite() {
                        continue;
                    }
                    a[0] += cell;
                    let d = data.nearest(&c).1;
                    for (t, &th) in thresholds.iter().enumerate() {
                        if d > th {
                            a[1 + t] += cell;
                        }
                    }
                }
            }
            a
        })
        .collect();
    let sums = per_grid.iter().fold(vec![0.0; 1 + N], |mut x, y| {
        for (a, b) in x.iter_mut().zip(y) {
            *a += b;
        }
        x
    });
    let area = sums[0];
    std::array::from_fn(|t| SupportReport {
        threshold: thresholds[t],
        area,
        unsupported_area: sums[1 + t],
        unsupported_fraction: if area > 0.0 { sums[1 + t] / area } else { 0.0 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square sampled on a 10 x 10 grid, data on its left half only: the right half
    /// beyond the threshold is unsupported.
    #[test]
    fn half_covered_square() {
        let grid: Vec<Vec<Point3<f64>>> = (0..=10)
            .map(|i| {
                (0..=10)
                    .map(|j| Point3::new(i as f64 / 10.0, j as f64 / 10.0, 0.0))
                    .collect()
            })
            .collect();
        let data: Vec<Point3<f64>> = (0..=50)
            .flat_map(|i| {
                (0..=100).map(move |j| Point3::new(i as f64 / 100.0, j as f64 / 100.0, 0.0))
            })
            .collect();
        let tree = KdTree::build(&data).unwrap();
        let r = surface_support(&[&grid], &tree, 0.12);
        assert!((r.area - 1.0).abs() < 1e-12, "{r:?}");
        // Cell centres at x = 0.05, 0.15, ...: those at x >= 0.65 are more than 0.12 from x = 0.5.
        assert!((r.unsupported_fraction - 0.4).abs() < 1e-12, "{r:?}");
        let all = surface_support(&[&grid], &tree, 1.0);
        assert_eq!(all.unsupported_area, 0.0);
        // Both at once: the same numbers.
        let both = surface_support_at(&[&grid], &tree, [0.12, 1.0]);
        assert_eq!(both, [r.clone(), all.clone()]);
    }
}
