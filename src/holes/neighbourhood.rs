//! The mesh around a hole: vertex-to-face adjacency, rings of vertices around the boundary
//! (seed 000 section 2.1, Fig. 1: "the boundary vertices and the vertices of all triangles
//! touching the boundary"), and the mean edge length the fill should match.

use crate::mesh::Mesh;

/// Faces around each vertex, in compressed rows (built once in O(F)).
#[derive(Debug, Clone)]
pub struct VertexFaces {
    offsets: Vec<u32>,
    faces: Vec<u32>,
}

impl VertexFaces {
    /// Builds the adjacency. Face indices must be within the vertex list.
    pub fn build(mesh: &Mesh) -> VertexFaces {
        let nv = mesh.positions.len();
        let mut count = vec![0u32; nv + 1];
        for f in &mesh.faces {
            for &v in f {
                count[v as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut faces = vec![0u32; count[nv] as usize];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                let slot = &mut fill[v as usize];
                faces[*slot as usize] = fi as u32;
                *slot += 1;
            }
        }
        VertexFaces {
            offsets: count,
            faces,
        }
    }

    /// Faces using vertex `v` (in increasing face order).
    pub fn of(&self, v: u32) -> &[u32] {
        let v = v as usize;
        if v + 1 >= self.offsets.len() {
            return &[];
        }
        &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}

/// The vertices within `rings` face-rings of `seeds`: ring 0 is the seeds, ring k+1 adds the
/// vertices of every face touching ring k. Sorted by index.
pub fn ring_vertices(mesh: &Mesh, vf: &VertexFaces, seeds: &[u32], rings: usize) -> Vec<u32> {
    let mut set: Vec<u32> = seeds.to_vec();
    set.sort_unstable();
    set.dedup();
    let mut frontier = set.clone();
    for _ in 0..rings {
        let mut next: Vec<u32> = Vec::new();
        for &v in &frontier {
            for &f in vf.of(v) {
                next.extend_from_slice(&mesh.faces[f as usize]);
            }
        }
        next.sort_unstable();
        next.dedup();
        next.retain(|v| set.binary_search(v).is_err());
        if next.is_empty() {
            break;
        }
        set.extend_from_slice(&next);
        set.sort_unstable();
        frontier = next;
    }
    set
}

/// Mean length of the edges of the faces touching `boundary` (each face edge counted once per
/// face); `None` when no face touches it.
pub fn mean_edge_length_around(mesh: &Mesh, vf: &VertexFaces, boundary: &[u32]) -> Option<f64> {
    let mut faces: Vec<u32> = boundary
        .iter()
        .flat_map(|&v| vf.of(v).iter().copied())
        .collect();
    faces.sort_unstable();
    faces.dedup();
    if faces.is_empty() {
        return None;
    }
    let mut sum = 0.0;
    for &f in &faces {
        let t = mesh.faces[f as usize];
        for k in 0..3 {
            sum += (mesh.positions[t[k] as usize] - mesh.positions[t[(k + 1) % 3] as usize]).norm();
        }
    }
    let mean = sum / (3 * faces.len()) as f64;
    (mean.is_finite() && mean > 0.0).then_some(mean)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn strip() -> Mesh {
        // 0-1-2-3 along x at y=0, 4-5-6-7 at y=1.
        let mut m = Mesh::default();
        for j in 0..2 {
            for i in 0..4 {
                m.positions.push(Point3::new(i as f64, j as f64, 0.0));
            }
        }
        for i in 0..3u32 {
            m.faces.push([i, i + 1, i + 5]);
            m.faces.push([i, i + 5, i + 4]);
        }
        m
    }

    #[test]
    fn rings_grow_by_faces() {
        let m = strip();
        let vf = VertexFaces::build(&m);
        assert_eq!(vf.of(0), &[0, 1]);
        assert_eq!(ring_vertices(&m, &vf, &[0], 0), vec![0]);
        assert_eq!(ring_vertices(&m, &vf, &[0], 1), vec![0, 1, 4, 5]);
        assert_eq!(ring_vertices(&m, &vf, &[0], 2), vec![0, 1, 2, 4, 5, 6]);
        let h = mean_edge_length_around(&m, &vf, &[0]).unwrap();
        let want = (1.0 + 2f64.sqrt() + 1.0 + 2f64.sqrt() + 1.0 + 1.0) / 6.0;
        assert!((h - want).abs() < 1e-12);
        assert!(mean_edge_length_around(&m, &vf, &[99]).is_none());
    }
}
