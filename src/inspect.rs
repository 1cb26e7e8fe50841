//! What `scansurf inspect` reports about a mesh or point cloud: counts, boundary loops, defects,
//! bounds, and a one-line verdict.

use crate::mesh::{Aabb, Mesh};
use serde::Serialize;

/// One boundary loop as reported.
#[derive(Debug, Clone, Serialize)]
pub struct LoopInfo {
    pub vertices: usize,
    pub length: f64,
    /// "hole" or "border" (the outer border of an open sheet).
    pub kind: &'static str,
    pub twisted: bool,
}

/// The inspection of one file.
#[derive(Debug, Clone, Serialize)]
pub struct Inspection {
    pub file: String,
    pub vertices: usize,
    pub referenced_vertices: usize,
    pub unreferenced_vertices: usize,
    pub faces: usize,
    pub has_normals: bool,
    pub components: usize,
    pub boundary_loops: Vec<LoopInfo>,
    pub holes: usize,
    pub boundary_edges: usize,
    pub non_manifold_edges: usize,
    pub non_manifold_vertices: usize,
    pub misoriented_edges: usize,
    pub degenerate_faces: usize,
    pub duplicate_vertices: usize,
    pub bbox: Option<Aabb>,
    pub bbox_diagonal: f64,
    pub mean_edge_length: f64,
    /// Euler characteristic V - E + F over referenced vertices (meshes only).
    pub euler_characteristic: Option<i64>,
    /// Scans in a scanner file (E57 point clouds; 1 for LAS/LAZ); `None` for other formats.
    pub scans: Option<usize>,
    pub verdict: String,
}

/// Inspects a mesh (or point cloud) read from `file`.
pub fn inspect(file: &str, mesh: &Mesh) -> Inspection {
    let bbox = mesh.aabb();
    let diag = bbox.map(|b| b.diagonal()).unwrap_or(0.0);
    if mesh.is_point_cloud() {
        return Inspection {
            file: file.to_string(),
            vertices: mesh.positions.len(),
            referenced_vertices: mesh.positions.len(),
            unreferenced_vertices: 0,
            faces: 0,
            has_normals: mesh.normals.is_some(),
            components: 0,
            boundary_loops: vec![],
            holes: 0,
            boundary_edges: 0,
            non_manifold_edges: 0,
            non_manifold_vertices: 0,
            misoriented_edges: 0,
            degenerate_faces: 0,
            duplicate_vertices: crate::mesh::Topology::build(mesh).duplicate_vertices,
            bbox,
            bbox_diagonal: diag,
            mean_edge_length: 0.0,
            euler_characteristic: None,
            scans: None,
            verdict: format!(
                "point cloud: {} points{}",
                mesh.positions.len(),
                if mesh.normals.is_some() {
                    " with normals"
                } else {
                    ""
                }
            ),
        };
    }
    let t = mesh.topology();
    let loops: Vec<LoopInfo> = t
        .loops
        .iter()
        .map(|l| LoopInfo {
            vertices: l.vertices.len(),
            length: l.length,
            kind: if l.outer_border { "border" } else { "hole" },
            twisted: l.twisted,
        })
        .collect();
    let holes = loops.iter().filter(|l| l.kind == "hole").count();
    let borders = loops.len() - holes;
    let referenced = mesh.positions.len() - t.unreferenced_vertices;
    let euler = referenced as i64 - t.edges.len() as i64 + mesh.faces.len() as i64;

    let mut parts: Vec<String> = Vec::new();
    if !t.non_manifold_edges.is_empty() || !t.non_manifold_vertices.is_empty() {
        parts.push(format!(
            "non-manifold: {} edges, {} vertices",
            t.non_manifold_edges.len(),
            t.non_manifold_vertices.len()
        ));
    }
    if t.misoriented_edges > 0 {
        parts.push(format!(
            "inconsistent orientation at {} edges",
            t.misoriented_edges
        ));
    }
    if loops.is_empty() {
        if parts.is_empty() {
            parts.push("closed manifold".into());
        } else {
            parts.push("closed".into());
        }
    } else {
        let plural = |n: usize, w: &str| format!("{n} {w}{}", if n == 1 { "" } else { "s" });
        match (borders, holes) {
            (0, h) => parts.push(format!("open: {}", plural(h, "hole"))),
            (b, 0) => parts.push(format!("open sheet: {}", plural(b, "border"))),
            (b, h) => parts.push(format!(
                "open sheet: {}, {}",
                plural(b, "border"),
                plural(h, "hole")
            )),
        }
    }
    if t.components.len() > 1 {
        parts.push(format!("{} components", t.components.len()));
    }
    if !t.degenerate_faces.is_empty() {
        parts.push(format!("{} degenerate faces", t.degenerate_faces.len()));
    }
    Inspection {
        file: file.to_string(),
        vertices: mesh.positions.len(),
        referenced_vertices: referenced,
        unreferenced_vertices: t.unreferenced_vertices,
        faces: mesh.faces.len(),
        has_normals: mesh.normals.is_some(),
        components: t.components.len(),
        holes,
        boundary_edges: t.boundary_edge_count(),
        boundary_loops: loops,
        non_manifold_edges: t.non_manifold_edges.len(),
        non_manifold_vertices: t.non_manifold_vertices.len(),
        misoriented_edges: t.misoriented_edges,
        degenerate_faces: t.degenerate_faces.len(),
        duplicate_vertices: t.duplicate_vertices,
        bbox,
        bbox_diagonal: diag,
        mean_edge_length: mesh.mean_edge_length(),
        euler_characteristic: Some(euler),
        scans: None,
        verdict: parts.join("; "),
    }
}

impl Inspection {
    /// Human-readable multi-line summary.
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(s, "{}: {}", self.file, self.verdict);
        if let Some(n) = self.scans {
            let _ = writeln!(s, "  scans: {n}");
        }
        let _ = writeln!(
            s,
            "  vertices: {} ({} referenced, {} unreferenced, {} duplicate positions)",
            self.vertices,
            self.referenced_vertices,
            self.unreferenced_vertices,
            self.duplicate_vertices
        );
        let _ = writeln!(
            s,
            "  faces: {}  components: {}  normals: {}",
            self.faces,
            self.components,
            if self.has_normals { "yes" } else { "no" }
        );
        if let Some(b) = &self.bbox {
            let _ = writeln!(
                s,
                "  bounds: [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]  diagonal {:.6}",
                b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z, self.bbox_diagonal
            );
        }
        if self.faces > 0 {
            let _ = writeln!(
                s,
                "  mean edge length: {:.6}  Euler characteristic: {}",
                self.mean_edge_length,
                self.euler_characteristic.unwrap_or(0)
            );
            let _ = writeln!(
                s,
                "  boundary loops: {} ({} holes), {} boundary edges",
                self.boundary_loops.len(),
                self.holes,
                self.boundary_edges
            );
            for (i, l) in self.boundary_loops.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "    #{:<3} {:<6} {:>6} vertices  length {:.6}{}",
                    i + 1,
                    l.kind,
                    l.vertices,
                    l.length,
                    if l.twisted { "  (twisted)" } else { "" }
                );
            }
            let _ = writeln!(
                s,
                "  non-manifold edges: {}  non-manifold vertices: {}  misoriented edges: {}  degenerate faces: {}",
                self.non_manifold_edges,
                self.non_manifold_vertices,
                self.misoriented_edges,
                self.degenerate_faces
            );
        }
        s
    }
}
