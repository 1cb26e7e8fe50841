//! `fit --sharp`: the crease-aligned quad net from the sharp implicit (issue 36), by one of two
//! routes ([`CreaseNetRoute`]).
//!
//! The remesh route (default): the sharp implicit's zero set is meshed as `reconstruct` does
//! ([`crate::reconstruct::surface_mesh`]: marching cubes, relaxation, the triangles across a
//! crease split where its two sides meet; no subdivision, [`SURFACE_SUBDIVISIONS`]), an open
//! fit keeps the triangles near the data only (less those where two sheets touch), and the
//! mesh becomes a quad net with its edges on the creases ([`crate::polygonize::remesh_net`]),
//! its crease and corner nodes between the regions' surfaces fitted to the data around them
//! where those follow their points ([`crate::features::data_sides`], within
//! [`crate::polygonize::remesh_net::DATA_SIDES_RADIUS`] target edges). The voxel route puts
//! the voxel net's nodes on the creases ([`crate::polygonize::crease_nodes`]); it cannot follow
//! a crease at an angle to its grid (docs/BENCHMARKS.md: crease max about 1e-2 of the
//! diagonal against 2e-4 to 1e-3).

use crate::features::sharp_field::SharpField;
use crate::implicit::PouImplicit;
use crate::mesh::retain::retain_faces;
use crate::mesh::Mesh;
use crate::polygonize::quad_net::QuadNet;
use crate::polygonize::remesh_net::{data_sides, remesh_net, RemeshNet, RemeshNetOptions};
use crate::reconstruct::{surface_mesh, ReconstructOptions, Timings};
use crate::spatial::KdTree;
use crate::Result;
use nalgebra::Point3;

/// Subdivisions of the marching-cubes mesh the remesh starts from. None: the remesh projects
/// onto that mesh and its nodes then onto the implicit's sides, so a finer mesh buys little
/// (make_parts' block.stl: crease max 4.5e-4 of the diagonal either way) at ten times the time
/// (12 s against 1.1 s) and twice the memory.
const SURFACE_SUBDIVISIONS: usize = 0;

/// How `fit --sharp` builds its crease-aligned net (`--crease-net`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum CreaseNetRoute {
    /// A crease-preserving remesh of the sharp implicit's mesh, split into quads.
    #[default]
    Remesh,
    /// The voxel net with its nodes put on the creases and corners.
    Voxel,
}

/// The crease-aligned net of `--sharp`, by the route that built it.
pub enum CreaseNet {
    /// The voxel net, its nodes placed, and the segmentation's region count.
    Placed(crate::polygonize::crease_nodes::CreaseNet, QuadNet, usize),
    Remeshed(crate::polygonize::remesh_net::RemeshNet),
}

impl CreaseNet {
    /// The net, its quads' regions and the number of regions.
    pub fn labelled(&self) -> (&QuadNet, &[u32], usize) {
        match self {
            CreaseNet::Placed(p, net, regions) => (net, &p.quad_region, *regions),
            CreaseNet::Remeshed(r) => (&r.net, &r.quad_region, r.report.regions),
        }
    }

    pub fn into_net(self) -> QuadNet {
        match self {
            CreaseNet::Placed(_, net, _) => net,
            CreaseNet::Remeshed(r) => r.net,
        }
    }
}

/// What the remesh route works from.
pub struct RemeshInputs<'a> {
    /// The sharp implicit, its options and its sides.
    pub f: &'a PouImplicit,
    pub implicit: &'a crate::implicit::FitOptions,
    pub field: &'a SharpField<'a>,
    /// The input's own points (not samples added on a coarse mesh).
    pub data: &'a [Point3<f64>],
    /// Their tree, for the support of an open fit.
    pub tree: &'a KdTree,
    /// Keep only the surface within this distance of the data (an open fit).
    pub open_support: Option<f64>,
    /// Quads wanted, before the creases' splits.
    pub quads: usize,
}

/// The remesh route (module doc).
pub fn remeshed(inputs: &RemeshInputs) -> Result<RemeshNet> {
    let ropts = ReconstructOptions {
        fit: inputs.implicit.clone(),
        max_subdivisions: SURFACE_SUBDIVISIONS,
        ..Default::default()
    };
    let mut timings = Timings::default();
    let surface = surface_mesh(
        inputs.f,
        inputs.data,
        Some(inputs.field),
        &ropts,
        &mut timings,
        &mut |_, _| {},
    )?;
    let mut mesh = surface.mesh;
    if let Some(r) = inputs.open_support {
        mesh = supported(&mesh, inputs.tree, r);
    }
    let diag = inputs.f.diagonal();
    let data = data_sides(inputs.field, &mesh, inputs.quads);
    remesh_net(
        &mesh,
        inputs.f,
        Some(inputs.field),
        Some(&data),
        diag,
        inputs.open_support.is_some(),
        &RemeshNetOptions::new(inputs.quads),
    )
}

/// Unmarks (`keep`) the triangles of `faces` around every vertex where the kept ones leave two
/// sheets touching (more than two boundary edges meet there), until there is none: the remesh
/// and the quad net need a 2-manifold with boundary.
fn drop_pinches(faces: &[[u32; 3]], keep: &mut [bool], vertices: usize) {
    loop {
        let mut directed = std::collections::HashSet::new();
        for (t, _) in faces.iter().zip(keep.iter()).filter(|x| *x.1) {
            for k in 0..3 {
                directed.insert((t[k], t[(k + 1) % 3]));
            }
        }
        let mut boundary = vec![0usize; vertices];
        for &(a, b) in &directed {
            if !directed.contains(&(b, a)) {
                boundary[a as usize] += 1;
                boundary[b as usize] += 1;
            }
        }
        let mut dropped = false;
        for (t, k) in faces.iter().zip(keep.iter_mut()) {
            if *k && t.iter().any(|&v| boundary[v as usize] > 2) {
                *k = false;
                dropped = true;
            }
        }
        if !dropped {
            return;
        }
    }
}

/// The triangles of `mesh` whose three vertices lie within `r` of a point of `tree` (less the
/// pinches, [`drop_pinches`]), with the vertices they use.
fn supported(mesh: &Mesh, tree: &KdTree, r: f64) -> Mesh {
    let near: Vec<bool> = mesh
        .positions
        .iter()
        .map(|p| tree.nearest(p).1 <= r)
        .collect();
    let mut keep: Vec<bool> = mesh
        .faces
        .iter()
        .map(|t| t.iter().all(|&v| near[v as usize]))
        .collect();
    drop_pinches(&mesh.faces, &mut keep, mesh.positions.len());
    retain_faces(mesh, &keep)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles touching at one vertex are a pinch and go; a fan around it stays.
    #[test]
    fn pinched_sheets_are_dropped_and_a_fan_kept() {
        let kept = |faces: &[[u32; 3]], vertices: usize| -> Vec<[u32; 3]> {
            let mut keep = vec![true; faces.len()];
            drop_pinches(faces, &mut keep, vertices);
            faces
                .iter()
                .zip(&keep)
                .filter(|x| *x.1)
                .map(|x| *x.0)
                .collect()
        };
        assert!(kept(&[[0, 1, 2], [0, 3, 4]], 5).is_empty());
        let fan = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]];
        assert_eq!(kept(&fan, 5), fan);
        // The fan plus a triangle touching its apex only: that one and the fan around the
        // apex go (the apex keeps four boundary edges until both sheets are gone).
        let mixed = kept(&[[0, 1, 2], [0, 2, 3], [0, 5, 6], [1, 7, 2]], 8);
        assert!(!mixed.contains(&[0, 5, 6]), "{mixed:?}");
    }
}
