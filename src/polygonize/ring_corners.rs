//! Corners that no triangle holds: three regions meeting around a vertex.
//!
//! [`super::crease_split`] puts a corner where a triangle's three vertices lie on three
//! regions. Beside a corner the triangles of marching cubes are small and oblique, and the
//! third face often gets no vertex of a triangle that also has one on each of the other two:
//! the three regions meet around a vertex (its own and its neighbours' labels), in no single
//! triangle. The corner is then missing, and the mesh cuts it off by up to a triangle (make_parts'
//! block from its cloud: the pocket's floor corner 0.07 mm off, 9.5e-4 of the diagonal).
//!
//! **Corner of a ring.** For each vertex `v` whose one ring (`v` and its neighbours) holds
//! exactly three regions, the point where the three sides meet is found by
//! [`super::crease_split::meet_point`] from `v` (the 3 x 3 Newton iteration of that module's
//! doc), and kept when it lies within the ring's longest edge of `v`. Rings of one corner give
//! one corner: a candidate within the larger of the two reaches of one kept before with the
//! same regions, or of a corner of a triangle (of any regions), is dropped. Vertices are
//! visited in index order, so the result does not depend on the thread count. The corners are
//! then snapped like those the fold guard dropped ([`super::corner_snap`]).

use super::crease_split::{crossing_edges, meet_point, CreaseSplitOptions, SideField};
use nalgebra::Point3;
use rayon::prelude::*;

/// A corner found around a vertex: its three regions (sorted), the point and its reach.
type RingCorner = ([u32; 3], Point3<f64>, f64);

/// The corners `(point, reach)` of the rings of `faces` (over `pos`, regions `label`) with three
/// regions, except those within reach of `known` corners (module doc).
pub fn ring_corners(
    pos: &[Point3<f64>],
    faces: &[[u32; 3]],
    label: &[u32],
    field: &dyn SideField,
    opts: &CreaseSplitOptions,
    known: &[(Point3<f64>, f64)],
) -> Vec<(Point3<f64>, f64)> {
    // Only a vertex with a neighbour on another region can have three regions in its ring:
    // neighbour lists for those alone (a mesh of millions of vertices has few).
    let n = pos.len().min(label.len());
    let mut slot: Vec<u32> = vec![u32::MAX; n];
    let mut nbr: Vec<Vec<u32>> = Vec::new();
    for (a, b) in crossing_edges(faces, label, n) {
        for v in [a as usize, b as usize] {
            if slot[v] == u32::MAX {
                slot[v] = nbr.len() as u32;
                nbr.push(Vec::new());
            }
        }
    }
    // Both directions of every edge: a boundary's or a badly oriented mesh's rings too.
    let edges = faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k] as usize, f[(k + 1) % 3] as usize)));
    for (a, b) in edges {
        if a < n && b < n {
            for (v, w) in [(a, b), (b, a)] {
                if let Some(l) = nbr.get_mut(slot[v] as usize) {
                    if !l.contains(&(w as u32)) {
                        l.push(w as u32);
                    }
                }
            }
        }
    }
    let ring = |v: usize| nbr.get(slot[v] as usize).map_or(&[][..], |l| &l[..]);
    let found: Vec<Option<RingCorner>> = (0..n)
        .into_par_iter()
        .map(|v| {
            let regions = ring_regions(v, ring(v), label)?;
            let reach = ring(v)
                .iter()
                .map(|&w| (pos[w as usize] - pos[v]).norm())
                .fold(0.0, f64::max);
            if reach <= 0.0 {
                return None;
            }
            let c = meet_point(field, &regions, pos[v], reach, opts)?;
            ((c - pos[v]).norm() <= reach).then_some((regions, c, reach))
        })
        .collect();
    let mut kept: Vec<RingCorner> = Vec::new();
    for (regions, c, reach) in found.into_iter().flatten() {
        let near_known = known.iter().any(|&(k, r)| (k - c).norm() <= r.max(reach));
        let near_kept = kept
            .iter()
            .any(|&(g, k, r)| g == regions && (k - c).norm() <= r.max(reach));
        if !near_known && !near_kept {
            kept.push((regions, c, reach));
        }
    }
    kept.into_iter().map(|(_, c, r)| (c, r)).collect()
}

