//! The decision of `--close`, and the support of a closed voxel net by the data.
//!
//! **Decision** ([`choose`]), before the implicit is fitted: `auto` is `open` when the escape
//! share of [`super::enclosure`] exceeds [`super::OPEN_ESCAPE`], else `smooth`.
//!
//! **Support** ([`net_support`]), on the first voxel net: a node (a lattice vertex, within
//! about a voxel h of the zero set) is *supported* when an input point lies within
//! r = [`super::SUPPORT_RADIUS`] h of it; a quad is supported when its four nodes are. The
//! voxel net's quads all have area h^2, so the share of unsupported quads is the share of the
//! implicit's closed surface the data do not back:
//!
//! ```text
//! u = #{quads with a node farther than r from every point} / #quads
//! ```
//!
//! `open` keeps the supported quads ([`super::trim`]); the report gives u either way.

use super::enclosure::Enclosure;
use super::Close;
use crate::polygonize::QuadNet;
use crate::spatial::KdTree;
use rayon::prelude::*;

/// What `--close` chose and why (the report's `close`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClosureReport {
    /// `--close` as given.
    pub requested: Close,
    /// What the fit did: `smooth` or `open`.
    pub chosen: Close,
    /// The ray test on the oriented input points.
    pub enclosure: Enclosure,
    /// Share of the closed voxel net's quads with a node farther than `support_radius` from
    /// every input point (the surface the implicit adds where there are no data).
    pub unsupported_share: f64,
    /// The distance used (model units).
    pub support_radius: f64,
    /// The choice in words.
    pub reason: String,
    /// What the trimming to the data did (`open` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trim: Option<super::TrimReport>,
    /// The rim carried to the data's edge (`open` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rim: Option<super::RimReport>,
    /// How much of the data the net covers, and the refinement it took (`open` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coverage: Option<super::coverage::CoverageReport>,
}

/// Decides `requested` from the ray test; the support fields are filled in by the net stage.
pub fn choose(requested: Close, enclosure: Enclosure) -> ClosureReport {
    let rays = format!(
        "{:.1} % of the rays cast inward from the points leave the part",
        100.0 * enclosure.escape_share
    );
    let bar = 100.0 * super::OPEN_ESCAPE;
    let (chosen, reason) = match requested {
        Close::Smooth => (
            Close::Smooth,
            format!("--close smooth: openings closed by the implicit ({rays})"),
        ),
        Close::Open => (
            Close::Open,
            format!("--close open: only the scanned surface is fitted ({rays})"),
        ),
        Close::Auto if enclosure.escape_share > super::OPEN_ESCAPE => (
            Close::Open,
            format!("the data do not enclose a volume: {rays} (more than {bar:.0} %), so only the scanned surface is fitted"),
        ),
        Close::Auto => (
            Close::Smooth,
            format!("the data enclose a volume: {rays} (at most {bar:.0} %), so openings are closed smoothly"),
        ),
    };
    ClosureReport {
        requested,
        chosen,
        enclosure,
        unsupported_share: 0.0,
        support_radius: 0.0,
        reason,
        trim: None,
        rim: None,
        coverage: None,
    }
}

/// Why a closed fit does not follow the data, given its net's unsupported share or the error
/// of its net: more than [`super::CLOSED_UNSUPPORTED`] of it unsupported (parts thinner than
/// the sampling resolves, closed away from the data), or no net at all. `None` when the
/// closed fit stands. The words go to [`ClosureReport::reopen`].
pub fn closed_shortfall(closed: std::result::Result<f64, &crate::Error>) -> Option<String> {
    match closed {
        Ok(u) if u > super::CLOSED_UNSUPPORTED => Some(format!(
            "{:.1} % of the closed surface has no point within a voxel (more than {:.0} %: \
             parts thinner than the sampling resolves, which the implicit closes away from the \
             data)",
            100.0 * u,
            100.0 * super::CLOSED_UNSUPPORTED
        )),
        Ok(_) => None,
        // The error's first clause ("the quad net could not be projected onto the implicit
        // surface"); the caller returns the whole error if the open fit fails too.
        Err(e) => {
            // The message without the variant's prefix ("numerical failure: ").
            let text = match e {
                crate::Error::Numerical(m) | crate::Error::Degenerate(m) => m.clone(),
                other => other.to_string(),
            };
            let clause = text.split([':', '(']).next().unwrap_or_default().trim();
            Some(format!("the closed surface could not be made ({clause})"))
        }
    }
}

impl ClosureReport {
    /// `auto` chose `smooth`, but the closed surface does not follow the data (`because`
    /// says how: more than [`super::CLOSED_UNSUPPORTED`] of it unsupported, or its net failed):
    /// the fit goes on open. True when the report changed (only `auto` and `smooth` do).
    pub fn reopen(&mut self, because: &str) -> bool {
        if self.requested != Close::Auto || self.chosen != Close::Smooth {
            return false;
        }
        self.chosen = Close::Open;
        self.reason = format!(
            "{}; but {because}, so only the scanned surface is fitted",
            self.reason
        );
        true
    }
}

/// Per quad of `net`: all four nodes have an input point within `radius`.
pub fn quads_near_data(net: &QuadNet, data: &KdTree, radius: f64) -> Vec<bool> {
    let nodes: Vec<bool> = net
        .nodes
        .par_iter()
        .map(|p| data.nearest(p).1 <= radius)
        .collect();
    net.quads
        .iter()
        .map(|q| q.iter().all(|&k| nodes[k as usize]))
        .collect()
}

/// Per quad of `net` (voxel edge `h`): all four nodes have an input point within
/// [`super::SUPPORT_RADIUS`] h; and the unsupported share u of the module doc.
pub fn net_support(net: &QuadNet, data: &KdTree, h: f64) -> (Vec<bool>, f64) {
    let quads = quads_near_data(net, data, super::SUPPORT_RADIUS * h);
    let unsupported = quads.iter().filter(|&&s| !s).count();
    (quads, unsupported as f64 / net.quads.len().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn enclosed() -> Enclosure {
        Enclosure {
            rays: 1000,
            escaped: 2,
            escape_share: 0.002,
        }
    }

    #[test]
    fn shortfall_over_the_bar_or_on_failure() {
        assert_eq!(closed_shortfall(Ok(0.0)), None);
        assert_eq!(
            closed_shortfall(Ok(crate::openings::CLOSED_UNSUPPORTED)),
            None
        );
        let over = closed_shortfall(Ok(0.104)).unwrap();
        assert!(over.starts_with("10.4 % of the closed surface"), "{over}");
        let e = crate::Error::Numerical("the quad net could not be projected: details".into());
        let failed = closed_shortfall(Err(&e)).unwrap();
        assert_eq!(
            failed,
            "the closed surface could not be made (the quad net could not be projected)"
        );
    }

    #[test]
    fn only_auto_smooth_reopens() {
        let mut auto = choose(Close::Auto, enclosed());
        assert_eq!(auto.chosen, Close::Smooth);
        assert!(auto.reopen("10.4 % of the closed surface has no point within a voxel"));
        assert_eq!(auto.chosen, Close::Open);
        assert!(auto.reason.contains("enclose a volume"), "{}", auto.reason);
        assert!(auto
            .reason
            .ends_with("so only the scanned surface is fitted"));
        // Already open, or smooth as asked: nothing changes.
        assert!(!auto.reopen("again"));
        let mut smooth = choose(Close::Smooth, enclosed());
        let before = smooth.clone();
        assert!(!smooth.reopen("anything"));
        assert_eq!(smooth, before);
    }
}
