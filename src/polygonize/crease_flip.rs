//! Edge flips that lay a crease on the mesh where [`super::crease_split`] gave up a split.
//!
//! After the crease points are put into the mesh, a crease runs along the mesh's edges from
//! one crease point to the next, except where the split of an edge crossing the crease was
//! given up (its crease point folded a triangle, or lay off the edge): there an edge (a, b)
//! from one face to the other still crosses the crease, and the two triangles on it,
//! (a, b, c) and (b, a, d), cut the edge off between the crease points c and d opposite it
//! (make_parts' block.stl: 19 such edges; flipped, the crease distance's 95th percentile goes
//! from 1.68e-4 to 1.58e-4 of the diagonal, lplate.stl's from 1.06e-5 to 7.8e-6).
//!
//! **Flip.** Such an edge, a and b original vertices of different regions and c and d both
//! crease points, is replaced by (c, d): the triangles (a, d, c) and (d, b, c), in the
//! orientation of the two they replace, so the crease runs from c to d on an edge. A flip is
//! made only when the edge (c, d) is not in the mesh yet (the mesh stays manifold) and neither
//! new triangle turns against the two old ones or is degenerate (the mesh does not fold).
//! Each triangle takes part in one flip at most; the faces are visited in order, so the
//! result does not depend on the thread count.

use super::crease_split::tri_normal;
use crate::mesh::Mesh;
use nalgebra::Point3;
use std::collections::HashMap;

/// Flips the edges that cross a crease between two crease points (module doc); returns how
/// many. `label` gives the region of the vertices before `first_new`; those from `first_new`
/// on are the crease points.
pub fn flip_across_creases(mesh: &mut Mesh, label: &[u32], first_new: usize) -> usize {
    let is_crease = |v: u32| v as usize >= first_new;
    // Each directed edge's face and the vertex opposite it.
    let mut opposite: HashMap<(u32, u32), (usize, u32)> = HashMap::new();
    for (i, f) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            opposite.insert((f[k], f[(k + 1) % 3]), (i, f[(k + 2) % 3]));
        }
    }
    let mut touched = vec![false; mesh.faces.len()];
    let mut flips = 0;
    for i in 0..mesh.faces.len() {
        if touched[i] {
            continue;
        }
        let f = mesh.faces[i];
        for k in 0..3 {
            let (a, b, c) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            if is_crease(a) || is_crease(b) || !is_crease(c) {
                continue;
            }
            if label[a as usize] == label[b as usize] {
                continue;
            }
            let Some(&(j, d)) = opposite.get(&(b, a)) else {
                continue;
            };
            if touched[j] || !is_crease(d) || d == c {
                continue;
            }
            if opposite.contains_key(&(c, d)) || opposite.contains_key(&(d, c)) {
                continue;
            }
            let new = [[a, d, c], [d, b, c]];
            if !keeps_orientation(&mesh.positions, &[f, mesh.faces[j]], &new) {
                continue;
            }
            mesh.faces[i] = new[0];
            mesh.faces[j] = new[1];
            touched[i] = true;
            touched[j] = true;
            for (face, t) in [(i, new[0]), (j, new[1])] {
                for m in 0..3 {
                    opposite.insert((t[m], t[(m + 1) % 3]), (face, t[(m + 2) % 3]));
                }
            }
            opposite.remove(&(a, b));
            opposite.remove(&(b, a));
            flips += 1;
            break;
        }
    }
    flips
}

/// Whether the triangles `new` are not degenerate and turn with each of `old`: every new
/// normal within 90 degrees of every old one.
fn keeps_orientation(pos: &[Point3<f64>], old: &[[u32; 3]; 2], new: &[[u32; 3]; 2]) -> bool {
    let old_n = old.map(|t| tri_normal(pos, &t));
    let scale = old_n[0].norm().max(old_n[1].norm());
    new.iter().all(|t| {
        let n = tri_normal(pos, t);
        n.norm() > 1e-6 * scale && old_n.iter().all(|o| n.dot(o) > 0.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles over the edge (0, 1) from region 0 to region 1, with crease points 2 and 3
    /// opposite it: the edge is flipped to (2, 3).
    fn kite(c: Point3<f64>, d: Point3<f64>) -> Mesh {
        Mesh {
            positions: vec![Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0), c, d],
            faces: vec![[0, 1, 2], [1, 0, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn an_edge_across_the_crease_between_two_crease_points_is_flipped() {
        let mut m = kite(Point3::new(0.5, 1.0, 0.0), Point3::new(0.5, -1.0, 0.0));
        let n = flip_across_creases(&mut m, &[0, 1], 2);
        assert_eq!(n, 1);
        let has = |a: u32, b: u32| {
            m.faces
                .iter()
                .any(|f| (0..3).any(|k| f[k] == a && f[(k + 1) % 3] == b))
        };
        assert!(has(2, 3) || has(3, 2), "{:?}", m.faces);
        assert!(!has(0, 1) && !has(1, 0), "{:?}", m.faces);
        // Orientation kept: both normals along +z like the originals'.
        for f in &m.faces {
            let p = f.map(|v| m.positions[v as usize]);
            assert!((p[1] - p[0]).cross(&(p[2] - p[0])).z > 0.0, "{:?}", m.faces);
        }
    }

    #[test]
    fn no_flip_within_a_region_off_the_crease_or_where_it_would_fold() {
        // Same region on both ends.
        let mut m = kite(Point3::new(0.5, 1.0, 0.0), Point3::new(0.5, -1.0, 0.0));
        assert_eq!(flip_across_creases(&mut m, &[0, 0], 2), 0);
        // The opposite vertices are not crease points.
        let mut m = kite(Point3::new(0.5, 1.0, 0.0), Point3::new(0.5, -1.0, 0.0));
        assert_eq!(flip_across_creases(&mut m, &[0, 1, 0, 1], 4), 0);
        // A non-convex quad: the flipped triangles would turn over.
        let mut m = kite(Point3::new(2.0, 0.2, 0.0), Point3::new(2.0, -0.2, 0.0));
        assert_eq!(flip_across_creases(&mut m, &[0, 1], 2), 0);
        assert_eq!(m.faces, vec![[0, 1, 2], [1, 0, 3]]);
    }
}
