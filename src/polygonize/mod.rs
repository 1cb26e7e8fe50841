//! From an implicit surface to a triangle mesh (seed 003 section 3.3): marching cubes, centroid
//! relaxation with re-projection (eq. 9), and 1-to-4 subdivision with projection.

pub mod components;
pub mod marching_cubes;
pub mod relax;
pub mod subdivide;

pub use marching_cubes::marching_cubes;
pub use relax::relax;
pub use subdivide::{refine, RefineOptions, RefineReport};
