//! Self-intersection check of a fill: does any fill triangle cut through the mesh near it, or
//! through another fill triangle?
//!
//! Hand-written because no crate in the dependency set has triangle-triangle tests (parry3d
//! would bring a whole physics stack for one predicate). Two triangles with no common vertex
//! intersect when an edge of one crosses the other (the segment-triangle test of Möller and
//! Trumbore), or, when coplanar, when their 2D projections overlap. Triangles sharing one vertex
//! intersect when an edge of one leaves the shared vertex into the other, or the opposite edge
//! crosses it; triangles sharing an edge intersect only when folded flat onto each other.
//! Candidate pairs come from a uniform grid over the fill's bounding box.

use super::neighbourhood::VertexFaces;
use super::patch::Patch;
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use std::collections::{HashMap, HashSet};

type Tri = [Point3<f64>; 3];

/// Pairs (fill face, other face) that intersect, for the faces `first_fill..` of `mesh` against
/// every face of `mesh` (fill faces pairwise once), sorted. Face indices into `mesh.faces`.
///
/// Candidates come from a uniform grid over the fill's box (cells about twice the mean fill
/// edge), held as a sorted list of (cell, face) entries; a pair is tested only in the first
/// cell the two faces share, so no pair is tested twice.
pub fn fill_intersections(mesh: &Mesh, first_fill: usize) -> Vec<(u32, u32)> {
    let nf = mesh.faces.len();
    if first_fill >= nf {
        return Vec::new();
    }
    let tri = |f: usize| -> Tri {
        let t = mesh.faces[f];
        [
            mesh.positions[t[0] as usize],
            mesh.positions[t[1] as usize],
            mesh.positions[t[2] as usize],
        ]
    };
    let mut lo = Point3::from(Vector3::repeat(f64::INFINITY));
    let mut hi = Point3::from(Vector3::repeat(f64::NEG_INFINITY));
    let mut edge_sum = 0.0;
    for f in first_fill..nf {
        let t = tri(f);
        for k in 0..3 {
            lo = lo.inf(&t[k]);
            hi = hi.sup(&t[k]);
            edge_sum += (t[k] - t[(k + 1) % 3]).norm();
        }
    }
    let mut cell = (2.0 * edge_sum / (3 * (nf - first_fill)) as f64).max(1e-12);
    let (lo, hi) = (lo - Vector3::repeat(cell), hi + Vector3::repeat(cell));
    // Keep the grid's cell count within u64 keys (and sane).
    while ((hi - lo) / cell)
        .iter()
        .map(|d| d.ceil() + 1.0)
        .product::<f64>()
        > 1e15
    {
        cell *= 2.0;
    }
    let dims: [i64; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / cell).ceil() as i64 + 1);
    let cell_of = |p: &Point3<f64>| -> [i64; 3] {
        std::array::from_fn(|k| (((p[k] - lo[k]) / cell).floor() as i64).clamp(0, dims[k] - 1))
    };
    let linear = |c: [i64; 3]| ((c[0] * dims[1] + c[1]) * dims[2] + c[2]) as u64;
    // Cell range of a face, `None` outside the box.
    let range = |f: usize| -> Option<([i64; 3], [i64; 3])> {
        let t = tri(f);
        let (mut a, mut b) = (t[0], t[0]);
        for p in &t {
            a = a.inf(p);
            b = b.sup(p);
        }
        if b.x < lo.x || b.y < lo.y || b.z < lo.z || a.x > hi.x || a.y > hi.y || a.z > hi.z {
            return None;
        }
        Some((cell_of(&a), cell_of(&b)))
    };
    // Faces in the box with their lowest cell; entries (cell, slot in `inbox`).
    let mut inbox: Vec<(u32, [i64; 3])> = Vec::new();
    let mut entries: Vec<(u64, u32)> = Vec::new();
    for f in 0..nf {
        if let Some((ca, cb)) = range(f) {
            let slot = inbox.len() as u32;
            inbox.push((f as u32, ca));
            for i in ca[0]..=cb[0] {
                for j in ca[1]..=cb[1] {
                    for k in ca[2]..=cb[2] {
                        entries.push((linear([i, j, k]), slot));
                    }
                }
            }
        }
    }
    entries.sort_unstable();
    let mut pairs = Vec::new();
    let mut start = 0;
    while start < entries.len() {
        let key = entries[start].0;
        let mut end = start;
        while end < entries.len() && entries[end].0 == key {
            end += 1;
        }
        let group = &entries[start..end];
        for &(_, sf) in group {
            let (f, fa) = inbox[sf as usize];
            if (f as usize) < first_fill {
                continue;
            }
            for &(_, sg) in group {
                let (g, ga) = inbox[sg as usize];
                let g_fill = (g as usize) >= first_fill;
                if g == f || (g_fill && g < f) {
                    continue;
                }
                // Test each pair once: in the first cell both faces cover.
                let first = std::array::from_fn(|k| fa[k].max(ga[k]));
                if linear(first) != key {
                    continue;
                }
                if faces_intersect(mesh, f as usize, g as usize) {
                    pairs.push(if g_fill { (f.min(g), f.max(g)) } else { (f, g) });
                }
            }
        }
        start = end;
    }
    pairs.sort_unstable();
    pairs
}

