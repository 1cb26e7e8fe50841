//! Whether a stage keeps the input's sharp edges (`--sharp on|off|auto`), decided from the
//! segmentation ([`super::segment`]).
//!
//! A machined part is made of several faces of comparable size: the planes, cylinders and
//! fillets between its creases. A scan of an organic shape is one smooth region, with at most
//! a few small ones behind mild creases (the rim of a half scan, a fold of noise). `auto`
//! keeps the edges when more than one region was found and the regions other than the largest
//! hold at least [`AUTO_OTHER_SHARE`] of the region points. Measured with `scansurf features`
//! (docs/BENCHMARKS.md, "Sharp edges by default"): make_parts' and the extra machined parts
//! 0.56-0.81, fandisk 0.74; the halves of organic scans 0.001-0.10, the bunny and spot one
//! region; the low-polygon cow mesh 0.29, whose facets' creases, kept, made it worse (normal
//! error against cow.obj 6.6 -> 8.3 degrees), hence 0.4 rather than 0.25.

use super::SegmentStats;

/// Smallest share of the region points outside the largest region for `auto` to keep the
/// edges.
pub const AUTO_OTHER_SHARE: f64 = 0.4;

/// `--sharp`: keep the sharp edges always (where creases are found), never, or when the
/// input looks machined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum SharpMode {
    /// Whenever the input has more than one smooth region.
    On,
    /// Never: the input is not segmented, every crease is rounded.
    Off,
    /// When the input looks machined (see the module doc).
    #[default]
    Auto,
}

/// What was chosen and why (the report's `sharp`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SharpChoice {
    pub requested: SharpMode,
    /// Whether the sharp edges are kept.
    pub sharp: bool,
    /// Smooth regions found.
    pub regions: usize,
    /// Share of the region points outside the largest region.
    pub other_share: f64,
    /// The reason, in words.
    pub reason: String,
}

/// Share of the points of `region_points` outside the largest region (0 with one region or
/// none).
pub fn other_share(region_points: &[usize]) -> f64 {
    let total: usize = region_points.iter().sum();
    let largest = region_points.iter().copied().max().unwrap_or(0);
    if total == 0 {
        0.0
    } else {
        (total - largest) as f64 / total as f64
    }
}

/// Decides `mode` for a segmentation with `stats` (`Off` is decided without segmenting; it
/// is answered here too, for callers that segment anyway).
pub fn choose(mode: SharpMode, stats: &SegmentStats) -> SharpChoice {
    let share = other_share(&stats.region_points);
    let regions = stats.regions;
    let (sharp, reason) = match mode {
        SharpMode::Off => (false, "--sharp off".to_string()),
        _ if regions <= 1 => (
            false,
            "one smooth region: no crease to keep (an organic shape)".to_string(),
        ),
        SharpMode::On => (true, format!("--sharp on: {regions} smooth regions")),
        SharpMode::Auto if share >= AUTO_OTHER_SHARE => (
            true,
            format!(
                "{regions} smooth regions, {:.0} % of the points outside the largest (at least \
                 {:.0} %: a machined part)",
                100.0 * share,
                100.0 * AUTO_OTHER_SHARE
            ),
        ),
        SharpMode::Auto => (
            false,
            format!(
                "{regions} smooth regions, but only {:.1} % of the points outside the largest \
                 (under {:.0} %: an organic shape with a few mild creases; --sharp on keeps them)",
                100.0 * share,
                100.0 * AUTO_OTHER_SHARE
            ),
        ),
    };
    SharpChoice {
        requested: mode,
        sharp,
        regions,
        other_share: share,
        reason,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(points: &[usize]) -> SegmentStats {
        SegmentStats {
            method: "mesh",
            regions: points.len(),
            region_points: points.to_vec(),
            ..SegmentStats::default()
        }
    }

    #[test]
    fn other_share_counts_all_but_the_largest() {
        assert_eq!(other_share(&[]), 0.0);
        assert_eq!(other_share(&[10]), 0.0);
        assert!((other_share(&[60, 30, 10]) - 0.4).abs() < 1e-12);
    }

    #[test]
    fn auto_keeps_the_edges_of_a_part_of_several_faces_only() {
        // A box: six faces of comparable size.
        let part = choose(SharpMode::Auto, &stats(&[30, 30, 20, 20, 10, 10]));
        assert!(part.sharp, "{}", part.reason);
        // An organic half scan: one region and a sliver behind a mild crease.
        let organic = choose(SharpMode::Auto, &stats(&[990, 10]));
        assert!(!organic.sharp, "{}", organic.reason);
        assert!(organic.reason.contains("--sharp on"));
        // `on` keeps the sliver's crease; no mode sharpens a single region.
        assert!(choose(SharpMode::On, &stats(&[990, 10])).sharp);
        assert!(!choose(SharpMode::On, &stats(&[1000])).sharp);
        assert!(!choose(SharpMode::Off, &stats(&[30, 30, 20, 20])).sharp);
    }
}
