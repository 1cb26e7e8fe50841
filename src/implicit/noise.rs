//! Estimate of the noise in oriented points: the median, over a sample of points, of the rms
//! residual of a quadratic height function (seed 004 eq. 1) fitted to each one's k nearest
//! neighbours. On a smooth, densely sampled surface the quadratic leaves almost nothing, so what
//! it leaves is the scatter of the points about the surface.
//!
//! The partition of unity uses it as a floor for its tolerance: asking local fits to pass closer
//! to the points than their own scatter only splits domains until they interpolate the noise.

use super::poly::{Degree, Frame, HeightPoly};
use crate::spatial::KdTree;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Median rms residual (with the degrees of freedom of the fit taken out) of local quadratic
/// fits over `k` neighbours, at up to `samples` evenly
/// strided points. 0 when no neighbourhood can be fitted.
pub fn estimate_noise(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    kd: &KdTree,
    k: usize,
    samples: usize,
) -> f64 {
    if points.len() < k.max(10) || samples == 0 {
        return 0.0;
    }
    let step = (points.len() / samples).max(1);
    let idx: Vec<usize> = (0..points.len()).step_by(step).collect();
    let mut r: Vec<f64> = idx
        .par_iter()
        .filter_map(|&i| {
            let nb = kd.knn(&points[i], k);
            let p: Vec<Point3<f64>> = nb.iter().map(|&(j, _)| points[j]).collect();
            let scale = nb.last()?.1;
            let frame = Frame::new(points[i], normals[i], scale.max(1e-300))?;
            // Neighbours folding over the frame (thin parts) say nothing about noise.
            if nb.iter().any(|&(j, _)| normals[j].dot(&frame.w) < 0.3) {
                return None;
            }
            let h = HeightPoly::fit(&p, frame, Degree::Quadratic).ok()?;
            // Unbiased for the 6 fitted coefficients.
            let ss: f64 = p.iter().map(|q| h.value(q).powi(2)).sum();
            Some((ss / (p.len() as f64 - 6.0).max(1.0)).sqrt())
        })
        .collect();
    if r.is_empty() {
        return 0.0;
    }
    let m = r.len() / 2;
    let (_, v, _) = r.select_nth_unstable_by(m, f64::total_cmp);
    *v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(noise: f64) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let mut s = 1u64;
        let mut p = Vec::new();
        for i in 0..60 {
            for j in 0..60 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let e = ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0 * noise;
                let (x, y) = (i as f64 * 0.01, j as f64 * 0.01);
                p.push(Point3::new(x, y, 0.2 * x * x + e));
            }
        }
        let n = vec![Vector3::z(); p.len()];
        (p, n)
    }

    #[test]
    fn measures_scatter() {
        let (p, n) = plane(0.0);
        let kd = KdTree::build(&p).unwrap();
        assert!(estimate_noise(&p, &n, &kd, 30, 500) < 1e-9);
        let (p, n) = plane(1e-3);
        let kd = KdTree::build(&p).unwrap();
        // Uniform noise of amplitude a has standard deviation a / sqrt(3).
        let s = estimate_noise(&p, &n, &kd, 30, 500);
        assert!(s > 0.4e-3 && s < 0.7e-3, "{s}");
    }
}
