//! A labelled triangle or quad-dominant mesh split into an all-quad net whose crease edges are
//! net edges (issue 36, the net from a crease-preserving surface mesh).
//!
//! One step of Catmull-Clark's topology (Catmull & Clark 1978), positions left linear: every
//! polygon with corners v_0 .. v_{k-1} (k = 3 or 4) gets a face point c (the mean of its
//! corners), every edge (a, b) an edge point m_ab = (a + b) / 2, and the polygon becomes k quads
//!
//! ```text
//!   [v_i, m_{i,i+1}, c, m_{i-1,i}],   i = 0 .. k-1,
//! ```
//!
//! oriented as the polygon. Every input edge becomes two net edges on the same segment, so an
//! edge between polygons of two regions (a crease of the surface mesh) stays a path of net
//! edges, and every input vertex stays a node: a corner where three regions meet stays a node.
//! A triangle gives three quads around a node of valence 3, a quad four around one of valence
//! 4; input vertices keep their valence. The positions are those of the mesh (chord midpoints,
//! face centres); moving the new nodes onto the surface and the crease nodes onto their crease
//! is the caller's.

use super::quad_net::QuadNet;
use crate::error::Result;
use nalgebra::Point3;
use std::collections::HashMap;

/// What a node of the split net lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeKind {
    /// Inside one region.
    Face,
    /// On a crease between two regions (or on an open boundary).
    Crease,
    /// An input vertex where three or more regions meet, or where creases end.
    Corner,
}

/// The split net with what the patch step needs about its creases.
#[derive(Debug, Clone)]
pub struct SplitNet {
    pub net: QuadNet,
    /// Region of each quad (that of its polygon).
    pub quad_labels: Vec<u32>,
    /// Per net edge ([`QuadNet::edges`]): true on a crease or open boundary.
    pub crease_edges: Vec<bool>,
    /// Per node.
    pub node_kinds: Vec<NodeKind>,
}

