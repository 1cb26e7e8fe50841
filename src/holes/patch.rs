//! A hole's fill under construction: a small triangle mesh of its own whose first vertices are
//! the hole's ring (original mesh vertices, never moved) and whose other vertices are new.
//!
//! Faces are oriented like the surrounding mesh: every ring edge `a -> b` that an original face
//! walks is walked `b -> a` by exactly one fill face, so that the filled mesh stays consistently
//! oriented.

use nalgebra::{Point3, Vector3};
use std::collections::HashSet;

/// The fill of one hole.
#[derive(Debug, Clone, Default)]
pub struct Patch {
    /// Local vertex positions: the ring first (`0..ring_len`), then new vertices.
    pub positions: Vec<Point3<f64>>,
    /// Unit normals per local vertex (the mesh's vertex normals on the ring, estimated for new
    /// vertices).
    pub normals: Vec<Vector3<f64>>,
    /// The mesh vertex of each ring vertex (`global[i]` for `i < ring_len`).
    pub global: Vec<u32>,
    /// Triangles over local indices.
    pub faces: Vec<[u32; 3]>,
    /// Local vertex pairs `(lo, hi)` the fill must not join by a new edge: ring vertices that an
    /// edge of the mesh already joins (including the ring's own edges, which the fill uses only
    /// as its border), and the ends of chords along which a folded ring was cut. An edge with
    /// three faces would be non-manifold.
    pub mesh_edges: HashSet<(u32, u32)>,
}

/// An undirected edge of a patch and the faces using it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeUse {
    /// Endpoints, smaller first.
    pub key: (u32, u32),
    /// The first two faces using it (`u32::MAX` when fewer).
    pub faces: [u32; 2],
    /// How many faces use it.
    pub count: u32,
}

impl EdgeUse {
    /// The entry of edge `k` in a list from [`Patch::edge_faces`].
    pub fn find(list: &[EdgeUse], k: (u32, u32)) -> Option<&EdgeUse> {
        list.binary_search_by(|e| e.key.cmp(&k))
            .ok()
            .map(|i| &list[i])
    }
}

/// Sorted pair.
pub fn key(a: u32, b: u32) -> (u32, u32) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

impl Patch {
    /// A patch holding just the ring. `ring` lists local positions/normals in fill order
    /// (counter-clockwise seen from outside, the reverse of the boundary walk).
    pub fn from_ring(
        positions: Vec<Point3<f64>>,
        normals: Vec<Vector3<f64>>,
        global: Vec<u32>,
        mesh_edges: HashSet<(u32, u32)>,
    ) -> Patch {
        Patch {
            positions,
            normals,
            global,
            faces: Vec::new(),
            mesh_edges,
        }
    }

    /// Number of ring (fixed) vertices.
    pub fn ring_len(&self) -> usize {
        self.global.len()
    }

    /// True for ring vertices, which never move.
    pub fn is_fixed(&self, v: u32) -> bool {
        (v as usize) < self.global.len()
    }

