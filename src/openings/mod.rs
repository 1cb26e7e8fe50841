//! Openings of the data: where the implicit's zero set is not backed by points (the underside of
//! a part scanned on a table, the back of a face scanned from the front), and what `fit` does
//! about them (`--close`, issue 34).
//!
//! The partition-of-unity implicit is defined in its whole root cube, so its zero set always
//! closes: across a small hole it bridges the rim smoothly (the bunny's base), across a missing
//! side it extrapolates the sides until they meet somewhere, often far from anything scanned.
//! [`decide::choose`] decides from a ray test on the oriented points ([`enclosure`]: do rays
//! cast inward leave the part?), before the implicit is fitted, and chooses:
//! - [`Close::Smooth`]: the closed surface of today (a solid; holes bridged by the implicit);
//! - [`Close::Open`]: only the scanned surface: [`trim::trim_to_data`] cuts the net to the
//!   quads the data support, and the patches stop where the data stop (an open shell).
//!
//! `auto` (the default) chooses `smooth` when the data enclose the volume (escape share at
//! most [`OPEN_ESCAPE`]) and `open` otherwise, and says why in the report; when more than
//! [`CLOSED_UNSUPPORTED`] of the closed net then has no data near it, it fits the surface open
//! after all. With `open` the
//! implicit does not bridge openings ([`crate::implicit::pou::FitOptions::bridge_openings`]):
//! what it would put there is cut away, and bridging a whole missing side is slow.

pub mod coverage;
pub mod decide;
pub mod enclosure;
pub mod pieces;
pub mod rim;
pub mod trim;

pub use decide::{choose, net_support, ClosureReport};
pub use rim::{fit_rim, RimReport};
pub use trim::{trim_to_data, TrimReport};

/// How `fit` treats the openings of the data (`--close`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Close {
    /// `smooth` when the data enclose the volume, `open` otherwise.
    Auto,
    /// Close every opening with the implicit's smooth extension (a closed solid).
    Smooth,
    /// Fit only the scanned surface (an open shell).
    Open,
}

impl std::str::FromStr for Close {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Close> {
        match s {
            "auto" => Ok(Close::Auto),
            "smooth" => Ok(Close::Smooth),
            "open" => Ok(Close::Open),
            other => Err(crate::Error::InvalidOption(format!(
                "--close must be auto, smooth or open, got `{other}`"
            ))),
        }
    }
}

/// Largest escape share ([`enclosure`]) for which `auto` closes the surface. Measured
/// (`examples/escape_share.rs`): closed models 0-0.6 % (the bunny with its base holes 0.24,
/// fandisk 0.17, teapot 0.42, spot's vertices as a sparse cloud 0.0, the machined parts as
/// meshes and clouds at most 0.6); scans without their underside 6.8 % (spot's upper
/// vertices as a sparse cloud) and 7.8 % (bracket) to 82 % (tilted block).
pub const OPEN_ESCAPE: f64 = 0.04;

/// Largest unsupported share (of the closed voxel net, [`decide::net_support`]) for which
/// `auto` keeps the closed surface. Over it the data enclose the volume but the implicit does
/// not follow them: parts thinner than the sampling resolves (the cow's ear cups and tail, the
/// two sides of a shell a few hundredths thick with their normals estimated alike) leave a
/// sheet the implicit can only close by a blob away from the data (cow: 10.4 % unsupported,
/// 39 % of the patch area farther than 1 % of the diagonal from the data). `auto` then fits
/// the scanned surface open ([`decide::ClosureReport::reopen`]). Closed models measure 0 % (the
/// bunny with its base holes bridged, spot, fandisk, the machined parts).
pub const CLOSED_UNSUPPORTED: f64 = 0.05;

/// Distance, in voxels, within which a net node must have an input point to count as supported
/// (a voxel-net node lies up to about a voxel from the zero set, and the points on it).
pub const SUPPORT_RADIUS: f64 = 1.0;
