//! Spatial search structures: a k-d tree for neighbour queries and an adaptive octree for the
//! domain decomposition of the implicit surface (seed 003 section 3.1).

pub mod box_index;
pub mod fast_hash;
pub mod kdtree;
pub mod octree;
pub mod triangle_bvh;

pub use box_index::BoxIndex;
pub use kdtree::KdTree;
pub use octree::{CellContext, Cube, Decision, Octree};
pub use triangle_bvh::TriangleBvh;
