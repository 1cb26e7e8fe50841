//! `reconstruct --remesh`: the sharp implicit's mesh as a light triangle mesh whose edges run
//! on the creases and whose vertices lie on the regions' surfaces (issue 35 item 4).
//!
//! Marching cubes and the split at the creases leave a mesh of half a million to 1.7 million
//! triangles on a make_parts part, its crease a zigzag of split points up to 1e-3 of the
//! diagonal off the true edge where the split points of neighbouring triangles disagree. Here
//! that mesh goes through the crease-aligned net of `fit --sharp`
//! ([`super::remesh_net`]: segmentation, a crease-preserving isotropic remesh at the length L
//! of [`QUADS`] quads, graded finer along curved creases and, inside a region, finer where
//! the mesh's curvature would put a chord more than [`SURFACE_TOLERANCE`] of the diagonal
//! off it ([`crate::mesh::crease_remesh::sizing`]), every triangle split into
//! three quads, every node put onto its region's side, crease and
//! corner nodes onto the meeting of the sides fitted to the data around them), and each quad
//! is cut along its shorter diagonal into two triangles. Crease edges are quad edges, so they
//! stay mesh edges.
//!
//! The sizes: a flat-shaded triangle of edge s on a cylinder of radius R is off the surface by
//! the sagitta s^2 / (8 R) and its normal by up to s / (2 R) at its edges; the surface
//! tolerance t makes s = sqrt(8 t / k) with the ring-averaged curvature k, about 2 / (pi R)
//! on a cylinder, so s is about sqrt(4 pi R t) and the normal error stays under
//! sqrt(pi t / R): 4 degrees on a 10 mm hole of a 76 mm part at t = 1e-4 of the diagonal,
//! less inside the triangles (the 22 make_parts inputs: 95 % of the faces' samples within
//! 1.9 degrees).

use super::quad_net::QuadNet;
use super::remesh_net::{data_sides, remesh_net, RemeshNetOptions, RemeshNetReport};
use crate::error::Result;
use crate::features::sharp_field::SharpField;
use crate::implicit::PouImplicit;
use crate::mesh::crease_remesh::{self, LabelledMesh};
use crate::mesh::Mesh;

/// Quads of the net the mesh is cut from before the creases' and the faces' tolerances split
/// it further (make_parts' parts: 25-124 k triangles at the end). A finer net (20,000) moved
/// more crease nodes onto wrong corners of the input mesh (13 of 22 parts within the crease
/// bar of 5e-4 of the diagonal, against 16 at 5,000).
pub const QUADS: usize = 5000;

/// Largest chord error of an edge inside a region, fraction of the diagonal (module doc).
pub const SURFACE_TOLERANCE: f64 = 1e-4;

/// What [`crease_mesh`] did (the reconstruct report's `remesh`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CreaseMeshReport {
    /// The net the mesh was cut from.
    #[serde(flatten)]
    pub net: RemeshNetReport,
    /// Slivers of the cut mesh removed by flips and collapses
    /// ([`crate::mesh::crease_remesh::clean`]).
    pub slivers_repaired: usize,
}

/// The crease-aligned triangle mesh of `mesh`, a mesh of the sharp implicit `f` with sides
/// `field` (module doc), and what the remesh did.
///
/// Putting the nodes onto the sides moves some of them onto their neighbours (two crease
/// nodes onto one corner) or onto the line through two others, so a few triangles of the cut
/// come out degenerate (13 of 70,000 on stepped.stl); the remesh's sliver clean-up, run once
/// more on the cut mesh labelled by its quads' regions, removes them.
pub fn crease_mesh(
    mesh: &Mesh,
    f: &PouImplicit,
    field: &SharpField,
) -> Result<(Mesh, CreaseMeshReport)> {
    let diagonal = f.diagonal();
    let data = data_sides(field, mesh, QUADS);
    let mut opts = RemeshNetOptions::new(QUADS);
    opts.surface_tolerance = Some(SURFACE_TOLERANCE);
    // Folds the data-fitted crease moves make are left to the sliver clean-up below rather
    // than undone (crease max on hexnut.stl 1.6e-3 -> 2.3e-4 of the diagonal, lplate.stl
    // 1.2e-3 -> 5.6e-5; docs/BENCHMARKS.md).
    opts.undo_folds = false;
    let net = remesh_net(mesh, f, Some(field), Some(&data), diagonal, false, &opts)?;
    let labelled = LabelledMesh {
        triangles: triangulate(&net.net),
        labels: net.quad_region.iter().flat_map(|&r| [r, r]).collect(),
        positions: net.net.nodes,
    };
    let (clean, slivers_repaired) = crease_remesh::clean(
        &labelled,
        net.report.target_edge,
        Some(net.report.crease_tolerance),
    )?;
    let out = Mesh {
        positions: clean.positions,
        normals: None,
        faces: clean.triangles,
    };
    let report = CreaseMeshReport {
        net: net.report,
        slivers_repaired,
    };
    Ok((out, report))
}

/// Two triangles per quad, cut along the shorter diagonal (the flatter cut on a curved
/// surface, and the one that keeps the larger of the smallest angles on a near-rectangle);
/// orientation as the quad's.
pub fn triangulate(net: &QuadNet) -> Vec<[u32; 3]> {
    let mut faces = Vec::with_capacity(2 * net.quads.len());
    for q in &net.quads {
        let p = |i: usize| net.nodes[q[i] as usize];
        if (p(0) - p(2)).norm_squared() <= (p(1) - p(3)).norm_squared() {
            faces.push([q[0], q[1], q[2]]);
            faces.push([q[0], q[2], q[3]]);
        } else {
            faces.push([q[0], q[1], q[3]]);
            faces.push([q[1], q[2], q[3]]);
        }
    }
    faces
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    /// A long thin quad is cut along its short diagonal, and both triangles keep the quad's
    /// orientation (their normals point the quad's way).
    #[test]
    fn quads_are_cut_along_the_short_diagonal() {
        // A rhombus, long along x: the diagonal 1-3 (along y) is the short one.
        let nodes = vec![
            Point3::new(-2.0, 0.0, 0.0),
            Point3::new(0.0, -0.5, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(0.0, 0.5, 0.0),
        ];
        let net = QuadNet::new_open(nodes.clone(), vec![[0, 1, 2, 3]]).unwrap();
        let t = triangulate(&net);
        assert_eq!(t, vec![[0, 1, 3], [1, 2, 3]]);
        for tri in &t {
            let [a, b, c] = tri.map(|i| nodes[i as usize]);
            assert!((b - a).cross(&(c - a)).z > 0.0, "{tri:?}");
        }
        // The same quad started one corner on: now its corners 0 and 2 span the short one.
        let net = QuadNet::new_open(nodes, vec![[1, 2, 3, 0]]).unwrap();
        assert_eq!(triangulate(&net), vec![[1, 2, 3], [1, 3, 0]]);
    }
}
