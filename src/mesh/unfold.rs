//! Folds inside a region of a labelled mesh, undone by edge flips.
//!
//! A sharp extraction splits the quads of its grid into triangles and moves vertices onto
//! creases; where a quad bent along one diagonal is split along the other, its two triangles
//! make a *fold*: a tent whose normals point more than 90 degrees apart, n0 . n1 < 0, although
//! both lie in one smooth region (make_parts' tilted.stl: 16 such edges in 35 744 triangles,
//! wedge.stl 3). The crease-preserving remesh projects onto these triangles and keeps any corner
//! their labels make, and the quads built on them fold.
//!
//! **Flip.** The shared edge (a, b) of such a pair, (a, b, c) and (b, a, d) of one label, is
//! replaced by (c, d): the triangles (c, a, d) and (d, b, c), in the orientation of the two
//! they replace. The flip is made when the edge (c, d) is not in the mesh yet (the mesh stays
//! manifold) and each new triangle lies flat against a neighbour across one of its other
//! edges, n . n' > [`FLAT_COS`] |n| |n'| (so neither is degenerate or folded); it takes the
//! region of the neighbour it agrees with best. At a corner the tent often stands in for a
//! triangle of another face (the floor of a slot at its end: wedge.stl), which the flip gives
//! back with that face's label. Passes repeat while they flip; each pass visits the edges in
//! order, so the result does not depend on the thread count.

use super::crease_remesh::LabelledMesh;
use nalgebra::Vector3;
use std::collections::HashMap;

/// The new pair's normals must agree this well (cosine) for a flip.
pub const FLAT_COS: f64 = 0.5;

/// What [`unfold`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct UnfoldReport {
    /// Folded edges inside a region found, and flipped flat.
    pub folds: usize,
    pub flipped: usize,
}

fn normal(m: &LabelledMesh, t: &[u32; 3]) -> Vector3<f64> {
    let [a, b, c] = t.map(|v| m.positions[v as usize]);
    (b - a).cross(&(c - a))
}

/// Each directed edge (a, b) of `m`'s triangles -> the triangle walking it.
fn directed_edges(m: &LabelledMesh) -> HashMap<(u32, u32), usize> {
    let mut walk = HashMap::new();
    for (f, t) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            walk.insert((t[k], t[(k + 1) % 3]), f);
        }
    }
    walk
}

/// The folded edges inside a region: (a, b) with its two triangles (the one walking a -> b
/// first), sorted; `walk` from [`directed_edges`].
fn folded_edges(
    m: &LabelledMesh,
    walk: &HashMap<(u32, u32), usize>,
) -> Vec<((u32, u32), usize, usize)> {
    let mut out: Vec<((u32, u32), usize, usize)> = walk
        .iter()
        .filter(|(&(a, b), _)| a < b)
        .filter_map(|(&(a, b), &f0)| {
            let &f1 = walk.get(&(b, a))?;
            let (n0, n1) = (normal(m, &m.triangles[f0]), normal(m, &m.triangles[f1]));
            (m.labels[f0] == m.labels[f1] && n0.dot(&n1) < 0.0).then_some(((a, b), f0, f1))
        })
        .collect();
    out.sort_unstable();
    out
}

/// Flips the folded edges inside the regions of `m` flat where it can (module doc).
pub fn unfold(m: &mut LabelledMesh) -> UnfoldReport {
    let mut report = UnfoldReport::default();
    for pass in 0..8 {
        let mut walk = directed_edges(m);
        let folds = folded_edges(m, &walk);
        if pass == 0 {
            report.folds = folds.len();
        }
        let mut touched = vec![false; m.triangles.len()];
        let mut flips = 0;
        for ((a, b), f0, f1) in folds {
            if touched[f0] || touched[f1] {
                continue;
            }
            let opposite = |f: usize| {
                m.triangles[f]
                    .into_iter()
                    .find(|&v| v != a && v != b)
                    .unwrap_or(a)
            };
            let (c, d) = (opposite(f0), opposite(f1));
            if c == d || walk.contains_key(&(c, d)) || walk.contains_key(&(d, c)) {
                continue;
            }
            let (t0, t1) = ([c, a, d], [d, b, c]);
            let (Some(l0), Some(l1)) = (
                best_neighbour(m, &walk, &t0, [f0, f1]),
                best_neighbour(m, &walk, &t1, [f0, f1]),
            ) else {
                continue;
            };
            m.triangles[f0] = t0;
            m.triangles[f1] = t1;
            m.labels[f0] = l0;
            m.labels[f1] = l1;
            // The directed edges: (a, b) and (b, a) go, (c, d) and (d, c) come, (a, d) and
            // (b, c) change triangle; the neighbours' own entries stay.
            walk.remove(&(a, b));
            walk.remove(&(b, a));
            walk.insert((a, d), f0);
            walk.insert((d, c), f0);
            walk.insert((c, a), f0);
            walk.insert((d, b), f1);
            walk.insert((b, c), f1);
            walk.insert((c, d), f1);
            touched[f0] = true;
            touched[f1] = true;
            flips += 1;
        }
        report.flipped += flips;
        if flips == 0 {
            break;
        }
    }
    report
}

