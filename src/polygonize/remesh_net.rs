//! The crease-aligned quad net from a crease-preserving remesh (`fit --sharp`, issue 36).
//!
//! The voxel net cannot follow a crease at an angle to its grid (a staircase of quads with
//! three corners on the crease); this route builds the net from a surface mesh instead:
//! 1. the mesh's triangles are labelled by smooth region ([`crate::features::segment_mesh`]:
//!    dihedral angles, regions too small or narrow absorbed);
//!    folds inside a region (a tent of two triangles facing apart, left by the sharp
//!    extraction) are flipped flat ([`crate::mesh::unfold`]);
//! 2. the labelled mesh is remeshed isotropically with its creases kept as edge paths and its
//!    corners pinned ([`crate::mesh::crease_remesh`], Botsch & Kobbelt 2004 with crease
//!    rules), at the edge length L that gives about the requested number of quads, with the
//!    crease edges split further where their chord error exceeds a tolerance, the sizes
//!    graded away from such creases ([`crate::mesh::crease_remesh::sizing`]) and the
//!    triangles made locally Delaunay at the end (fewer obtuse triangles, whose quads are
//!    darts);
//! 3. every triangle is split into three quads ([`super::quad_split`], one Catmull-Clark
//!    topology step): crease edges stay net edges, corners stay nodes, quads keep their
//!    region, and no quad has three corners on one crease.
//!
//! 4. with the sharp implicit's sides given, the nodes (edge midpoints and centroids lie on
//!    chords) are put onto them ([`super::side_projection`]); with the data's local surfaces
//!    given too, a crease or corner node goes between those where they follow their points
//!    about as well as the implicit's sides, unless that folds a quad.
//!
//! The quad count: a triangle of edge L has area sqrt(3)/4 L^2 and gives three quads, so a
//! surface of area A needs L = sqrt(3 A / (sqrt(3)/4 Q)) for Q quads (more where a crease's
//! chord tolerance splits its edges).

use super::crease_nodes::LocalSides;
use super::crease_split::SideField;
use super::net_quality::{folded_quads, net_quality, NetQuality};
use super::quad_net::QuadNet;
use super::quad_split::{split_into_quads, NodeKind};
use super::side_projection::{
    project_onto_sides, region_map, FoldCheck, SideProjectionReport, Sides,
};
use crate::error::Result;
use crate::features::data_sides::DataSides;
use crate::features::segment_mesh::segment_mesh_hinted;
use crate::features::sharp_field::SharpField;
use crate::implicit::Implicit;
use crate::mesh::crease_remesh::{remesh, LabelledMesh, RemeshOptions};
use crate::mesh::unfold::{unfold, UnfoldReport};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Longest move of a node onto the sides, in target edge lengths L (a net edge is L / 2).
pub const MAX_MOVE: f64 = 0.25;

/// Options of [`remesh_net`].
#[derive(Debug, Clone, Copy)]
pub struct RemeshNetOptions {
    /// Quads wanted (before the crease splits).
    pub quads: usize,
    /// Largest chord error of a crease edge, as a fraction of the diagonal (default 2.5e-4,
    /// half the acceptance bar of issue 36 for the crease distance).
    pub crease_tolerance: f64,
    /// Remeshing iterations (default 10).
    pub iterations: usize,
    /// Growth of the target length per unit length away from a finely split crease (default
    /// 0.5; [`crate::mesh::crease_remesh::sizing`]).
    pub grade: f64,
    /// Largest chord error of an edge inside a region, as a fraction of the diagonal, through
    /// the sizing field of the mesh's curvature: curved faces get shorter edges (`None`, the
    /// default for `fit`: the target length alone;
    /// [`crate::mesh::crease_remesh::RemeshOptions::surface_sizing`]).
    pub surface_tolerance: Option<f64>,
    /// Whether a crease node's move onto the sides fitted to the data that folds a quad is
    /// undone (default true: a patch net keeps no new folds;
    /// [`super::side_projection::project_onto_sides`]).
    pub undo_folds: bool,
}

impl RemeshNetOptions {
    pub fn new(quads: usize) -> Self {
        RemeshNetOptions {
            quads,
            crease_tolerance: 2.5e-4,
            iterations: 10,
            grade: 0.5,
            surface_tolerance: None,
            undo_folds: true,
        }
    }
}

