//! The quad net stage of `fit` in one call: choose the voxel size (from `--patches N` or
//! `--patch-size L`), build the regularized voxel net, project it onto the implicit and smooth
//! it there (seed 004 section 3). The report is what `--report` JSON shows for this stage.

use crate::implicit::Implicit;
use crate::mesh::Aabb;
use crate::polygonize::net_smooth::{project_and_smooth, SmoothOptions, SmoothReport};
use crate::polygonize::patch_count::{net_for_patch_count, PatchCountReport};
use crate::polygonize::voxel_net::{build_voxel_net, VoxelNetOptions, VoxelNetStats};
use crate::polygonize::QuadNet;
use crate::{Error, Result};
use nalgebra::Point3;

/// How big the patches should be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PatchSize {
    /// About this many patches (within 15 %): `--patches N`.
    Count(usize),
    /// Voxel edge, the nominal patch edge: `--patch-size L`.
    Edge(f64),
}

/// Default patch count of `fit`.
pub const DEFAULT_PATCHES: usize = 1500;

/// What the net stage did and how good the net is.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetReport {
    /// Voxel edge used.
    pub h: f64,
    pub patches: usize,
    pub nodes: usize,
    pub edges: usize,
    /// V - E + F (2 per sphere-like component).
    pub euler_characteristic: i64,
    pub components: usize,
    /// Entry k: number of nodes with k quads.
    pub valence_histogram: Vec<usize>,
    pub voxels: VoxelNetStats,
    /// Present when the size came from a patch count.
    pub patch_count: Option<PatchCountReport>,
    /// Quality right after projection and after smoothing.
    pub smoothing: SmoothReport,
}

/// Builds, projects and smooths the quad net of f = 0 near `seeds` (points on or near the
/// surface, e.g. the input cloud; at least one per surface component) within `bounds`.
/// Errors: an invalid size, no seed near the surface, and the failures of the stages.
pub fn fit_net<I: Implicit + ?Sized>(
    f: &I,
    seeds: &[Point3<f64>],
    bounds: &Aabb,
    size: PatchSize,
) -> Result<(QuadNet, NetReport)> {
    let scale = bounds.diagonal();
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::Degenerate(
            "bounding box is empty or not finite".into(),
        ));
    }
    let (voxel_net, patch_count) = match size {
        PatchSize::Count(n) => {
            let (v, r) = net_for_patch_count(f, seeds, bounds, n)?;
            (v, Some(r))
        }
        PatchSize::Edge(l) => {
            if !(l.is_finite() && l > 0.0) {
                return Err(Error::InvalidOption(format!(
                    "patch size must be a positive length, got {l}"
                )));
            }
            (
                build_voxel_net(f, seeds, bounds, &VoxelNetOptions::new(l))?,
                None,
            )
        }
    };
    let h = voxel_net.h;
    let mut net = voxel_net.net;
    let smoothing = project_and_smooth(&mut net, f, &SmoothOptions::new(scale, h))?;
    let report = NetReport {
        h,
        patches: net.quads.len(),
        nodes: net.nodes.len(),
        edges: net.edges.len(),
        euler_characteristic: net.euler_characteristic(),
        components: net.components().1,
        valence_histogram: net.valence_histogram(),
        voxels: voxel_net.stats,
        patch_count,
        smoothing,
    };
    Ok((net, report))
}
