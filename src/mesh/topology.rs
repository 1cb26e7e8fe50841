//! Edge adjacency of a triangle mesh and what it tells: boundary loops, non-manifold edges and
//! vertices, connected components, orientation consistency.
//!
//! Built once in O(F log F) from the face list; no half-edge structure is needed for the
//! queries scansurf makes, and this one tolerates non-manifold input (which a half-edge
//! structure cannot hold).

use super::Mesh;
use std::collections::HashMap;

/// One undirected edge and the faces that use it.
#[derive(Debug, Clone)]
pub struct Edge {
    /// Endpoints, `v[0] < v[1]`.
    pub v: [u32; 2],
    /// Faces using the edge, with `true` when the face walks it from `v[0]` to `v[1]`.
    pub faces: Vec<(u32, bool)>,
}

/// A closed chain of boundary edges, in the direction the adjacent faces walk them.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BoundaryLoop {
    /// Vertex indices in order; the loop closes from the last back to the first.
    pub vertices: Vec<u32>,
    /// Sum of the edge lengths.
    pub length: f64,
    /// True when the loop passes a vertex twice (a "twisted" or pinched loop).
    pub twisted: bool,
    /// True when the loop is taken for the outer border of an open sheet rather than a hole:
    /// the longest loop of its component, when it is longer than the component's bounding-box
    /// diagonal (a hole that large is an opening by design, not a scanning gap).
    pub outer_border: bool,
    /// Connected component (index into [`Topology::components`]) the loop belongs to.
    pub component: u32,
}

/// Adjacency of a mesh.
#[derive(Debug, Clone, Default)]
pub struct Topology {
    /// Every undirected edge.
    pub edges: Vec<Edge>,
    /// Edge index by sorted endpoint pair.
    pub edge_index: HashMap<(u32, u32), u32>,
    /// Boundary loops (edges used by exactly one face).
    pub loops: Vec<BoundaryLoop>,
    /// Edges used by three or more faces.
    pub non_manifold_edges: Vec<u32>,
    /// Vertices whose faces form more than one fan (two sheets touching at a point), or that lie
    /// on a non-manifold edge.
    pub non_manifold_vertices: Vec<u32>,
    /// Interior edges whose two faces walk them in the same direction (inconsistent orientation).
    pub misoriented_edges: usize,
    /// Component id per face.
    pub face_component: Vec<u32>,
    /// Number of faces per component, largest first in id order of first appearance.
    pub components: Vec<usize>,
    /// Vertices referenced by no face.
    pub unreferenced_vertices: usize,
    /// Faces with a repeated vertex index or zero area.
    pub degenerate_faces: Vec<u32>,
    /// Vertices at exactly the same position as an earlier vertex.
    pub duplicate_vertices: usize,
}

/// Among the outgoing boundary edges `b -> c`, the one reached first when turning
/// counter-clockwise (around the vertex normal at `b`) from the incoming direction `b -> a`: the
/// walk has its faces on the left, so the hole it goes around lies counter-clockwise of `b -> a`.
fn pick_turn(
    mesh: &Mesh,
    vnormals: &[nalgebra::Vector3<f64>],
    a: u32,
    b: u32,
    cands: &[(u32, u32)],
) -> Option<(u32, u32)> {
    let pb = mesh.positions[b as usize];
    let n = vnormals.get(b as usize).copied().unwrap_or_default();
    let project = |v: nalgebra::Vector3<f64>| v - n * n.dot(&v);
    let din = project(mesh.positions[a as usize] - pb);
    let ccw = |c: u32| {
        let d = project(mesh.positions[c as usize] - pb);
        let ang = n.dot(&din.cross(&d)).atan2(din.dot(&d));
        if ang <= 0.0 {
            ang + std::f64::consts::TAU
        } else {
            ang
        }
    };
    cands
        .iter()
        .copied()
        .min_by(|x, y| ccw(x.0).total_cmp(&ccw(y.0)).then(x.0.cmp(&y.0)))
}

/// Union-find with path halving.
pub(crate) struct DisjointSets {
    parent: Vec<u32>,
}

impl DisjointSets {
    pub(crate) fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n as u32).collect(),
        }
    }
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = p;
            x = p;
        }
        x
    }
    pub(crate) fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.parent[hi as usize] = lo;
        }
    }
}

