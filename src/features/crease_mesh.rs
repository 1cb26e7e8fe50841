//! Crease polylines and corners of a triangle mesh from its smooth regions
//! ([`super::segment_mesh`]): a mesh of a machined part keeps its sharp edges as mesh edges, so
//! the creases are the mesh edges whose two triangles belong to different regions, chained
//! through the vertices where exactly two such edges of the same region pair meet.
//!
//! A chain ends at a *corner* (a vertex whose triangles belong to three or more regions, or
//! where three or more crease edges meet), at a vertex where the pair of regions changes, at
//! the end of a crease that fades out, or closes on itself (the rim of a hole). A chain that
//! turns by more than `turn_deg` at one vertex (measured between chords two edges long on
//! each side, so that a mesh's zigzag along a straight edge does not count) is split there and
//! the vertex is a corner too.
//!
//! Each polyline's angle is the length-weighted mean dihedral angle (between the two
//! triangles' unit normals) of its edges.

use super::lines::{cluster, Crease};
use super::segment_mesh::MeshLabels;
use crate::mesh::adjacency::Adjacency;
use crate::mesh::Mesh;
use crate::Result;
use nalgebra::{Point3, Vector3};

/// Creases and corners of `mesh` whose faces are labelled by `labels`.
pub fn mesh_creases(
    mesh: &Mesh,
    labels: &MeshLabels,
    turn_deg: f64,
) -> Result<(Vec<Crease>, Vec<Point3<f64>>)> {
    let adj = Adjacency::build(mesh)?;
    let fl = &labels.face_label;
    let normal = |f: u32| mesh.face_cross(f as usize).try_normalize(1e-300);
    // Crease edges: (vertex a, vertex b, pair, dihedral degrees, length).
    struct Edge {
        v: [u32; 2],
        pair: (u32, u32),
        angle: f64,
        len: f64,
    }
    let mut edges = Vec::new();
    let mut at: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
    for (e, &[a, b]) in adj.edges.iter().enumerate() {
        let &[f, g] = adj.faces_of_edge(e) else {
            continue;
        };
        let (la, lb) = (fl[f as usize], fl[g as usize]);
        if la == lb {
            continue;
        }
        let angle = match (normal(f), normal(g)) {
            (Some(n), Some(m)) => n.dot(&m).clamp(-1.0, 1.0).acos().to_degrees(),
            _ => 0.0,
        };
        let len = (mesh.positions[a as usize] - mesh.positions[b as usize]).norm();
        at[a as usize].push(edges.len() as u32);
        at[b as usize].push(edges.len() as u32);
        edges.push(Edge {
            v: [a, b],
            pair: (la.min(lb), la.max(lb)),
            angle,
            len,
        });
    }
    // Corners: three or more regions around a vertex, or three or more crease edges.
    let mut corner = vec![false; mesh.positions.len()];
    for (v, c) in corner.iter_mut().enumerate() {
        if at[v].is_empty() {
            continue;
        }
        let mut regions: Vec<u32> = adj
            .faces_of_vertex(v)
            .iter()
            .map(|&f| fl[f as usize])
            .collect();
        regions.sort_unstable();
        regions.dedup();
        *c = regions.len() >= 3 || at[v].len() >= 3;
    }
    let stop = |v: usize| {
        corner[v] || at[v].len() != 2 || {
            let (e0, e1) = (&edges[at[v][0] as usize], &edges[at[v][1] as usize]);
            e0.pair != e1.pair
        }
    };
    // Walk chains from every stop vertex, then the loops that have none.
    let mut used = vec![false; edges.len()];
    let mut chains: Vec<(Vec<u32>, Vec<u32>, bool)> = Vec::new(); // vertices, edges, closed
    let walk = |start: u32, first: u32, used: &mut Vec<bool>| {
        let mut verts = vec![start];
        let mut es = Vec::new();
        let (mut v, mut e) = (start, first);
        loop {
            used[e as usize] = true;
            es.push(e);
            let [a, b] = edges[e as usize].v;
            v = if a == v { b } else { a };
            verts.push(v);
            if v == start || stop(v as usize) {
                break;
            }
            match at[v as usize].iter().find(|&&x| !used[x as usize]) {
                Some(&x) => e = x,
                None => break,
            }
        }
        let closed = verts.len() > 2 && verts[0] == verts[verts.len() - 1];
        (verts, es, closed)
    };
    for (v, around) in at.iter().enumerate() {
        if around.is_empty() || !stop(v) {
            continue;
        }
        for &e in around {
            if !used[e as usize] {
                chains.push(walk(v as u32, e, &mut used));
            }
        }
    }
    for e in 0..edges.len() {
        if !used[e] {
            let start = edges[e].v[0];
            chains.push(walk(start, e as u32, &mut used));
        }
    }
    // Split at sharp turns; those vertices become corners.
    let pos = |v: u32| mesh.positions[v as usize];
    let cos_turn = turn_deg.to_radians().cos();
    let mut corners: Vec<Point3<f64>> = (0..mesh.positions.len())
        .filter(|&v| corner[v])
        .map(|v| mesh.positions[v])
        .collect();
    let mut creases = Vec::new();
    for (verts, es, closed) in chains {
        let mut pieces: Vec<(usize, usize)> = Vec::new();
        let mut from = 0;
        let n = verts.len();
        for i in 2..n.saturating_sub(2) {
            let din: Vector3<f64> = pos(verts[i]) - pos(verts[i - 2]);
            let dout: Vector3<f64> = pos(verts[i + 2]) - pos(verts[i]);
            let (Some(a), Some(b)) = (din.try_normalize(1e-300), dout.try_normalize(1e-300)) else {
                continue;
            };
            if a.dot(&b) < cos_turn && i - from >= 2 {
                pieces.push((from, i));
                corners.push(pos(verts[i]));
                from = i;
            }
        }
        pieces.push((from, n - 1));
        let whole_loop = closed && pieces.len() == 1;
        for (s, t) in pieces {
            let ex = &es[s..t];
            let total: f64 = ex.iter().map(|&e| edges[e as usize].len).sum();
            let angle = if total > 0.0 {
                ex.iter()
                    .map(|&e| edges[e as usize].angle * edges[e as usize].len)
                    .sum::<f64>()
                    / total
            } else {
                0.0
            };
            let pair = edges[es[s] as usize].pair;
            creases.push(Crease {
                points: verts[s..=t]
                    .iter()
                    .map(|&v| {
                        let p = pos(v);
                        [p.x, p.y, p.z]
                    })
                    .collect(),
                angle_deg: angle,
                regions: [pair.0, pair.1],
                closed: whole_loop,
            });
        }
    }
    // Corner vertices a short edge apart are one corner.
    let corners = cluster(&corners, 2.0 * mesh.mean_edge_length());
    Ok((creases, corners))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::features::segment_mesh::{segment_mesh, MeshOptions};

    /// A closed axis-aligned box [0,2]x[0,1]x[0,1], each face split into a grid of triangles.
    pub(crate) fn box_mesh(n: usize) -> Mesh {
        let mut positions = Vec::new();
        let mut index = std::collections::BTreeMap::new();
        let mut faces = Vec::new();
        let size = [2.0, 1.0, 1.0];
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in 0..2 {
                // Vertex ids of this face's grid, shared with the faces around it.
                let mut ids = Vec::new();
                for j in 0..=n {
                    for i in 0..=n {
                        let mut p = [0.0; 3];
                        p[axis] = side as f64 * size[axis];
                        p[u] = i as f64 / n as f64 * size[u];
                        p[v] = j as f64 / n as f64 * size[v];
                        let key = p.map(|x| (x * 1e6).round() as i64);
                        let id = *index.entry(key).or_insert_with(|| {
                            positions.push(Point3::new(p[0], p[1], p[2]));
                            positions.len() as u32 - 1
                        });
                        ids.push(id);
                    }
                }
                let id = |i: usize, j: usize| ids[j * (n + 1) + i];
                for j in 0..n {
                    for i in 0..n {
                        let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                        if side == 1 {
                            faces.push([a, b, c]);
                            faces.push([a, c, d]);
                        } else {
                            faces.push([a, c, b]);
                            faces.push([a, d, c]);
                        }
                    }
                }
            }
        }
        Mesh {
            positions,
            normals: None,
            faces,
        }
    }

    #[test]
    fn a_box_has_twelve_right_angled_creases_and_eight_corners() {
        let mesh = box_mesh(6);
        let labels = segment_mesh(&mesh, &MeshOptions::default()).unwrap();
        assert_eq!(labels.regions, 6);
        let (creases, corners) = mesh_creases(&mesh, &labels, 60.0).unwrap();
        assert_eq!(creases.len(), 12, "{creases:?}");
        for c in &creases {
            assert!((c.angle_deg - 90.0).abs() < 1e-6, "{c:?}");
            assert!(!c.closed);
        }
        let total: f64 = creases.iter().map(Crease::length).sum();
        assert!((total - 4.0 * (2.0 + 1.0 + 1.0)).abs() < 1e-9, "{total}");
        assert_eq!(corners.len(), 8, "{corners:?}");
        for c in &corners {
            for (k, s) in [2.0, 1.0, 1.0].iter().enumerate() {
                assert!(c[k].abs() < 1e-9 || (c[k] - s).abs() < 1e-9, "{c}");
            }
        }
    }
}
