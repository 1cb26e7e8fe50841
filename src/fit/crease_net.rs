//! `fit --sharp`: the crease-aligned quad net from the sharp implicit (issue 36), by one of two
//! routes ([`CreaseNetRoute`]).
//!
//! The remesh route (default): the sharp implicit's zero set is meshed as `reconstruct` does
//! ([`crate::reconstruct::surface_mesh`]: marching cubes, relaxation, subdivision to the
//! tolerance, the triangles across a crease split where its two sides meet), an open fit keeps
//! the triangles near the data only, and the mesh becomes a quad net with its edges on the
//! creases ([`crate::polygonize::remesh_net`]). The voxel route puts the voxel net's nodes on
//! the creases ([`crate::polygonize::crease_nodes`]); it cannot follow a crease at an angle to
//! its grid (docs/BENCHMARKS.md: crease max about 1e-2 of the diagonal against 2e-4 to 1e-3).

use crate::features::sharp_field::SharpField;
use crate::implicit::PouImplicit;
use crate::mesh::Mesh;
use crate::polygonize::remesh_net::{remesh_net, RemeshNet, RemeshNetOptions};
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
    Placed(
        crate::polygonize::crease_nodes::CreaseNet,
        crate::polygonize::quad_net::QuadNet,
        usize,
    ),
    Remeshed(crate::polygonize::remesh_net::RemeshNet),
}

impl CreaseNet {
    /// The net, its quads' regions and the number of regions.
    pub fn labelled(&self) -> (&crate::polygonize::quad_net::QuadNet, &[u32], usize) {
        match self {
            CreaseNet::Placed(p, net, regions) => (net, &p.quad_region, *regions),
            CreaseNet::Remeshed(r) => (&r.net, &r.quad_region, r.report.regions),
        }
    }

    pub fn into_net(self) -> crate::polygonize::quad_net::QuadNet {
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
    remesh_net(
        &mesh,
        inputs.f,
        Some(inputs.field),
        diag,
        inputs.open_support.is_some(),
        &RemeshNetOptions::new(inputs.quads),
    )
}

/// The triangles of `mesh` whose three vertices lie within `r` of a point of `tree`, with the
/// vertices they use.
fn supported(mesh: &Mesh, tree: &KdTree, r: f64) -> Mesh {
    let near: Vec<bool> = mesh
        .positions
        .iter()
        .map(|p| tree.nearest(p).1 <= r)
        .collect();
    let faces: Vec<[u32; 3]> = mesh
        .faces
        .iter()
        .filter(|t| t.iter().all(|&v| near[v as usize]))
        .copied()
        .collect();
    let mut index = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let faces = faces
        .into_iter()
        .map(|t| {
            t.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = positions.len() as u32;
                    positions.push(mesh.positions[v as usize]);
                }
                index[v as usize]
            })
        })
        .collect();
    Mesh {
        positions,
        normals: None,
        faces,
    }
}
