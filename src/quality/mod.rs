//! Measured quality of a patch network: how far the input points lie from the surfaces
//! (point inversion on the patches) and how large the normal jump is across shared edges.
//! These are the figures `fit` writes in its report; they are computed on the exact B-spline
//! surfaces, not on a tessellation.

pub mod continuity;
pub mod control_net;
pub mod folds;
pub mod patch_deviation;
pub mod support;

pub use continuity::{normal_jumps, ContinuityReport};
pub use folds::{folds, FoldReport, SampleGrid};
pub use patch_deviation::{deviation_from_patches, PatchDeviation};
pub use support::{surface_support, surface_support_at, SupportReport};