/// Intersecting pairs between a hole's fill and the mesh near it (the faces reached from the
/// ring through faces overlapping the fill's bounding box), and among the fill's own faces.
pub fn patch_intersections(mesh: &Mesh, vf: &VertexFaces, patch: &Patch) -> usize {
    if patch.faces.is_empty() {
        return 0;
    }
    let mut lo = Point3::from(Vector3::repeat(f64::INFINITY));
    let mut hi = Point3::from(Vector3::repeat(f64::NEG_INFINITY));
    for p in &patch.positions {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let pad = Vector3::repeat(1e-9 * (hi - lo).norm());
    let (lo, hi) = (lo - pad, hi + pad);
    let overlaps = |f: u32| {
        let t = mesh.faces[f as usize];
        let (mut a, mut b) = (mesh.positions[t[0] as usize], mesh.positions[t[0] as usize]);
        for &v in &t[1..] {
            a = a.inf(&mesh.positions[v as usize]);
            b = b.sup(&mesh.positions[v as usize]);
        }
        !(b.x < lo.x || b.y < lo.y || b.z < lo.z || a.x > hi.x || a.y > hi.y || a.z > hi.z)
    };
    // Flood from the ring's faces through faces overlapping the box.
    let mut seen: HashSet<u32> = HashSet::new();
    let mut stack: Vec<u32> = Vec::new();
    for &g in &patch.global {
        for &f in vf.of(g) {
            if seen.insert(f) {
                stack.push(f);
            }
        }
    }
    let mut near: Vec<u32> = Vec::new();
    while let Some(f) = stack.pop() {
        if !overlaps(f) {
            continue;
        }
        near.push(f);
        for &v in &mesh.faces[f as usize] {
            for &g in vf.of(v) {
                if seen.insert(g) {
                    stack.push(g);
                }
            }
        }
    }
    near.sort_unstable();
    // A small mesh: the patch's vertices (ring first, as in the mesh), then the others.
    let mut local: HashMap<u32, u32> = patch
        .global
        .iter()
        .enumerate()
        .map(|(i, &g)| (g, i as u32))
        .collect();
    let mut sub = Mesh {
        positions: patch.positions.clone(),
        normals: None,
        faces: Vec::with_capacity(near.len() + patch.faces.len()),
    };
    for &f in &near {
        let t = mesh.faces[f as usize];
        let mut lf = [0u32; 3];
        for k in 0..3 {
            lf[k] = *local.entry(t[k]).or_insert_with(|| {
                sub.positions.push(mesh.positions[t[k] as usize]);
                (sub.positions.len() - 1) as u32
            });
        }
        sub.faces.push(lf);
    }
    let first = sub.faces.len();
    sub.faces.extend_from_slice(&patch.faces);
    fill_intersections(&sub, first).len()
}

/// Do faces `f` and `g` of `mesh` intersect beyond what their shared vertices allow?
pub fn faces_intersect(mesh: &Mesh, f: usize, g: usize) -> bool {
    let (a, b) = (mesh.faces[f], mesh.faces[g]);
    let p = |v: u32| mesh.positions[v as usize];
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| a[i] == b[j])
        .collect();
    let ta: Tri = [p(a[0]), p(a[1]), p(a[2])];
    let tb: Tri = [p(b[0]), p(b[1]), p(b[2])];
    match shared.len() {
        0 => triangles_intersect(&ta, &tb),
        1 => {
            let (i, j) = shared[0];
            touching_at_vertex(&ta, i, &tb) || touching_at_vertex(&tb, j, &ta)
        }
        2 => {
            // Folded flat onto each other: the two opposite vertices on the same side of the
            // shared edge, in the same plane.
            let ia = (0..3)
                .find(|i| !shared.iter().any(|s| s.0 == *i))
                .unwrap_or(0);
            let jb = (0..3)
                .find(|j| !shared.iter().any(|s| s.1 == *j))
                .unwrap_or(0);
            let (s0, s1) = (ta[shared[0].0], ta[shared[1].0]);
            let e = s1 - s0;
            let u = (ta[ia] - s0) - e * ((ta[ia] - s0).dot(&e) / e.norm_squared());
            let w = (tb[jb] - s0) - e * ((tb[jb] - s0).dot(&e) / e.norm_squared());
            let c = u.dot(&w) / (u.norm() * w.norm());
            c > 1.0 - 1e-9
        }
        _ => false,
    }
}