impl Topology {
    /// Builds the adjacency of `mesh`. Face indices must be within the vertex list (the readers
    /// guarantee it).
    pub fn build(mesh: &Mesh) -> Topology {
        let nv = mesh.positions.len();
        let nf = mesh.faces.len();
        let mut t = Topology::default();

        // Edges.
        let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(3 * nf);
        for (fi, f) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                if a == b {
                    continue;
                }
                let (lo, hi, fwd) = if a < b { (a, b, true) } else { (b, a, false) };
                half.push((lo, hi, fi as u32, fwd));
            }
        }
        half.sort_unstable();
        let mut i = 0;
        while i < half.len() {
            let (lo, hi) = (half[i].0, half[i].1);
            let mut faces = Vec::with_capacity(2);
            while i < half.len() && half[i].0 == lo && half[i].1 == hi {
                faces.push((half[i].2, half[i].3));
                i += 1;
            }
            let id = t.edges.len() as u32;
            t.edge_index.insert((lo, hi), id);
            if faces.len() > 2 {
                t.non_manifold_edges.push(id);
            } else if faces.len() == 2 && faces[0].1 == faces[1].1 {
                t.misoriented_edges += 1;
            }
            t.edges.push(Edge { v: [lo, hi], faces });
        }

        // Degenerate faces and references.
        let diag = mesh.aabb().map(|b| b.diagonal()).unwrap_or(0.0);
        let area_eps = (diag * 1e-12).powi(2);
        let mut referenced = vec![false; nv];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                referenced[v as usize] = true;
            }
            if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || mesh.face_area(fi) <= area_eps {
                t.degenerate_faces.push(fi as u32);
            }
        }
        t.unreferenced_vertices = referenced.iter().filter(|&&r| !r).count();

        // Duplicate positions (bitwise equal coordinates, +0 and -0 identified).
        let mut seen: HashMap<[u64; 3], u32> = HashMap::with_capacity(nv);
        for (i, p) in mesh.positions.iter().enumerate() {
            let key = [
                (p.x + 0.0).to_bits(),
                (p.y + 0.0).to_bits(),
                (p.z + 0.0).to_bits(),
            ];
            if seen.insert(key, i as u32).is_some() {
                t.duplicate_vertices += 1;
            }
        }

        // Components: faces joined through shared vertices.
        let mut ds = DisjointSets::new(nv);
        for f in &mesh.faces {
            ds.union(f[0], f[1]);
            ds.union(f[1], f[2]);
        }
        let mut comp_of_root: HashMap<u32, u32> = HashMap::new();
        t.face_component = Vec::with_capacity(nf);
        for f in &mesh.faces {
            let r = ds.find(f[0]);
            let n = comp_of_root.len() as u32;
            let c = *comp_of_root.entry(r).or_insert(n);
            if c as usize == t.components.len() {
                t.components.push(0);
            }
            t.components[c as usize] += 1;
            t.face_component.push(c);
        }

        t.find_non_manifold_vertices(mesh);
        t.find_loops(mesh);
        t
    }

    /// Corners (face, vertex) joined across manifold edges; a vertex whose corners fall into
    /// more than one set has more than one fan.
    fn find_non_manifold_vertices(&mut self, mesh: &Mesh) {
        let nf = mesh.faces.len();
        let corner = |f: u32, v: u32| -> Option<u32> {
            let face = mesh.faces[f as usize];
            face.iter().position(|&x| x == v).map(|k| 3 * f + k as u32)
        };
        let mut ds = DisjointSets::new(3 * nf);
        let mut flagged = vec![false; mesh.positions.len()];
        for e in &self.edges {
            if e.faces.len() == 2 {
                let (f, g) = (e.faces[0].0, e.faces[1].0);
                for &v in &e.v {
                    if let (Some(a), Some(b)) = (corner(f, v), corner(g, v)) {
                        ds.union(a, b);
                    }
                }
            } else if e.faces.len() > 2 {
                flagged[e.v[0] as usize] = true;
                flagged[e.v[1] as usize] = true;
            }
        }
        let mut root_of_vertex: Vec<u32> = vec![u32::MAX; mesh.positions.len()];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for (k, &v) in f.iter().enumerate() {
                if f.iter().filter(|&&x| x == v).count() > 1 {
                    continue; // degenerate face: no fan
                }
                let r = ds.find(3 * fi as u32 + k as u32);
                let slot = &mut root_of_vertex[v as usize];
                if *slot == u32::MAX {
                    *slot = r;
                } else if *slot != r {
                    flagged[v as usize] = true;
                }
            }
        }
        self.non_manifold_vertices = flagged
            .iter()
            .enumerate()
            .filter(|(_, &f)| f)
            .map(|(i, _)| i as u32)
            .collect();
    }

    /// Chains the boundary edges into loops, each walked with its faces on the left. At a vertex
    /// with several outgoing boundary edges (holes touching at a vertex), the walk takes the
    /// sharpest turn into the hole side, so that two holes touching at a vertex stay two loops.
    fn find_loops(&mut self, mesh: &Mesh) {
        // Directed boundary half-edges, as the single face walks them.
        let mut out: HashMap<u32, Vec<(u32, u32)>> = HashMap::new(); // from -> [(to, face)]
        let mut n_boundary = 0usize;
        for e in &self.edges {
            if e.faces.len() == 1 {
                let (f, fwd) = e.faces[0];
                let (a, b) = if fwd {
                    (e.v[0], e.v[1])
                } else {
                    (e.v[1], e.v[0])
                };
                out.entry(a).or_default().push((b, f));
                n_boundary += 1;
            }
        }
        if n_boundary == 0 {
            return;
        }
        let mut used: std::collections::HashSet<(u32, u32)> = std::collections::HashSet::new();
        // Vertex normals are needed only where several boundary edges leave one vertex.
        let vnormals = if out.values().any(|c| c.len() > 1) {
            super::normals::vertex_normals(mesh)
        } else {
            Vec::new()
        };
        let mut starts: Vec<(u32, u32)> = out
            .iter()
            .flat_map(|(&a, v)| v.iter().map(move |&(b, _)| (a, b)))
            .collect();
        starts.sort_unstable();

        for &(a0, b0) in &starts {
            if used.contains(&(a0, b0)) {
                continue;
            }
            let mut verts = vec![a0];
            let (mut a, mut b) = (a0, b0);
            used.insert((a, b));
            let mut face = out
                .get(&a)
                .and_then(|c| c.iter().find(|x| x.0 == b))
                .map(|x| x.1)
                .unwrap_or(0);
            let mut guard = 0usize;
            loop {
                if b == a0 {
                    break;
                }
                verts.push(b);
                let cands = match out.get(&b) {
                    Some(c) => c,
                    None => break,
                };
                let next = if cands.len() == 1 {
                    Some(cands[0])
                } else {
                    let free: Vec<(u32, u32)> = cands
                        .iter()
                        .copied()
                        .filter(|x| !used.contains(&(b, x.0)))
                        .collect();
                    pick_turn(mesh, &vnormals, a, b, &free)
                };
                let Some((c, f)) = next else { break };
                if used.contains(&(b, c)) {
                    break;
                }
                used.insert((b, c));
                a = b;
                b = c;
                face = f;
                guard += 1;
                if guard > n_boundary {
                    break;
                }
            }
            let length = (0..verts.len())
                .map(|i| {
                    (mesh.positions[verts[i] as usize]
                        - mesh.positions[verts[(i + 1) % verts.len()] as usize])
                        .norm()
                })
                .sum();
            let mut sorted = verts.clone();
            sorted.sort_unstable();
            sorted.dedup();
            let twisted = sorted.len() != verts.len();
            let component = self.face_component.get(face as usize).copied().unwrap_or(0);
            self.loops.push(BoundaryLoop {
                vertices: verts,
                length,
                twisted,
                outer_border: false,
                component,
            });
        }

        // Outer borders: per component, the longest loop if it is longer than the component's
        // bounding-box diagonal.
        let mut comp_boxes: Vec<Option<super::Aabb>> = vec![None; self.components.len()];
        for (fi, f) in mesh.faces.iter().enumerate() {
            let c = self.face_component[fi] as usize;
            for &v in f {
                let p = mesh.positions[v as usize];
                comp_boxes[c] = Some(match comp_boxes[c] {
                    None => super::Aabb { min: p, max: p },
                    Some(b) => super::Aabb {
                        min: b.min.inf(&p),
                        max: b.max.sup(&p),
                    },
                });
            }
        }
        for (c, bx) in comp_boxes.iter().enumerate() {
            let best = self
                .loops
                .iter()
                .enumerate()
                .filter(|(_, l)| l.component as usize == c)
                .max_by(|x, y| x.1.length.total_cmp(&y.1.length))
                .map(|(i, _)| i);
            if let (Some(i), Some(bx)) = (best, bx) {
                if self.loops[i].length > bx.diagonal() {
                    self.loops[i].outer_border = true;
                }
            }
        }
        // Stable order: by component, then longest first.
        self.loops.sort_by(|x, y| {
            x.component
                .cmp(&y.component)
                .then(y.vertices.len().cmp(&x.vertices.len()))
                .then(x.vertices[0].cmp(&y.vertices[0]))
        });
    }

    /// Number of boundary edges.
    pub fn boundary_edge_count(&self) -> usize {
        self.edges.iter().filter(|e| e.faces.len() == 1).count()
    }

    /// True when every edge has exactly two faces, every vertex one fan and orientation agrees.
    pub fn is_closed_manifold(&self) -> bool {
        !self.edges.is_empty()
            && self.edges.iter().all(|e| e.faces.len() == 2)
            && self.non_manifold_vertices.is_empty()
            && self.misoriented_edges == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn grid(n: usize) -> Mesh {
        // An n x n grid of unit squares in the z=0 plane, two triangles each.
        let mut m = Mesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(Point3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                m.faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        m
    }

    #[test]
    fn sheet_has_one_border_and_holes_are_holes() {
        let mut m = grid(6);
        // Remove the two triangles of the square (2,2): a hole of 4 vertices.
        let k = 2 * (2 * 6 + 2);
        m.faces.drain(k..k + 2);
        let t = Topology::build(&m);
        assert_eq!(t.loops.len(), 2);
        let border = t.loops.iter().find(|l| l.outer_border).unwrap();
        assert_eq!(border.vertices.len(), 24);
        let hole = t.loops.iter().find(|l| !l.outer_border).unwrap();
        assert_eq!(hole.vertices.len(), 4);
        assert!(t.non_manifold_edges.is_empty() && t.non_manifold_vertices.is_empty());
        assert_eq!(t.misoriented_edges, 0);
    }

    #[test]
    fn two_holes_touching_at_a_vertex_stay_two_loops() {
        let mut m = grid(6);
        // Remove squares (2,2) and (3,3): they share the vertex (3,3).
        let a = 2 * (2 * 6 + 2);
        let b = 2 * (3 * 6 + 3);
        m.faces.drain(b..b + 2);
        m.faces.drain(a..a + 2);
        let t = Topology::build(&m);
        let holes: Vec<_> = t.loops.iter().filter(|l| !l.outer_border).collect();
        assert_eq!(holes.len(), 2, "{:?}", t.loops);
        assert!(holes.iter().all(|l| l.vertices.len() == 4));
        assert_eq!(t.non_manifold_vertices, vec![3 * 7 + 3]);
    }

    #[test]
    fn non_manifold_edge_and_bowtie() {
        let mut m = Mesh::default();
        for p in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
        ] {
            m.positions.push(Point3::from(p));
        }
        m.faces = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let t = Topology::build(&m);
        assert_eq!(t.non_manifold_edges.len(), 1);
        // Bow-tie: two triangles sharing only vertex 0.
        let mut b = Mesh::default();
        for p in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ] {
            b.positions.push(Point3::from(p));
        }
        b.faces = vec![[0, 1, 2], [0, 3, 4]];
        let t = Topology::build(&b);
        assert_eq!(t.non_manifold_vertices, vec![0]);
        assert_eq!(t.components.len(), 1);
        assert_eq!(t.loops.len(), 2);
    }

    #[test]
    fn misoriented_and_degenerate_and_duplicates() {
        let mut m = grid(1);
        m.faces[1] = [m.faces[1][0], m.faces[1][2], m.faces[1][1]];
        m.positions.push(Point3::new(0.0, 0.0, 0.0));
        m.faces.push([0, 0, 1]);
        let t = Topology::build(&m);
        assert_eq!(t.misoriented_edges, 1);
        assert_eq!(t.degenerate_faces, vec![2]);
        assert_eq!(t.duplicate_vertices, 1);
        assert_eq!(t.unreferenced_vertices, 1);
    }

    #[test]
    fn closed_tetrahedron() {
        let mut m = Mesh::default();
        for p in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ] {
            m.positions.push(Point3::from(p));
        }
        m.faces = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        let t = Topology::build(&m);
        assert!(t.is_closed_manifold());
        assert!(m.signed_volume() > 0.0);
        let n = crate::mesh::normals::vertex_normals(&m);
        assert!(n[3].z > 0.0);
    }
}
