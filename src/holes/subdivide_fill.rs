//! Edge-driven 1-to-4 subdivision of a fill patch (seed 002 section 3.4, Fig. 7).
//!
//! Every inner edge chosen by the caller gets a new vertex (placed by the caller, e.g. on a
//! circular arc); each face is then cut by how many of its edges were split: three gives the
//! regular 1-to-4 split, two gives three triangles (the quadrilateral cut along its shorter
//! diagonal), one gives two. Ring edges are never split: they are shared with the original
//! faces, which must stay as they are, and a vertex in the middle of one would leave a crack.
//! Splitting only edges longer than a threshold makes this the "repeat 1-to-4 subdivision until
//! the new edges are short enough" loop of seed 002, without refining what is already fine.

use super::patch::{key, Patch};
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;

/// Places the new vertex of edge (a, b): its position and unit normal.
pub type Midpoint<'a> = dyn Fn(&Patch, u32, u32) -> (Point3<f64>, Vector3<f64>) + 'a;

/// Splits the inner edges `(a, b)` (with `a < b`) for which `split` holds, at the point and normal
/// `midpoint` returns, and re-triangulates. Returns the number of edges split.
pub fn refine(
    patch: &mut Patch,
    split: &dyn Fn(&Patch, u32, u32) -> bool,
    midpoint: &Midpoint<'_>,
) -> usize {
    let edges = patch.edge_faces();
    let mut mids: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for e in &edges {
        let (a, b) = e.key;
        if e.count == 2 && split(patch, a, b) {
            let (p, n) = midpoint(patch, a, b);
            let v = patch.add_vertex(p, n);
            mids.insert((a, b), v);
        }
    }
    if mids.is_empty() {
        return 0;
    }
    let old = std::mem::take(&mut patch.faces);
    let mut faces = Vec::with_capacity(old.len() * 3);
    for f in old {
        let m: [Option<u32>; 3] =
            std::array::from_fn(|k| mids.get(&key(f[k], f[(k + 1) % 3])).copied());
        match m.iter().filter(|x| x.is_some()).count() {
            0 => faces.push(f),
            3 => {
                let (m0, m1, m2) = (m[0].unwrap_or(0), m[1].unwrap_or(0), m[2].unwrap_or(0));
                faces.push([f[0], m0, m2]);
                faces.push([m0, f[1], m1]);
                faces.push([m2, m1, f[2]]);
                faces.push([m0, m1, m2]);
            }
            1 => {
                // Rotate so that the split edge is f[0] -> f[1].
                let k = m.iter().position(|x| x.is_some()).unwrap_or(0);
                let (a, b, c) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
                let mm = m[k].unwrap_or(0);
                faces.push([a, mm, c]);
                faces.push([mm, b, c]);
            }
            _ => {
                // Two split edges: rotate so that the unsplit one is f[2] -> f[0].
                let k = m.iter().position(|x| x.is_none()).unwrap_or(0);
                // Unsplit edge is (f[k], f[k+1]); rename so that it is (c, a).
                let (c, a, b) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
                let mab = m[(k + 1) % 3].unwrap_or(0);
                let mbc = m[(k + 2) % 3].unwrap_or(0);
                faces.push([mab, b, mbc]);
                // Quadrilateral a, mab, mbc, c: cut along its shorter diagonal.
                let d1 = patch.edge_length(a, mbc);
                let d2 = patch.edge_length(mab, c);
                if d1 <= d2 {
                    faces.push([a, mab, mbc]);
                    faces.push([a, mbc, c]);
                } else {
                    faces.push([a, mab, c]);
                    faces.push([mab, mbc, c]);
                }
            }
        }
    }
    patch.faces = faces;
    mids.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Patch {
        let pos = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.5, 0.5, 0.0),
        ];
        let mut p = Patch::from_ring(
            pos[..4].to_vec(),
            vec![Vector3::z(); 4],
            vec![0, 1, 2, 3],
            Default::default(),
        );
        p.add_vertex(pos[4], Vector3::z());
        p.faces = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        p
    }

    #[test]
    fn splits_inner_edges_only_and_stays_closed() {
        let mut p = square();
        let mid = |p: &Patch, a: u32, b: u32| {
            (
                nalgebra::center(&p.positions[a as usize], &p.positions[b as usize]),
                Vector3::z(),
            )
        };
        let n = refine(&mut p, &|_, _, _| true, &mid);
        assert_eq!(n, 4, "the four spokes are inner edges");
        assert!(p.check_topology().is_ok(), "{:?}", p.check_topology());
        assert_eq!(p.faces.len(), 12);
        // Only one edge: 1 -> 2 faces, again closed.
        let mut q = square();
        refine(&mut q, &|_, a, b| (a, b) == (0, 4), &mid);
        assert!(q.check_topology().is_ok());
        assert_eq!(q.faces.len(), 6);
        // Total area is preserved.
        let area: f64 = q.faces.iter().map(|f| 0.5 * q.face_cross(f).norm()).sum();
        assert!((area - 1.0).abs() < 1e-12);
    }
}
