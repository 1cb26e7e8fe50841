//! Cutting holes into meshes, for tests, fixtures and benchmarks.
//!
//! A hole is the set of vertices inside a region (a ball, or any predicate) that are connected
//! to the region's seed vertex through inside vertices (so a ball does not also cut through a
//! thin part on the other side); every face touching one of them is removed. Removing faces
//! can pinch the boundary at a vertex (two ends of the hole touching); such vertices are then
//! cut out too, until the boundary is clean. Unreferenced vertices are removed and the rest
//! renumbered in order.

use super::neighbourhood::VertexFaces;
use crate::mesh::{Mesh, Topology};
use nalgebra::Point3;

/// Removes the region around the vertex nearest `seed` where `inside` holds (see the module doc).
pub fn cut_region(mesh: &Mesh, seed: &Point3<f64>, inside: &Inside<'_>) -> Mesh {
    cut_regions(mesh, &[(*seed, inside)])
}

/// Tells whether a point lies in a region to cut.
pub type Inside<'a> = dyn Fn(&Point3<f64>) -> bool + 'a;

/// Removes several regions at once (one adjacency build and one clean-up pass, for large
/// meshes): each region is the set of vertices around the vertex nearest its seed where its
/// predicate holds.
pub fn cut_regions(mesh: &Mesh, regions: &[(Point3<f64>, &Inside<'_>)]) -> Mesh {
    let used = mesh.referenced();
    let vf = VertexFaces::build(mesh);
    let mut removed_v = vec![false; mesh.positions.len()];
    for (seed, inside) in regions {
        let start = mesh
            .positions
            .iter()
            .enumerate()
            .filter(|(i, _)| used[*i])
            .min_by(|a, b| (a.1 - seed).norm().total_cmp(&(b.1 - seed).norm()))
            .map(|(i, _)| i as u32);
        let Some(start) = start else {
            continue;
        };
        let mut stack = vec![start];
        removed_v[start as usize] = true;
        while let Some(v) = stack.pop() {
            for &f in vf.of(v) {
                for &u in &mesh.faces[f as usize] {
                    if !removed_v[u as usize] && inside(&mesh.positions[u as usize]) {
                        removed_v[u as usize] = true;
                        stack.push(u);
                    }
                }
            }
        }
    }
    let mut keep: Vec<bool> = mesh
        .faces
        .iter()
        .map(|f| !f.iter().any(|&v| removed_v[v as usize]))
        .collect();
    // Clean pinched boundaries.
    for _ in 0..20 {
        let sub = filter_faces(mesh, &keep);
        let t = Topology::build(&sub);
        if t.non_manifold_vertices.is_empty() {
            break;
        }
        let bad: std::collections::HashSet<u32> = t.non_manifold_vertices.iter().copied().collect();
        for (k, f) in mesh.faces.iter().enumerate() {
            if f.iter().any(|v| bad.contains(v)) {
                keep[k] = false;
            }
        }
    }
    compact(&filter_faces(mesh, &keep))
}

/// Removes balls `(centre, radius)` at once (see [`cut_regions`]).
pub fn cut_balls(mesh: &Mesh, balls: &[(Point3<f64>, f64)]) -> Mesh {
    let preds: Vec<Box<Inside<'_>>> = balls
        .iter()
        .map(|&(c, r)| Box::new(move |p: &Point3<f64>| (p - c).norm() < r) as Box<Inside<'_>>)
        .collect();
    let regions: Vec<(Point3<f64>, &Inside<'_>)> = balls
        .iter()
        .zip(&preds)
        .map(|(b, p)| (b.0, p.as_ref()))
        .collect();
    cut_regions(mesh, &regions)
}

/// Removes the hole within distance `radius` of `centre` (see [`cut_region`]).
pub fn cut_ball(mesh: &Mesh, centre: &Point3<f64>, radius: f64) -> Mesh {
    cut_region(mesh, centre, &|p| (p - centre).norm() < radius)
}

/// The mesh with only the faces where `keep` holds (vertices unchanged).
fn filter_faces(mesh: &Mesh, keep: &[bool]) -> Mesh {
    Mesh {
        positions: mesh.positions.clone(),
        normals: mesh.normals.clone(),
        faces: mesh
            .faces
            .iter()
            .zip(keep)
            .filter(|(_, &k)| k)
            .map(|(f, _)| *f)
            .collect(),
    }
}

/// Drops unreferenced vertices, keeping the others' order.
pub fn compact(mesh: &Mesh) -> Mesh {
    let used = mesh.referenced();
    let mut map = vec![u32::MAX; mesh.positions.len()];
    let mut out = Mesh::default();
    let mut normals = mesh.normals.as_ref().map(|_| Vec::new());
    for (i, p) in mesh.positions.iter().enumerate() {
        if used[i] {
            map[i] = out.positions.len() as u32;
            out.positions.push(*p);
            if let (Some(dst), Some(src)) = (normals.as_mut(), mesh.normals.as_ref()) {
                dst.push(src[i]);
            }
        }
    }
    out.normals = normals;
    out.faces = mesh
        .faces
        .iter()
        .map(|f| [map[f[0] as usize], map[f[1] as usize], map[f[2] as usize]])
        .collect();
    out
}

#[cfg(test)]
mod tests {
    use super::super::testing::cube_sphere;
    use super::*;

    #[test]
    fn ball_cut_gives_one_clean_hole() {
        let s = cube_sphere(8, 1.0);
        let c = cut_ball(&s, &Point3::new(0.0, 0.0, 1.0), 0.5);
        let t = c.topology();
        assert_eq!(t.loops.len(), 1);
        assert!(!t.loops[0].twisted);
        assert!(t.non_manifold_vertices.is_empty());
        assert_eq!(t.unreferenced_vertices, 0);
        assert!(c.faces.len() < s.faces.len());
        let two = cut_balls(
            &s,
            &[
                (Point3::new(0.0, 0.0, 1.0), 0.5),
                (Point3::new(0.0, 0.0, -1.0), 0.3),
            ],
        );
        assert_eq!(two.topology().loops.len(), 2);
        assert!(c
            .positions
            .iter()
            .all(|p| (p - Point3::new(0.0, 0.0, 1.0)).norm() >= 0.5));
    }
}
