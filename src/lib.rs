//! scansurf: 3D scan data (point clouds, triangle meshes with holes and noise) to CAD surfaces,
//! a sewn network of bicubic B-spline patches written as STEP and IGES.
//!
//! The pipeline (see `docs/` and the design notes): input file -> [`mesh::Mesh`] -> pre-passes
//! (hole filling, smoothing, normals) -> an implicit surface f(x) = 0 -> outputs (meshes, quad
//! nets, patch networks, STEP/IGES, reports).

pub mod cli;
pub mod error;
pub mod export;
pub mod features;
pub mod fit;
pub mod holes;
pub mod implicit;
pub mod inspect;
pub mod io;
pub mod limits;
pub mod mesh;
pub mod metrics;
pub mod normals;
pub mod nurbs;
pub mod openings;
pub mod polygonize;
pub mod quality;
pub mod reconstruct;
pub mod render;
pub mod sketch;
pub mod smooth;
pub mod spatial;

pub use error::{Error, Result};
pub use mesh::Mesh;
