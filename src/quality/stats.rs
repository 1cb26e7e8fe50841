//! Summary statistics of a set of distances: max, mean, RMS, p95, p99, absolute and relative to
//! a reference length (the bounding-box diagonal of the input).

use serde::Serialize;

/// Distance statistics, absolute and relative to `reference`.
#[derive(Debug, Clone, Copy, Default, Serialize, PartialEq)]
pub struct DistanceStats {
    pub count: usize,
    pub max: f64,
    pub mean: f64,
    pub rms: f64,
    pub p95: f64,
    pub p99: f64,
    /// The length the `_rel` figures are relative to.
    pub reference: f64,
    pub max_rel: f64,
    pub mean_rel: f64,
    pub rms_rel: f64,
    pub p95_rel: f64,
    pub p99_rel: f64,
}

/// The `q`-quantile (0..=1) of sorted values, by linear interpolation between order statistics
/// (numpy's default, so figures compare with `np.percentile`).
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    let t = pos - lo as f64;
    sorted[lo] * (1.0 - t) + sorted[hi] * t
}

impl DistanceStats {
    /// Statistics of `d` (non-finite values are counted as +infinity in max and skipped in the
    /// means), relative figures against `reference` (> 0).
    pub fn of(d: &[f64], reference: f64) -> DistanceStats {
        let mut s: Vec<f64> = d.iter().copied().filter(|x| x.is_finite()).collect();
        if s.is_empty() {
            return DistanceStats {
                reference,
                ..Default::default()
            };
        }
        s.sort_by(f64::total_cmp);
        let n = s.len() as f64;
        let mean = s.iter().sum::<f64>() / n;
        let rms = (s.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
        let max = if s.len() < d.len() {
            f64::INFINITY
        } else {
            s[s.len() - 1]
        };
        let p95 = quantile_sorted(&s, 0.95);
        let p99 = quantile_sorted(&s, 0.99);
        let r = if reference > 0.0 { reference } else { 1.0 };
        DistanceStats {
            count: d.len(),
            max,
            mean,
            rms,
            p95,
            p99,
            reference,
            max_rel: max / r,
            mean_rel: mean / r,
            rms_rel: rms / r,
            p95_rel: p95 / r,
            p99_rel: p99 / r,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_numpy_percentile() {
        let d: Vec<f64> = (1..=100).map(|x| x as f64).collect();
        let s = DistanceStats::of(&d, 10.0);
        assert!((s.p95 - 95.05).abs() < 1e-12);
        assert!((s.p99 - 99.01).abs() < 1e-12);
        assert_eq!(s.max, 100.0);
        assert!((s.mean - 50.5).abs() < 1e-12);
        assert!((s.max_rel - 10.0).abs() < 1e-12);
    }

    #[test]
    fn empty_and_nan() {
        assert_eq!(DistanceStats::of(&[], 1.0).count, 0);
        let s = DistanceStats::of(&[1.0, f64::NAN], 1.0);
        assert!(s.max.is_infinite());
        assert_eq!(s.mean, 1.0);
    }
}
