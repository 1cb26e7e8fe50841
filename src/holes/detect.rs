//! Which boundary loops are holes to fill (seed 002 section 3.1 and its hole list: each loop is
//! a hole or the border, and simple or twisted).
//!
//! The loops come from [`Topology`]: walked with the faces on the left, with the longest loop
//! of an open sheet flagged as its outer border (when it is longer than the sheet's bounding-box
//! diagonal). That length test also flags a large hole with a jagged ring in a closed surface,
//! so a flagged loop is taken for the border only if it also spans the sheet: its own
//! bounding-box diagonal is at least half the component's. A loop is left open when it is the
//! border (unless `keep_border` is off) or when its size exceeds `max_size` (an opening by
//! design).
//! Twisted loops, which pass a vertex more than once, are cut at the repeated vertices into
//! simple loops, each filled on its own.

use crate::mesh::{Mesh, Topology};

/// What a loop is taken for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LoopKind {
    /// A hole to fill.
    Hole,
    /// The outer border of an open sheet (left open while `keep_border` is on).
    OuterBorder,
    /// Larger than `max_size` (left open).
    TooLarge,
}

/// One simple loop to consider.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DetectedLoop {
    /// Index of the loop in [`Topology::loops`].
    pub loop_index: usize,
    /// Part of that loop when it was twisted and cut (0 otherwise).
    pub part: usize,
    /// The loop's vertices in boundary-walk order (faces on the left).
    pub vertices: Vec<u32>,
    /// Sum of the edge lengths.
    pub perimeter: f64,
    /// The hole's size: the diagonal of its vertices' bounding box.
    pub size: f64,
    /// True when it came from a twisted loop.
    pub twisted: bool,
    pub kind: LoopKind,
}

/// Lists the loops of `topo`, cut into simple loops, and classifies them (see the module doc).
pub fn detect_holes(
    mesh: &Mesh,
    topo: &Topology,
    keep_border: bool,
    max_size: Option<f64>,
) -> Vec<DetectedLoop> {
    // Bounding-box diagonal of each component.
    let mut boxes: Vec<Option<crate::mesh::Aabb>> = vec![None; topo.components.len()];
    for (fi, f) in mesh.faces.iter().enumerate() {
        let Some(&c) = topo.face_component.get(fi) else {
            continue;
        };
        for &v in f {
            let p = mesh.positions[v as usize];
            let b = boxes[c as usize].get_or_insert(crate::mesh::Aabb { min: p, max: p });
            b.min = b.min.inf(&p);
            b.max = b.max.sup(&p);
        }
    }
    let comp_diag = |c: u32| {
        boxes
            .get(c as usize)
            .copied()
            .flatten()
            .map(|b| b.diagonal())
            .unwrap_or(0.0)
    };
    let mut out = Vec::new();
    for (li, lp) in topo.loops.iter().enumerate() {
        let whole_size = crate::mesh::Aabb::of(
            &lp.vertices
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .collect::<Vec<_>>(),
        )
        .map(|b| b.diagonal())
        .unwrap_or(0.0);
        let border = lp.outer_border && whole_size >= 0.5 * comp_diag(lp.component);
        let parts = if lp.twisted {
            split_twisted(&lp.vertices)
        } else {
            vec![lp.vertices.clone()]
        };
        for (pi, verts) in parts.into_iter().enumerate() {
            let pts: Vec<_> = verts.iter().map(|&v| mesh.positions[v as usize]).collect();
            let perimeter = (0..pts.len())
                .map(|i| (pts[(i + 1) % pts.len()] - pts[i]).norm())
                .sum();
            let size = crate::mesh::Aabb::of(&pts)
                .map(|b| b.diagonal())
                .unwrap_or(0.0);
            let kind = if border && keep_border {
                LoopKind::OuterBorder
            } else if max_size.is_some_and(|m| size > m) {
                LoopKind::TooLarge
            } else {
                LoopKind::Hole
            };
            out.push(DetectedLoop {
                loop_index: li,
                part: pi,
                vertices: verts,
                perimeter,
                size,
                twisted: lp.twisted,
                kind,
            });
        }
    }
    out
}

/// Cuts a closed vertex walk at its repeated vertices into simple closed walks (in order of
/// completion). Parts with fewer than three vertices (a walk back along the same edge) are
/// dropped: they enclose nothing.
pub fn split_twisted(walk: &[u32]) -> Vec<Vec<u32>> {
    let mut parts = Vec::new();
    let mut stack: Vec<u32> = Vec::with_capacity(walk.len());
    let mut pos: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    for &v in walk {
        if let Some(&p) = pos.get(&v) {
            // Close the sub-walk v .. (top of stack) .. v.
            let part: Vec<u32> = stack[p..].to_vec();
            for u in &stack[p + 1..] {
                pos.remove(u);
            }
            stack.truncate(p + 1);
            if part.len() >= 3 {
                parts.push(part);
            }
        } else {
            pos.insert(v, stack.len());
            stack.push(v);
        }
    }
    if stack.len() >= 3 {
        parts.push(stack);
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figure_eight_splits_in_two() {
        // 0 1 2 0 3 4: two triangles sharing vertex 0.
        let parts = split_twisted(&[0, 1, 2, 0, 3, 4]);
        assert_eq!(parts, vec![vec![0, 1, 2], vec![0, 3, 4]]);
        // Nested: 0 1 2 3 1 4 5 -> [1 2 3], [0 1 4 5].
        let parts = split_twisted(&[0, 1, 2, 3, 1, 4, 5]);
        assert_eq!(parts, vec![vec![1, 2, 3], vec![0, 1, 4, 5]]);
        // Simple walk stays whole.
        assert_eq!(split_twisted(&[5, 6, 7, 8]), vec![vec![5, 6, 7, 8]]);
    }

    #[test]
    fn large_jagged_hole_in_a_closed_surface_is_a_hole() {
        // A coarse sphere with a cap cut off: the ring is longer than the bounding-box
        // diagonal (Topology flags it), but spans only part of the sphere.
        let s = crate::holes::testing::cube_sphere(12, 1.0);
        let cut = crate::holes::cut::cut_ball(&s, &nalgebra::Point3::new(0.0, 0.0, 1.0), 0.4);
        let t = Topology::build(&cut);
        assert!(t.loops[0].outer_border);
        let d = detect_holes(&cut, &t, true, None);
        assert_eq!(d[0].kind, LoopKind::Hole);
    }

    #[test]
    fn border_and_size_classification() {
        let mut m = Mesh::default();
        let n = 6;
        for j in 0..=n {
            for i in 0..=n {
                m.positions
                    .push(nalgebra::Point3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                if (i, j) == (2, 2) {
                    continue;
                }
                m.faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let t = Topology::build(&m);
        let d = detect_holes(&m, &t, true, None);
        assert_eq!(d.len(), 2);
        assert_eq!(d.iter().filter(|l| l.kind == LoopKind::Hole).count(), 1);
        assert_eq!(
            d.iter().filter(|l| l.kind == LoopKind::OuterBorder).count(),
            1
        );
        let d = detect_holes(&m, &t, false, Some(2.0));
        assert_eq!(d.iter().filter(|l| l.kind == LoopKind::Hole).count(), 1);
        assert_eq!(d.iter().filter(|l| l.kind == LoopKind::TooLarge).count(), 1);
        let hole = d.iter().find(|l| l.kind == LoopKind::Hole).unwrap();
        assert!((hole.size - 2f64.sqrt()).abs() < 1e-12);
        assert!((hole.perimeter - 4.0).abs() < 1e-12);
    }
}