/// Triangles `t` and `o` share vertex `t[i]`: does `t` reach into `o` elsewhere?
fn touching_at_vertex(t: &Tri, i: usize, o: &Tri) -> bool {
    let s = t[i];
    let (u, w) = (t[(i + 1) % 3], t[(i + 2) % 3]);
    let scale = (u - s).norm().max((w - s).norm());
    let eps = 1e-9;
    // The usual case: t's other two vertices strictly on one side of o's plane, so t meets that
    // plane only at the shared vertex.
    let n = (o[1] - o[0]).cross(&(o[2] - o[0]));
    let nl = n.norm();
    if nl > 0.0 {
        let (du, dw) = ((u - s).dot(&n) / nl, (w - s).dot(&n) / nl);
        let tiny = 1e-12 * scale;
        if (du > tiny && dw > tiny) || (du < -tiny && dw < -tiny) {
            return false;
        }
    }
    // The opposite edge of t crossing o.
    if segment_hits_triangle(&u, &w, o, eps).is_some() {
        return true;
    }
    // Edges leaving the shared vertex: hits beyond the vertex itself.
    for q in [u, w] {
        if let Some(tt) = segment_hits_triangle(&s, &q, o, eps) {
            if tt * (q - s).norm() > 1e-7 * scale {
                return true;
            }
        }
    }
    false
}

/// Parameter t in [0, 1] where segment p-q meets triangle `tri` (non-coplanar case), with a
/// relative tolerance `eps` on the barycentric coordinates.
fn segment_hits_triangle(p: &Point3<f64>, q: &Point3<f64>, tri: &Tri, eps: f64) -> Option<f64> {
    let d = q - p;
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    let scale = e1.norm() * e2.norm() * d.norm();
    if det.abs() <= 1e-12 * scale {
        return None; // parallel: handled by the coplanar test
    }
    let inv = 1.0 / det;
    let s = p - tri[0];
    let u = s.dot(&h) * inv;
    if !(-eps..=1.0 + eps).contains(&u) {
        return None;
    }
    let qv = s.cross(&e1);
    let v = d.dot(&qv) * inv;
    if v < -eps || u + v > 1.0 + eps {
        return None;
    }
    let t = e2.dot(&qv) * inv;
    (-eps..=1.0 + eps).contains(&t).then_some(t.clamp(0.0, 1.0))
}

/// General triangle-triangle intersection (no shared vertices).
pub fn triangles_intersect(a: &Tri, b: &Tri) -> bool {
    let na = (a[1] - a[0]).cross(&(a[2] - a[0]));
    let la = na.norm();
    let size = (a[1] - a[0]).norm().max((b[1] - b[0]).norm());
    if la > 0.0 {
        let dist: [f64; 3] = std::array::from_fn(|k| (b[k] - a[0]).dot(&na) / la);
        if dist.iter().all(|d| d.abs() <= 1e-12 * size) {
            return coplanar_overlap(a, b, &na);
        }
        if dist.iter().all(|&d| d > 1e-12 * size) || dist.iter().all(|&d| d < -1e-12 * size) {
            return false;
        }
    }
    // And a against b's plane.
    let nb = (b[1] - b[0]).cross(&(b[2] - b[0]));
    let lb = nb.norm();
    if lb > 0.0 {
        let dist: [f64; 3] = std::array::from_fn(|k| (a[k] - b[0]).dot(&nb) / lb);
        if dist.iter().all(|&d| d > 1e-12 * size) || dist.iter().all(|&d| d < -1e-12 * size) {
            return false;
        }
    }
    for k in 0..3 {
        if segment_hits_triangle(&a[k], &a[(k + 1) % 3], b, 0.0).is_some()
            || segment_hits_triangle(&b[k], &b[(k + 1) % 3], a, 0.0).is_some()
        {
            return true;
        }
    }
    false
}

