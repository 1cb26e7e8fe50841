//! B-spline curves and surfaces, bicubic interpolation with clamped end tangents (seed 004
//! eq. 4-14), and the patch network that STEP and IGES export take.
//!
//! - [`basis`]: Cox-de Boor basis functions, derivatives, knot spans (eq. 5-8).
//! - [`params`]: interpolation parameters (square-root chord, eq. 9) and cubic knot vectors.
//! - [`curve`]: [`BSplineCurve`], cubic interpolation with end tangents (eq. 9-11).
//! - [`surface`]: [`BSplineSurface`], grid interpolation (eq. 9-14), point inversion.
//! - [`network`]: [`PatchNetwork`], patches sewn along shared edge curves.
//! - [`extend`]: a surface extended beyond its domain by a C1 linear apron (STEP faces as
//!   trimmed regions of larger surfaces).
//! - [`restrict`]: a surface restricted to a parameter sub-rectangle (knot insertion).

pub mod basis;
pub mod curve;
pub mod extend;
pub mod network;
pub mod params;
pub mod restrict;
pub mod surface;

pub use curve::BSplineCurve;
pub use network::{NetEdge, NetFace, PatchInput, PatchNetwork};
pub use params::Params;
pub use surface::{
    end_slope, estimate_twists, BSplineSurface, ClosestPoint, PatchGrid, Side, SurfaceDerivatives,
    Twist,
};
