//! `fit`: from the smoothed quad net on the implicit to the data of one bicubic patch per quad
//! (seed 004 section 3, Fig. 5(c)): sample grids on f = 0 with boundary tangents, shared
//! bit-for-bit along every net edge so that the patch network is watertight by construction.
//!
//! - [`crease_net`]: the crease-aligned net of `--sharp`, by remesh or voxel net;
//! - [`net`]: the quad net stage (voxel size from the patch count, voxel net, projection and
//!   smoothing) in one call;
//! - [`ribbons`]: quad strips (ribbons) of edges that must share one sample count;
//! - [`cross_tangents`]: cross-boundary derivatives made coplanar with the interpolated boundary
//!   curve, for equal normals on both sides at every boundary sample;
//! - [`edge_curve`]: the samples and tangents of one net edge, from that edge's data alone;
//! - [`spline_check`]: the complete cubic spline a row of samples will become, for the
//!   tolerance test;
//! - [`samples`]: the per-patch grids, their counts chosen from `--tolerance`.
//! - [`vertex_twists`]: corner twists made first-order compatible around every net vertex.

pub mod crease_net;
pub mod cross_tangents;
pub mod edge_curve;
pub mod net;
pub mod pipeline;
pub mod ribbons;
pub mod samples;
pub mod spline_check;
pub mod vertex_twists;