/// Overlap of two coplanar triangles (normal `n`): projected to the dominant plane.
fn coplanar_overlap(a: &Tri, b: &Tri, n: &Vector3<f64>) -> bool {
    let ax = if n.x.abs() >= n.y.abs() && n.x.abs() >= n.z.abs() {
        0
    } else if n.y.abs() >= n.z.abs() {
        1
    } else {
        2
    };
    let (i, j) = ((ax + 1) % 3, (ax + 2) % 3);
    let pa: Vec<nalgebra::Point2<f64>> = a
        .iter()
        .map(|p| nalgebra::Point2::new(p[i], p[j]))
        .collect();
    let pb: Vec<nalgebra::Point2<f64>> = b
        .iter()
        .map(|p| nalgebra::Point2::new(p[i], p[j]))
        .collect();
    use super::plane::orient;
    let proper = |p: &nalgebra::Point2<f64>,
                  q: &nalgebra::Point2<f64>,
                  r: &nalgebra::Point2<f64>,
                  s: &nalgebra::Point2<f64>| {
        let (d1, d2) = (orient(p, q, r), orient(p, q, s));
        let (d3, d4) = (orient(r, s, p), orient(r, s, q));
        d1 * d2 < 0.0 && d3 * d4 < 0.0
    };
    for k in 0..3 {
        for l in 0..3 {
            if proper(&pa[k], &pa[(k + 1) % 3], &pb[l], &pb[(l + 1) % 3]) {
                return true;
            }
        }
    }
    let strictly_inside = |p: &nalgebra::Point2<f64>, t: &[nalgebra::Point2<f64>]| {
        let s = orient(&t[0], &t[1], &t[2]).signum();
        (0..3).all(|k| orient(&t[k], &t[(k + 1) % 3], p) * s > 0.0)
    };
    pa.iter().any(|p| strictly_inside(p, &pb)) || pb.iter().any(|p| strictly_inside(p, &pa))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Tri {
        [Point3::from(a), Point3::from(b), Point3::from(c)]
    }

    #[test]
    fn crossing_and_separate_triangles() {
        let a = t([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
        let b = t([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.0]);
        assert!(triangles_intersect(&a, &b));
        let c = t([0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [0.5, 1.5, 0.5]);
        assert!(!triangles_intersect(&a, &c));
        let d = t([0.2, 0.2, 0.0], [0.8, 0.2, 0.0], [0.2, 0.8, 0.0]);
        assert!(triangles_intersect(&a, &d), "coplanar overlap");
        let e = t([5.0, 5.0, 0.0], [6.0, 5.0, 0.0], [5.0, 6.0, 0.0]);
        assert!(!triangles_intersect(&a, &e));
    }

    #[test]
    fn shared_vertex_and_edge_cases() {
        let mut m = Mesh::default();
        for p in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.2, 0.2, 1.0],
            [0.3, 0.3, -1.0],
            [0.2, 0.1, 0.0],
            [-1.0, 0.5, 0.3],
        ] {
            m.positions.push(Point3::from(p));
        }
        // Two flat neighbours across edge 1-2: fine.
        m.faces = vec![[0, 1, 2], [1, 3, 2]];
        assert!(!faces_intersect(&m, 0, 1));
        // Sharing vertex 0, reaching through face 0 (edge 4-5 crosses it).
        m.faces = vec![[0, 1, 2], [0, 4, 5]];
        assert!(faces_intersect(&m, 0, 1));
        // Sharing vertex 0, just touching there.
        m.faces = vec![[0, 1, 2], [0, 4, 7]];
        assert!(!faces_intersect(&m, 0, 1));
        // Sharing edge 0-1 and folded flat back onto face 0.
        m.faces = vec![[0, 1, 2], [1, 0, 6]];
        assert!(faces_intersect(&m, 0, 1));
        // fill_intersections finds the crossing pair.
        m.faces = vec![[0, 1, 2], [5, 4, 3]];
        assert_eq!(fill_intersections(&m, 1), vec![(1, 0)]);
    }
}