/// The label of the neighbour across an edge of the new triangle `t` (not one of the pair
/// `pair` being flipped) whose normal agrees best with `t`'s, if any agrees within
/// [`FLAT_COS`]: the region the new triangle lies in.
fn best_neighbour(
    m: &LabelledMesh,
    walk: &HashMap<(u32, u32), usize>,
    t: &[u32; 3],
    pair: [usize; 2],
) -> Option<u32> {
    let n = normal(m, t);
    let len = n.norm();
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    (0..3)
        .filter_map(|k| walk.get(&(t[(k + 1) % 3], t[k])).copied())
        .filter(|f| !pair.contains(f))
        .map(|f| {
            let nf = normal(m, &m.triangles[f]);
            (n.dot(&nf) / (len * nf.norm()), m.labels[f])
        })
        .filter(|(cos, _)| *cos > FLAT_COS)
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, l)| l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    /// Two triangles on the diagonal 0-2 of the square (0, 0)-(1, 1) in z = 0, the second's
    /// third corner pulled back over the first (to (0.9, 0.2, 0.1)): a fold, as a quad split
    /// along the wrong diagonal gives; the other diagonal, 1-3, gives two upward triangles,
    /// each flat against a neighbour (the one right of 1-2 in region 2).
    fn tent(label1: u32) -> LabelledMesh {
        LabelledMesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.9, 0.2, 0.1),
                Point3::new(0.5, -1.0, 0.0),
                Point3::new(2.0, 0.5, 0.0),
            ],
            // With flat neighbours below the edge 0-1 and right of 1-2.
            triangles: vec![[0, 1, 2], [0, 2, 3], [1, 0, 4], [2, 1, 5]],
            labels: vec![0, label1, 0, 2],
        }
    }

    #[test]
    fn a_fold_inside_a_region_is_flipped_flat() {
        let mut m = tent(0);
        let n = |m: &LabelledMesh, f: usize| normal(m, &m.triangles[f]);
        assert!(n(&m, 0).dot(&n(&m, 1)) < 0.0);
        let r = unfold(&mut m);
        assert_eq!(
            r,
            UnfoldReport {
                folds: 1,
                flipped: 1
            }
        );
        assert!(folded_edges(&m, &directed_edges(&m)).is_empty());
        // The diagonal is now 1-3, the orientation kept (normals up, as the neighbours').
        let has = |t: &[u32; 3], a, b| t.contains(&a) && t.contains(&b);
        assert!(has(&m.triangles[0], 1, 3) && has(&m.triangles[1], 1, 3));
        for f in 0..2 {
            assert!(n(&m, f).z > 0.0, "{:?}", m.triangles[f]);
        }
        // Each took the region of the neighbour it lies against.
        let t13 = |l| (0..2).find(|&f| m.labels[f] == l).map(|f| m.triangles[f]);
        assert!(t13(2).is_some_and(|t| t.contains(&2)), "{:?}", m.labels);
        assert!(t13(0).is_some_and(|t| t.contains(&0)), "{:?}", m.labels);
    }

    #[test]
    fn a_crease_between_two_regions_is_left_alone() {
        let mut m = tent(1);
        let before = m.triangles.clone();
        assert_eq!(unfold(&mut m), UnfoldReport::default());
        assert_eq!(m.triangles, before);
    }
}