/// Splits `polygons` (3 or 4 vertex indices into `positions`, counter-clockwise seen from
/// outside; `labels` their regions) into quads. `open` accepts a mesh with boundary edges
/// (a partial scan), which count as creases. Errors when a polygon has another size or a bad
/// index, or when the result is not a consistently oriented 2-manifold ([`QuadNet::new`]).
pub fn split_into_quads(
    positions: &[Point3<f64>],
    polygons: &[Vec<u32>],
    labels: &[u32],
    open: bool,
) -> Result<SplitNet> {
    use crate::error::Error;
    if labels.len() != polygons.len() {
        return Err(Error::Degenerate(format!(
            "quad split: {} labels for {} polygons",
            labels.len(),
            polygons.len()
        )));
    }
    let mut nodes: Vec<Point3<f64>> = positions.to_vec();
    // Edge point of each undirected input edge, and the labels of the polygons on it.
    let mut edge_point: HashMap<(u32, u32), (u32, Vec<u32>)> = HashMap::new();
    let mut quads = Vec::new();
    let mut quad_labels = Vec::new();
    for (p, (poly, &label)) in polygons.iter().zip(labels).enumerate() {
        if !(3..=4).contains(&poly.len()) {
            return Err(Error::Degenerate(format!(
                "quad split: polygon {p} has {} corners (3 or 4 expected)",
                poly.len()
            )));
        }
        if let Some(&bad) = poly.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(Error::Degenerate(format!(
                "quad split: polygon {p} names vertex {bad} of {}",
                positions.len()
            )));
        }
        let k = poly.len();
        let centre = Point3::from(
            poly.iter()
                .map(|&v| positions[v as usize].coords)
                .sum::<nalgebra::Vector3<f64>>()
                / k as f64,
        );
        let c = nodes.len() as u32;
        nodes.push(centre);
        let mut mids = Vec::with_capacity(k);
        for i in 0..k {
            let (a, b) = (poly[i], poly[(i + 1) % k]);
            let key = (a.min(b), a.max(b));
            let entry = edge_point.entry(key).or_insert_with(|| {
                let m = nodes.len() as u32;
                nodes.push(nalgebra::center(
                    &positions[a as usize],
                    &positions[b as usize],
                ));
                (m, Vec::new())
            });
            entry.1.push(label);
            mids.push(entry.0);
        }
        for i in 0..k {
            quads.push([poly[i], mids[i], c, mids[(i + k - 1) % k]]);
            quad_labels.push(label);
        }
    }
    let net = if open {
        QuadNet::new_open(nodes, quads)?
    } else {
        QuadNet::new(nodes, quads)?
    };

    // Crease edges: the halves of input edges between two regions or on the boundary.
    let mut crease_point = vec![false; net.nodes.len()];
    for (m, labs) in edge_point.values() {
        crease_point[*m as usize] = labs.len() < 2 || labs.iter().any(|&l| l != labs[0]);
    }
    let crease_edges: Vec<bool> = net
        .edges
        .iter()
        .map(|&[a, b]| {
            // One end is an edge point (the other an input vertex or a face point): a net edge
            // along an input edge joins an input vertex to that edge's point.
            let input = positions.len() as u32;
            let (v, m) = if a < input { (b, a) } else { (a, b) };
            m < input && crease_point[v as usize]
        })
        .collect();

    // Node kinds: an input vertex by the regions around it and its crease edges.
    let mut node_kinds = vec![NodeKind::Face; net.nodes.len()];
    for (i, kind) in node_kinds.iter_mut().enumerate() {
        if crease_point[i] {
            *kind = NodeKind::Crease;
        }
    }
    let mut creases_at = vec![0u32; positions.len()];
    let mut regions_at: Vec<Vec<u32>> = vec![Vec::new(); positions.len()];
    for (e, &[a, b]) in net.edges.iter().enumerate() {
        if crease_edges[e] {
            let v = a.min(b) as usize;
            creases_at[v] += 1;
        }
    }
    for (q, quad) in net.quads.iter().enumerate() {
        let v = quad[0] as usize;
        if !regions_at[v].contains(&quad_labels[q]) {
            regions_at[v].push(quad_labels[q]);
        }
    }
    for v in 0..positions.len() {
        node_kinds[v] = match (regions_at[v].len(), creases_at[v]) {
            (r, _) if r >= 3 => NodeKind::Corner,
            (_, 0) => NodeKind::Face,
            (_, 2) => NodeKind::Crease,
            _ => NodeKind::Corner,
        };
    }
    Ok(SplitNet {
        net,
        quad_labels,
        crease_edges,
        node_kinds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> (Vec<Point3<f64>>, Vec<Vec<u32>>) {
        let p: Vec<Point3<f64>> = (0..8)
            .map(|i| Point3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        // Counter-clockwise seen from outside.
        let faces = vec![
            vec![0, 2, 3, 1], // z = 0
            vec![4, 5, 7, 6], // z = 1
            vec![0, 1, 5, 4], // y = 0
            vec![2, 6, 7, 3], // y = 1
            vec![0, 4, 6, 2], // x = 0
            vec![1, 3, 7, 5], // x = 1
        ];
        (p, faces)
    }

    #[test]
    fn a_cube_s_faces_give_a_net_with_its_edges_and_corners() {
        let (p, faces) = cube();
        let s = split_into_quads(&p, &faces, &[0, 1, 2, 3, 4, 5], false).unwrap();
        assert_eq!(s.net.quads.len(), 24);
        assert_eq!(s.net.nodes.len(), 8 + 12 + 6);
        assert_eq!(s.net.euler_characteristic(), 2);
        assert_eq!(s.crease_edges.iter().filter(|&&c| c).count(), 24);
        let count = |k| s.node_kinds.iter().filter(|&&n| n == k).count();
        assert_eq!(count(NodeKind::Corner), 8);
        assert_eq!(count(NodeKind::Crease), 12);
        assert_eq!(count(NodeKind::Face), 6);
        // Every crease edge lies on a cube edge: both ends share two coordinates in {0, 1}.
        for (e, &[a, b]) in s.net.edges.iter().enumerate() {
            let (pa, pb) = (s.net.nodes[a as usize], s.net.nodes[b as usize]);
            let on_cube_edge =
                |q: Point3<f64>| q.iter().filter(|&&x| x == 0.0 || x == 1.0).count() >= 2;
            assert_eq!(s.crease_edges[e], on_cube_edge(pa) && on_cube_edge(pb));
        }
    }

    #[test]
    fn a_single_region_has_no_creases_and_triangles_give_valence_3_centres() {
        let (p, faces) = cube();
        // Each cube face cut into two triangles, all of one region.
        let tris: Vec<Vec<u32>> = faces
            .iter()
            .flat_map(|f| [vec![f[0], f[1], f[2]], vec![f[0], f[2], f[3]]])
            .collect();
        let s = split_into_quads(&p, &tris, &[7; 12], false).unwrap();
        assert_eq!(s.net.quads.len(), 36);
        assert!(s.crease_edges.iter().all(|&c| !c));
        assert!(s.node_kinds.iter().all(|&k| k == NodeKind::Face));
        // Corner 2 of every quad is its triangle's face point.
        for q in &s.net.quads {
            assert_eq!(s.net.valence(q[2] as usize), 3);
        }
    }

    #[test]
    fn an_open_sheet_s_border_is_a_crease() {
        let p = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        let s = split_into_quads(&p, &[vec![0, 1, 2, 3]], &[0], true).unwrap();
        assert_eq!(s.crease_edges.iter().filter(|&&c| c).count(), 8);
        assert!(s.node_kinds[..4].iter().all(|&k| k == NodeKind::Crease));
        assert_eq!(s.node_kinds[4], NodeKind::Face);
    }

    #[test]
    fn bad_polygons_are_errors_naming_them() {
        let (p, _) = cube();
        let e = split_into_quads(&p, &[vec![0, 1]], &[0], true).unwrap_err();
        assert!(e.to_string().contains("polygon 0 has 2 corners"), "{e}");
        let e = split_into_quads(&p, &[vec![0, 1, 9]], &[0], true).unwrap_err();
        assert!(e.to_string().contains("names vertex 9"), "{e}");
    }
}