/// What [`remesh_net`] did (the report's `crease_remesh`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RemeshNetReport {
    /// Triangles of the surface mesh remeshed, and its smooth regions.
    pub surface_triangles: usize,
    pub regions: usize,
    /// Folds inside a region of the surface mesh, and those flipped flat before the remesh
    /// ([`crate::mesh::unfold`]).
    pub unfold: UnfoldReport,
    /// The remesh's target edge length L and crease chord tolerance (model units).
    pub target_edge: f64,
    pub crease_tolerance: f64,
    /// Triangles after the remesh (each gives three quads).
    pub triangles: usize,
    pub quads: usize,
    pub nodes: usize,
    /// Nodes on one crease, and corners (three regions, a crease's end or a pinned turn).
    pub crease_nodes: usize,
    pub corner_nodes: usize,
    /// Net edges on a crease (or on an open boundary).
    pub crease_edges: usize,
    /// The nodes put onto the sharp implicit's sides (when given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projection: Option<SideProjectionReport>,
    /// The net's shape on the implicit the mesh came from (flipped and degenerate quads:
    /// folds).
    pub quality: NetQuality,
}

/// The remesh's target edge length for `quads` quads on `mesh`: three quads per equilateral
/// triangle of that edge, the triangles covering the mesh's area.
pub fn target_edge(mesh: &Mesh, quads: usize) -> f64 {
    let area: f64 = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).sum();
    let per_triangle = 3f64.sqrt() / 4.0;
    (3.0 * area / (per_triangle * quads.max(1) as f64)).sqrt()
}

/// Radius, in target edges of the remesh, of the data fitted around a crease or corner node
/// for the surfaces it is put between ([`crate::features::data_sides`]).
pub const DATA_SIDES_RADIUS: f64 = 1.5;

/// The data's local surfaces around the nodes of a net of `quads` quads on `mesh`.
pub fn data_sides<'a>(field: &SharpField<'a>, mesh: &Mesh, quads: usize) -> DataSides<'a> {
    DataSides {
        seg: field.seg,
        radius: DATA_SIDES_RADIUS * target_edge(mesh, quads),
    }
}

/// The crease-aligned net and its labels.
#[derive(Debug, Clone)]
pub struct RemeshNet {
    pub net: QuadNet,
    /// Region of each quad.
    pub quad_region: Vec<u32>,
    /// Role of each node.
    pub node_kinds: Vec<NodeKind>,
    pub report: RemeshNetReport,
}

