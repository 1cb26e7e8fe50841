//! Corners put back that the fold guard of [`super::crease_split`] dropped.
//!
//! A triangle with three regions gets the corner where their surfaces meet only while all three
//! of its edges keep their crease points; beside a corner marching cubes leaves small, oblique
//! triangles, and a neighbour whose pieces would turn over gives up the split of an edge it
//! shares with the corner's triangle, so the corner goes too and the mesh cuts it off (an
//! L-plate from its mesh: a box corner 0.15 mm off, 1.7e-3 of the diagonal).
//!
//! **Snap.** Each corner found but dropped moves the mesh vertex nearest to it (after the
//! split, the flips and the crease snap) onto it, when that vertex lies within the corner
//! triangle's longest edge and no triangle around it turns over or collapses
//! ([`super::crease_snap::move_unfolded`]). A vertex moves once; the corners are visited in the
//! order of their triangles, so the result does not depend on the thread count.

use super::crease_snap::{face_rings, move_unfolded};
use crate::mesh::Mesh;
use crate::spatial::KdTree;
use nalgebra::Point3;

/// Moves the vertex nearest to each corner `(point, reach)` onto it (module doc); returns how
/// many moved.
pub fn snap_to_corners(mesh: &mut Mesh, corners: &[(Point3<f64>, f64)]) -> usize {
    if corners.is_empty() {
        return 0;
    }
    let Ok(kd) = KdTree::build(&mesh.positions) else {
        return 0;
    };
    let ring = face_rings(mesh);
    let mut moved = vec![false; mesh.positions.len()];
    let mut count = 0;
    for &(c, reach) in corners {
        let (v, d) = kd.nearest(&c);
        if d > reach || moved[v] || ring[v].is_empty() {
            continue;
        }
        if move_unfolded(mesh, &ring, v as u32, c) {
            moved[v] = true;
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of four triangles around vertex 4, a little off the corner (0, 0, 0) of the
    /// pyramid they approximate.
    fn fan(centre: Point3<f64>) -> Mesh {
        Mesh {
            positions: vec![
                Point3::new(1.0, 0.0, -1.0),
                Point3::new(0.0, 1.0, -1.0),
                Point3::new(-1.0, 0.0, -1.0),
                Point3::new(0.0, -1.0, -1.0),
                centre,
            ],
            faces: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
            ..Default::default()
        }
    }

    #[test]
    fn the_nearest_vertex_moves_onto_a_dropped_corner() {
        let mut m = fan(Point3::new(0.1, 0.05, -0.2));
        let n = snap_to_corners(&mut m, &[(Point3::origin(), 0.5)]);
        assert_eq!(n, 1);
        assert_eq!(m.positions[4], Point3::origin());
        assert_eq!(m.positions[0], Point3::new(1.0, 0.0, -1.0));
    }

    #[test]
    fn corners_out_of_reach_or_folding_leave_the_mesh_alone() {
        let mut m = fan(Point3::new(0.1, 0.05, -0.2));
        let before = m.positions.clone();
        // Beyond reach.
        assert_eq!(snap_to_corners(&mut m, &[(Point3::origin(), 0.1)]), 0);
        assert_eq!(m.positions, before);
        // A flat fan: within reach, but moving there (past the edge 0-1) turns a triangle over.
        let mut m = fan(Point3::new(0.1, 0.05, -1.0));
        let before = m.positions.clone();
        assert_eq!(
            snap_to_corners(&mut m, &[(Point3::new(0.55, 0.55, -1.0), 2.0)]),
            0
        );
        assert_eq!(m.positions, before);
        assert_eq!(snap_to_corners(&mut m, &[]), 0);
    }
}
