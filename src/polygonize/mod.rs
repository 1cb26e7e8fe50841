//! Polygonization of an implicit surface f(x) = 0: the quad net that `fit` turns into patches.
//!
//! Seed 004 section 3: the outer faces of the voxels that straddle the implicit's zero set form a
//! quad net ([`voxel_net`]); its nodes are projected onto the surface along the gradient
//! ([`newton`]) and smoothed on it ([`net_smooth`]); each quad then becomes one patch
//! (`fit::samples`). [`patch_count`] picks the voxel edge h for a target number of patches.

pub mod net_quality;
pub mod net_smooth;
pub mod newton;
pub mod patch_count;
pub mod quad_net;
pub mod voxel_net;

#[cfg(test)]
pub(crate) mod test_shapes;

pub use quad_net::QuadNet;