    /// Appends a new vertex and returns its local index.
    pub fn add_vertex(&mut self, p: Point3<f64>, n: Vector3<f64>) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        (self.positions.len() - 1) as u32
    }

    /// True when `a` and `b` must not be joined by a new edge (see `mesh_edges`).
    pub fn is_mesh_edge(&self, a: u32, b: u32) -> bool {
        self.mesh_edges.contains(&key(a, b))
    }

    /// Undirected edges of the fill's faces with the faces using them, sorted by edge (so that
    /// every pass over the edges is deterministic, and [`EdgeUse::find`] can bisect).
    pub fn edge_faces(&self) -> Vec<EdgeUse> {
        let mut half: Vec<((u32, u32), u32)> = Vec::with_capacity(3 * self.faces.len());
        for (fi, f) in self.faces.iter().enumerate() {
            for k in 0..3 {
                half.push((key(f[k], f[(k + 1) % 3]), fi as u32));
            }
        }
        half.sort_unstable();
        let mut out: Vec<EdgeUse> = Vec::with_capacity(half.len() / 2 + 1);
        for (k, f) in half {
            match out.last_mut() {
                Some(e) if e.key == k => {
                    if e.count < 2 {
                        e.faces[e.count as usize] = f;
                    }
                    e.count += 1;
                }
                _ => out.push(EdgeUse {
                    key: k,
                    faces: [f, u32::MAX],
                    count: 1,
                }),
            }
        }
        out
    }

    /// Sorted, deduplicated neighbours of every local vertex through the fill's faces.
    pub fn neighbours(&self) -> Vec<Vec<u32>> {
        let mut nb: Vec<Vec<u32>> = vec![Vec::new(); self.positions.len()];
        for f in &self.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                nb[a as usize].push(b);
                nb[b as usize].push(a);
            }
        }
        for v in &mut nb {
            v.sort_unstable();
            v.dedup();
        }
        nb
    }

    /// Faces incident to each local vertex.
    pub fn vertex_faces(&self) -> Vec<Vec<u32>> {
        let mut vf: Vec<Vec<u32>> = vec![Vec::new(); self.positions.len()];
        for (fi, f) in self.faces.iter().enumerate() {
            for &v in f {
                vf[v as usize].push(fi as u32);
            }
        }
        vf
    }

    /// (b - a) x (c - a) of face `f`.
    pub fn face_cross(&self, f: &[u32; 3]) -> Vector3<f64> {
        let p = |i: u32| self.positions[i as usize];
        (p(f[1]) - p(f[0])).cross(&(p(f[2]) - p(f[0])))
    }

    /// Length of the edge between local vertices `a` and `b`.
    pub fn edge_length(&self, a: u32, b: u32) -> f64 {
        (self.positions[a as usize] - self.positions[b as usize]).norm()
    }

    /// Checks the fill's topology against its ring: every ring edge used once in the fill
    /// direction, every other edge exactly twice in opposite directions, no edge the mesh already
    /// has, no repeated vertex in a face. Returns a description of the first problem.
    pub fn check_topology(&self) -> std::result::Result<(), String> {
        let n = self.ring_len() as u32;
        let mut directed: HashSet<(u32, u32)> = HashSet::new();
        for f in &self.faces {
            if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
                return Err(format!("face {f:?} repeats a vertex"));
            }
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                if !directed.insert((a, b)) {
                    return Err(format!("edge {a}->{b} walked twice in the same direction"));
                }
            }
        }
        for e in &self.edge_faces() {
            let (a, b) = e.key;
            let ring_edge = a < n && b < n && ((a + 1) % n == b || (b + 1) % n == a);
            if ring_edge {
                // The fill walks the ring i -> i+1.
                let (s, t) = if (a + 1) % n == b { (a, b) } else { (b, a) };
                if e.count != 1 || !directed.contains(&(s, t)) {
                    return Err(format!("ring edge {s}->{t} not used exactly once"));
                }
            } else {
                if e.count != 2 {
                    return Err(format!(
                        "inner edge {a}-{b} has {} faces, expected 2",
                        e.count
                    ));
                }
                if self.is_mesh_edge(a, b) {
                    return Err(format!("edge {a}-{b} already exists in the mesh"));
                }
            }
        }
        // Every ring edge must be present.
        for i in 0..n {
            let j = (i + 1) % n;
            if n >= 3 && !directed.contains(&(i, j)) {
                return Err(format!("ring edge {i}->{j} missing"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_patch_topology() {
        let pos = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        let mut p = Patch::from_ring(
            pos,
            vec![Vector3::z(); 4],
            vec![10, 11, 12, 13],
            [(0, 1), (1, 2), (2, 3), (0, 3)].into_iter().collect(),
        );
        p.faces = vec![[0, 1, 2], [0, 2, 3]];
        assert!(p.check_topology().is_ok());
        p.faces = vec![[0, 1, 2]];
        assert!(p.check_topology().is_err());
        p.faces = vec![[0, 2, 1], [0, 3, 2]];
        assert!(p.check_topology().is_err());
        // The diagonal 0-2 already exists in the mesh.
        p.mesh_edges.insert((0, 2));
        p.faces = vec![[0, 1, 2], [0, 2, 3]];
        assert!(p.check_topology().is_err());
        assert_eq!(p.neighbours()[0], vec![1, 2, 3]);
    }
}