/// The three regions of `v`'s ring (`v` and its neighbours `nbr`), sorted, or `None` when it
/// holds another number of regions.
fn ring_regions(v: usize, nbr: &[u32], label: &[u32]) -> Option<[u32; 3]> {
    let mut r: Vec<u32> = std::iter::once(v as u32)
        .chain(nbr.iter().copied())
        .filter_map(|w| label.get(w as usize).copied())
        .collect();
    r.sort_unstable();
    r.dedup();
    (r.len() == 3).then(|| [r[0], r[1], r[2]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::crease_split::tests::Cube;
    use nalgebra::Vector3;

    /// A fan around a vertex of the cube's +z face near its corner (1, 1, 1): one neighbour on
    /// +x, one on +y, two on +z, so the ring holds three regions and no triangle does.
    fn fan(v: Point3<f64>) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let pos = vec![
            v,
            Point3::new(1.0, 0.6, 0.7),
            Point3::new(0.5, 0.5, 1.0),
            Point3::new(0.6, 1.0, 0.7),
            Point3::new(0.85, 0.85, 0.9),
        ];
        (pos, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    }

    fn labels(pos: &[Point3<f64>]) -> Vec<u32> {
        pos.iter().map(|p| Cube.region(p)).collect()
    }

    #[test]
    fn a_corner_around_a_vertex_is_found() {
        let (pos, faces) = fan(Point3::new(0.95, 0.95, 0.97));
        let l = labels(&pos);
        // Three regions in the ring, none in a triangle.
        assert!(faces.iter().all(|f| {
            let mut r = f.map(|v| l[v as usize]).to_vec();
            r.sort_unstable();
            r.dedup();
            r.len() < 3
        }));
        let c = ring_corners(&pos, &faces, &l, &Cube, &CreaseSplitOptions::default(), &[]);
        assert_eq!(c.len(), 1, "{c:?}");
        assert!((c[0].0 - Point3::new(1.0, 1.0, 1.0)).norm() < 1e-6, "{c:?}");
        // Its reach: the ring's longest edge.
        assert!((c[0].1 - (pos[2] - pos[0]).norm()).abs() < 1e-12);
    }

    #[test]
    fn a_corner_beyond_the_ring_s_longest_edge_is_refused() {
        // A ring 0.094 across whose regions meet 0.15 from its vertex: Newton reaches the
        // corner (its steps may be twice the ring), but it belongs to another ring.
        let pos = vec![
            Point3::new(0.9, 0.9, 0.95),
            Point3::new(0.98, 0.9, 0.9),
            Point3::new(0.85, 0.85, 0.98),
            Point3::new(0.9, 0.98, 0.9),
        ];
        let faces = vec![[0, 1, 2], [0, 2, 3]];
        let l = labels(&pos);
        let opts = CreaseSplitOptions::default();
        assert!(ring_corners(&pos, &faces, &l, &Cube, &opts, &[]).is_empty());
        // The same ring twice as wide reaches it.
        let wide: Vec<Point3<f64>> = pos.iter().map(|p| pos[0] + (p - pos[0]) * 2.0).collect();
        let l = labels(&wide);
        let c = ring_corners(&wide, &faces, &l, &Cube, &opts, &[]);
        assert_eq!(c.len(), 1, "{c:?}");
    }

    #[test]
    fn a_known_corner_or_two_regions_give_none() {
        let (pos, faces) = fan(Point3::new(0.95, 0.95, 0.97));
        let l = labels(&pos);
        let opts = CreaseSplitOptions::default();
        let known = [(Point3::new(1.0, 1.0, 0.999), 0.01)];
        assert!(ring_corners(&pos, &faces, &l, &Cube, &opts, &known).is_empty());
        // The +y neighbour moved onto +z: an edge, no corner.
        let (mut pos, faces) = fan(Point3::new(0.95, 0.95, 0.97));
        pos[3] = Point3::new(0.6, 0.9, 1.0);
        let l = labels(&pos);
        assert!(ring_corners(&pos, &faces, &l, &Cube, &opts, &[]).is_empty());
    }

    #[test]
    fn rings_of_one_corner_give_it_once_and_far_corners_are_refused() {
        // Two fans sharing the corner: the second vertex's copy of the fan, shifted in index.
        let (mut pos, mut faces) = fan(Point3::new(0.95, 0.95, 0.97));
        let (p2, f2) = fan(Point3::new(0.93, 0.96, 0.98));
        let off = pos.len() as u32;
        pos.extend(p2);
        faces.extend(f2.iter().map(|f| f.map(|v| v + off)));
        let l = labels(&pos);
        let opts = CreaseSplitOptions::default();
        let c = ring_corners(&pos, &faces, &l, &Cube, &opts, &[]);
        assert_eq!(c.len(), 1, "{c:?}");
        // A ring much smaller than its distance to the corner: the corner is out of reach.
        let s = 0.01;
        let v = Point3::new(0.5, 0.5, 1.0);
        let pos = vec![
            v,
            v + Vector3::new(s, 0.0, 0.0),
            v + Vector3::new(0.0, s, 0.0),
            v + Vector3::new(-s, 0.0, 0.0),
        ];
        // Labels as if the ring held three regions (a mislabelled vertex far from the corner).
        let l = vec![5, 1, 3, 5];
        let faces = vec![[0, 1, 2], [0, 2, 3]];
        assert!(ring_corners(&pos, &faces, &l, &Cube, &opts, &[]).is_empty());
    }
}
