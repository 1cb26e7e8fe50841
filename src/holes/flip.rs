//! Edge flips toward the Delaunay criterion on a fill patch, in 3D.
//!
//! Not in the seed papers; added because both fills produce slivers the papers leave to their
//! smoothing: the Delaunay triangulation of a hole's ring (seed 002) has only ring vertices, so
//! many of its triangles join three consecutive ring vertices, and on a curved surface such a
//! triangle stands at an angle to its neighbours. An inner edge a-b with opposite vertices c, d
//! is flipped to c-d when the angles at c and d add up to more than pi (the edge is not locally
//! Delaunay), unless c-d already exists (in the patch or, between ring vertices, in the mesh) or
//! the flip would fold the surface.

use super::patch::{key, EdgeUse, Patch};
use std::collections::HashSet;

/// Angle at `p` in triangle p, q, r.
fn angle_at(
    p: &nalgebra::Point3<f64>,
    q: &nalgebra::Point3<f64>,
    r: &nalgebra::Point3<f64>,
) -> f64 {
    let (u, v) = (q - p, r - p);
    u.cross(&v).norm().atan2(u.dot(&v))
}

/// Flips inner edges that are not locally Delaunay, in rounds of independent flips (each face
/// takes part in at most one flip per round), until none is left or `max_rounds` is reached.
/// Returns the number of flips.
pub fn delaunay_flips(patch: &mut Patch, max_rounds: usize) -> usize {
    let mut total = 0;
    for _ in 0..max_rounds {
        let edges = patch.edge_faces();
        let mut touched = vec![false; patch.faces.len()];
        let mut flips = 0;
        let mut created: HashSet<(u32, u32)> = HashSet::new();
        for e in &edges {
            if e.count != 2 {
                continue;
            }
            let (a, b) = e.key;
            let (f1, f2) = (e.faces[0] as usize, e.faces[1] as usize);
            if touched[f1] || touched[f2] {
                continue;
            }
            // Orient: f1 walks a -> b, f2 walks b -> a.
            let walks =
                |f: &[u32; 3], s: u32, t: u32| (0..3).any(|k| f[k] == s && f[(k + 1) % 3] == t);
            let (f1, f2) = if walks(&patch.faces[f1], a, b) {
                (f1, f2)
            } else {
                (f2, f1)
            };
            let (fa, fb) = (patch.faces[f1], patch.faces[f2]);
            if !walks(&fa, a, b) || !walks(&fb, b, a) {
                continue; // inconsistent orientation: leave alone
            }
            let c = fa.iter().copied().find(|&x| x != a && x != b);
            let d = fb.iter().copied().find(|&x| x != a && x != b);
            let (Some(c), Some(d)) = (c, d) else { continue };
            if c == d {
                continue;
            }
            let p = |i: u32| patch.positions[i as usize];
            let sum = angle_at(&p(c), &p(a), &p(b)) + angle_at(&p(d), &p(a), &p(b));
            if sum <= std::f64::consts::PI + 1e-9 {
                continue;
            }
            let cd = key(c, d);
            if EdgeUse::find(&edges, cd).is_some()
                || created.contains(&cd)
                || patch.is_mesh_edge(c, d)
            {
                continue;
            }
            // New faces (a, d, c) and (d, b, c); they must face the way the old pair did.
            let old = patch.face_cross(&fa) + patch.face_cross(&fb);
            let n1 = patch.face_cross(&[a, d, c]);
            let n2 = patch.face_cross(&[d, b, c]);
            let scale = old.norm();
            if !(scale > 0.0)
                || n1.dot(&old) <= 1e-6 * scale * n1.norm()
                || n2.dot(&old) <= 1e-6 * scale * n2.norm()
                || n1.dot(&n2) <= 0.0
            {
                continue;
            }
            patch.faces[f1] = [a, d, c];
            patch.faces[f2] = [d, b, c];
            touched[f1] = true;
            touched[f2] = true;
            created.insert(cd);
            flips += 1;
        }
        total += flips;
        if flips == 0 {
            break;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Vector3};

    #[test]
    fn flips_a_bad_diagonal_but_not_a_mesh_edge() {
        // A long thin rhombus split along its long diagonal 0-2.
        let pos = vec![
            Point3::new(-2.0, 0.0, 0.0),
            Point3::new(0.0, -0.5, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(0.0, 0.5, 0.0),
        ];
        let make = |mesh_edges: HashSet<(u32, u32)>| {
            let mut p = Patch::from_ring(
                pos.clone(),
                vec![Vector3::z(); 4],
                vec![0, 1, 2, 3],
                mesh_edges,
            );
            p.faces = vec![[0, 1, 2], [0, 2, 3]];
            p
        };
        let mut p = make(HashSet::new());
        assert_eq!(delaunay_flips(&mut p, 5), 1);
        assert!(p.check_topology().is_ok());
        assert!(p.faces.iter().all(|f| f.contains(&1) && f.contains(&3)));
        let mut q = make([(1, 3)].into_iter().collect());
        assert_eq!(delaunay_flips(&mut q, 5), 0);
    }
}