/// Builds the crease-aligned quad net of the surface `mesh` (module doc), the zero set of `f`
/// (the net's quality is measured on it); `diagonal` is the model's size the tolerance is a
/// fraction of, `open` accepts a mesh with boundary edges (which count as creases). With
/// `sides` (the sharp implicit's), the nodes are then put onto them
/// ([`super::side_projection`]).
pub fn remesh_net<I: Implicit + ?Sized>(
    mesh: &Mesh,
    f: &I,
    sides: Option<&dyn SideField>,
    data: Option<&dyn LocalSides>,
    diagonal: f64,
    open: bool,
    opts: &RemeshNetOptions,
) -> Result<RemeshNet> {
    // The sides' regions (the input data's segmentation) keep a true face narrower than the
    // mesh's edges from being absorbed by its neighbour.
    let hint: Option<Vec<u32>> = sides.map(|field| {
        (0..mesh.faces.len())
            .into_par_iter()
            .map(|f| field.region(&mesh.face_centroid(f)))
            .collect()
    });
    let seg = segment_mesh_hinted(mesh, &Default::default(), hint.as_deref())?;
    let target = target_edge(mesh, opts.quads);
    let mut ro = RemeshOptions::new(target);
    ro.iterations = opts.iterations;
    ro.crease_tolerance = Some(opts.crease_tolerance * diagonal);
    ro.grade = Some(opts.grade);
    ro.surface_sizing = opts.surface_tolerance.map(|t| t * diagonal);
    ro.delaunay = true;
    ro.clean_slivers = true;
    let mut labelled = LabelledMesh {
        positions: mesh.positions.clone(),
        triangles: mesh.faces.clone(),
        labels: seg.face_label,
    };
    let unfolded = unfold(&mut labelled);
    let out = remesh(&labelled, &ro)?;
    let polygons: Vec<Vec<u32>> = out.triangles.iter().map(|t| t.to_vec()).collect();
    let mut split = split_into_quads(&out.positions, &polygons, &out.labels, open)?;
    let fold_check = |net: &QuadNet| folded_quads(net, f, diagonal, 0.5 * target);
    let projection = sides.map(|field| {
        let map = region_map(&split.net, &split.quad_labels, seg.regions, field);
        project_onto_sides(
            &mut split.net,
            &split.quad_labels,
            &map,
            Sides { field, data },
            0.5 * target,
            MAX_MOVE * target,
            opts.undo_folds.then_some(&fold_check as &FoldCheck),
        )
    });
    let count = |k: NodeKind| split.node_kinds.iter().filter(|&&x| x == k).count();
    // The quads' nominal edge: half a triangle's.
    let quality = net_quality(&split.net, f, diagonal, 0.5 * target);
    let report = RemeshNetReport {
        surface_triangles: mesh.faces.len(),
        regions: seg.regions,
        unfold: unfolded,
        target_edge: target,
        crease_tolerance: opts.crease_tolerance * diagonal,
        triangles: out.triangles.len(),
        quads: split.net.quads.len(),
        nodes: split.net.nodes.len(),
        crease_nodes: count(NodeKind::Crease),
        corner_nodes: count(NodeKind::Corner),
        crease_edges: split.crease_edges.iter().filter(|&&c| c).count(),
        projection,
        quality,
    };
    Ok(RemeshNet {
        net: split.net,
        quad_region: split.quad_labels,
        node_kinds: split.node_kinds,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Vector3};

    /// A closed cylinder of radius 1 on z in [0, 1]: the wall (region 0), top (1), bottom (2).
    struct Cylinder;
    impl Cylinder {
        fn sides(x: &Point3<f64>) -> [(f64, Vector3<f64>); 3] {
            let r = x.x.hypot(x.y).max(1e-300);
            [
                (r - 1.0, Vector3::new(x.x / r, x.y / r, 0.0)),
                (x.z - 1.0, Vector3::z()),
                (-x.z, -Vector3::z()),
            ]
        }
    }
    impl SideField for Cylinder {
        fn region(&self, x: &Point3<f64>) -> u32 {
            let s = Self::sides(x);
            (0..3)
                .min_by(|&a, &b| s[a].0.abs().total_cmp(&s[b].0.abs()))
                .unwrap_or(0) as u32
        }
        fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
            Self::sides(x)[region as usize]
        }
    }
    impl Implicit for Cylinder {
        fn value(&self, x: &Point3<f64>) -> f64 {
            Self::sides(x).iter().map(|s| s.0).fold(f64::MIN, f64::max)
        }
    }

    /// The cylinder as a mesh: `n` segments around, `m` rows up, caps fanned from their
    /// centres; counter-clockwise from outside.
    fn cylinder_mesh(n: usize, m: usize) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..=m {
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                positions.push(Point3::new(a.cos(), a.sin(), j as f64 / m as f64));
            }
        }
        let ring = |i: usize, j: usize| (j * n + i % n) as u32;
        let mut faces = Vec::new();
        for j in 0..m {
            for i in 0..n {
                faces.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                faces.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        let (bottom, top) = (positions.len() as u32, positions.len() as u32 + 1);
        positions.push(Point3::new(0.0, 0.0, 0.0));
        positions.push(Point3::new(0.0, 0.0, 1.0));
        for i in 0..n {
            faces.push([bottom, ring(i + 1, 0), ring(i, 0)]);
            faces.push([top, ring(i, m), ring(i + 1, m)]);
        }
        Mesh {
            positions,
            normals: None,
            faces,
        }
    }

    /// The net's edges follow the two round creases, and with the sides given every node lies
    /// on its surfaces (the crease nodes on the circles), which the chords' midpoints and
    /// centroids do not without them.
    #[test]
    fn cylinder_net_lies_on_its_sides_and_creases() {
        let mesh = cylinder_mesh(96, 16);
        let diag = 5f64.sqrt();
        let opts = RemeshNetOptions::new(400);
        let off = |net: &QuadNet| {
            net.nodes
                .iter()
                .map(|p| Cylinder.value(p).abs())
                .fold(0.0, f64::max)
        };
        let plain = remesh_net(&mesh, &Cylinder, None, None, diag, false, &opts).unwrap();
        assert!(off(&plain.net) > 1e-2, "{}", off(&plain.net));
        let on = remesh_net(&mesh, &Cylinder, Some(&Cylinder), None, diag, false, &opts).unwrap();
        let r = &on.report;
        assert_eq!(r.regions, 3, "{r:?}");
        assert_eq!(r.corner_nodes, 0, "{r:?}");
        // The rims' chord tolerance (2.5e-4 of the diagonal) asks for edges of
        // sqrt(8 R t) = 0.067, about 94 per rim, and the sizes grade away from them: far more
        // quads than the 400 asked for, on a part this small.
        assert!(
            r.crease_edges > 300 && r.quads > 400 && r.quads < 6000,
            "{r:?}"
        );
        let p = r.projection.unwrap();
        assert_eq!(p.kept, 0, "{p:?}");
        assert_eq!(p.crease_nodes, r.crease_nodes, "{p:?}");
        // (Within the Newton tolerance, 1e-4 of the edge length.)
        assert!(off(&on.net) < 1e-4, "{}", off(&on.net));
        for (p, k) in on.net.nodes.iter().zip(&on.node_kinds) {
            if *k == NodeKind::Crease {
                let z = p.z.min(1.0 - p.z).abs();
                assert!((p.x.hypot(p.y) - 1.0).abs() < 1e-6 && z < 1e-6, "{p}");
            }
        }
        // Every quad lies on one side and the net keeps its shape.
        assert_eq!(r.quality.flipped, 0, "{:?}", r.quality);
        assert_eq!(r.quality.degenerate, 0, "{:?}", r.quality);
    }
}
