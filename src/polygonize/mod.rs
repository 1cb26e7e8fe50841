//! From an implicit surface f(x) = 0 to polygons.
//!
//! Triangle meshes (seed 003 section 3.3): marching cubes, centroid relaxation with
//! re-projection (eq. 9), and 1-to-4 subdivision with projection.
//!
//! The quad net that `fit` turns into patches (seed 004 section 3): the outer faces of the
//! voxels that straddle the zero set form a quad net ([`voxel_net`]); its nodes are projected
//! onto the surface along the gradient ([`newton`]) and smoothed on it ([`net_smooth`]); each
//! quad then becomes one patch (`fit::samples`). [`patch_count`] picks the voxel edge h for a
//! target number of patches.

pub mod components;
pub mod corner_snap;
pub mod crease_collapse;
pub mod crease_flip;
pub mod crease_labels;
pub mod crease_mesh;
pub mod crease_nodes;
pub mod crease_snap;
pub mod crease_split;
pub mod marching_cubes;
pub mod relax;
pub mod remesh_net;
pub mod ring_corners;
pub mod side_projection;
pub mod subdivide;

pub mod log_map;
pub mod net_quality;
pub mod net_smooth;
pub mod newton;
pub mod patch_count;
pub mod quad_net;
pub mod quad_split;
pub mod voxel_net;

#[cfg(test)]
pub(crate) mod test_shapes;

pub use marching_cubes::marching_cubes;
pub use quad_net::QuadNet;
pub use relax::relax;
pub use subdivide::{refine, RefineOptions, RefineReport};
