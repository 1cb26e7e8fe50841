//! 1-to-4 midpoint subdivision of a triangle mesh (seed 003 section 3.3, seed 002): every edge
//! gets a new vertex at its midpoint and every triangle becomes four.
//!
//! Inputs: a mesh. Outputs: the subdivided mesh (old vertices keep their indices, the new ones
//! follow, one per edge) and, for each new vertex, the two endpoints of its edge.

use super::Mesh;
use crate::spatial::fast_hash::IntMap;

/// The subdivided mesh and the parent edge `[a, b]` of every new vertex (in index order, the
/// first new vertex being `mesh.positions.len()`).
pub fn subdivide(mesh: &Mesh) -> (Mesh, Vec<[u32; 2]>) {
    let n = mesh.positions.len() as u32;
    let mut edge_vertex: IntMap<(u32, u32), u32> = IntMap::default();
    edge_vertex.reserve(mesh.faces.len() * 2);
    let mut parents: Vec<[u32; 2]> = Vec::new();
    let mut positions = mesh.positions.clone();
    let mut mid = |a: u32, b: u32, positions: &mut Vec<_>| -> u32 {
        let key = (a.min(b), a.max(b));
        *edge_vertex.entry(key).or_insert_with(|| {
            let pa: nalgebra::Point3<f64> = positions[a as usize];
            let pb = positions[b as usize];
            positions.push(nalgebra::center(&pa, &pb));
            parents.push([key.0, key.1]);
            n + parents.len() as u32 - 1
        })
    };
    let mut faces = Vec::with_capacity(mesh.faces.len() * 4);
    for &[a, b, c] in &mesh.faces {
        let ab = mid(a, b, &mut positions);
        let bc = mid(b, c, &mut positions);
        let ca = mid(c, a, &mut positions);
        faces.push([a, ab, ca]);
        faces.push([ab, b, bc]);
        faces.push([ca, bc, c]);
        faces.push([ab, bc, ca]);
    }
    (
        Mesh {
            positions,
            normals: None,
            faces,
        },
        parents,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;
    use nalgebra::Point3;

    fn tetra() -> Mesh {
        Mesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
                Point3::new(0.0, 0.0, 1.0),
            ],
            normals: None,
            faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        }
    }

    #[test]
    fn counts_topology_and_area() {
        let m = tetra();
        assert!(Topology::build(&m).is_closed_manifold());
        let (s, parents) = subdivide(&m);
        assert_eq!(s.positions.len(), 4 + 6);
        assert_eq!(parents.len(), 6);
        assert_eq!(s.faces.len(), 16);
        assert!(Topology::build(&s).is_closed_manifold());
        assert!((s.signed_volume() - m.signed_volume()).abs() < 1e-12);
        let area = |m: &Mesh| (0..m.faces.len()).map(|f| m.face_area(f)).sum::<f64>();
        assert!((area(&s) - area(&m)).abs() < 1e-12);
        for (k, [a, b]) in parents.iter().enumerate() {
            let p = s.positions[4 + k];
            let q = nalgebra::center(&m.positions[*a as usize], &m.positions[*b as usize]);
            assert_eq!(p, q);
        }
    }
}
