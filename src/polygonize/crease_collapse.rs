//! The staircase of quads along a crease that does not follow the grid, removed by quad
//! collapse (issue 36 item 2, for [`super::crease_nodes`]).
//!
//! A crease at an angle to the voxel grid runs between the quads of its two regions as a
//! staircase of net edges: where the path turns, one quad (of region r) has two consecutive
//! sides a-b and b-c on the crease, both bordering quads of the other region s. Put on the
//! crease, a, b and c would lie on one line and the quad would be a triangle. Such a quad is
//! collapsed along its other diagonal: its corner b and the opposite corner d become one node
//! m (at their midpoint, then put on the crease with the others). The sides a-b and a-d become
//! one edge a-m, b-c and c-d one edge m-c, so the quad across a-b (region s) and the one
//! across a-d (region r) now share a-m, and the crease runs a-m-c, a straight step. The net
//! stays a closed (or open) manifold of quads with one quad and one node fewer; m has the
//! valence val(b) + val(d) - 2 and a and c one less each (irregular nodes on the crease,
//! where the patches meet with G0 only).
//!
//! A collapse is made only when it keeps the net manifold: b and d have no common neighbour
//! but a and c (else an edge would be used three times), no quad but q holds both, neither is
//! on the boundary of an open net, m's valence stays at most [`MAX_VALENCE`] and a's and c's
//! at least 3. Collapses
//! within one round touch disjoint quads' nodes; rounds repeat until none is left (at most
//! [`MAX_ROUNDS`]).

use super::crease_labels::{role_of, NodeRole};
use nalgebra::Point3;
use std::collections::{HashMap, HashSet};

/// Largest valence of a merged node.
pub const MAX_VALENCE: usize = 7;
/// Most collapse rounds.
pub const MAX_ROUNDS: usize = 8;

/// Which staircase quads [`collapse_staircases`] collapses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CollapseScope {
    /// Every step.
    All,
    /// Only the steps at a corner: one of the step's three crease nodes a, b, c has quads of
    /// three or more regions whose surfaces meet near it (the caller's [`CornerOk`]): the
    /// corner-cutting quad of a corner whose node has valence 4, and the step it leaves beside
    /// the merged node, round after round.
    AtCorners,
}

/// Whether three regions' surfaces meet near a node (a corner of the part, not three regions
/// side by side such as a chamfer narrower than a quad between two faces).
pub type CornerOk<'a> = dyn Fn(&Point3<f64>, &[u32]) -> bool + 'a;

/// A quad net as lists, with a region per quad.
pub struct LabelledQuads {
    pub nodes: Vec<Point3<f64>>,
    pub quads: Vec<[u32; 4]>,
    pub quad_region: Vec<u32>,
}

/// Collapses the staircase quads of `net` (module doc); `pinned` nodes (an open net's
/// boundary) are never merged. Returns how many quads were collapsed and the merged nodes
/// (at their new indices: unreferenced nodes are removed at the end).
pub fn collapse_staircases(
    net: &mut LabelledQuads,
    pinned: &[bool],
    scope: CollapseScope,
    corner_ok: &CornerOk<'_>,
) -> (usize, Vec<u32>) {
    let mut merged = vec![false; net.nodes.len()];
    let mut collapsed = 0;
    for _ in 0..MAX_ROUNDS {
        let n = collapse_round(net, pinned, scope, corner_ok, &mut merged);
        if n == 0 {
            break;
        }
        collapsed += n;
    }
    if collapsed == 0 {
        return (0, Vec::new());
    }
    compact(net, &mut merged);
    let merged = (0..merged.len() as u32)
        .filter(|&i| merged[i as usize])
        .collect();
    (collapsed, merged)
}

/// The undirected edge key.
fn key(a: u32, b: u32) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// One round: every staircase quad whose nodes no earlier collapse of the round touched.
fn collapse_round(
    net: &mut LabelledQuads,
    pinned: &[bool],
    scope: CollapseScope,
    corner_ok: &CornerOk<'_>,
    merged: &mut [bool],
) -> usize {
    let mut edge_quads: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    let mut node_quads: HashMap<u32, Vec<usize>> = HashMap::new();
    for (q, quad) in net.quads.iter().enumerate() {
        for k in 0..4 {
            edge_quads
                .entry(key(quad[k], quad[(k + 1) % 4]))
                .or_default()
                .push(q);
            node_quads.entry(quad[k]).or_default().push(q);
        }
    }
    // Corner nodes: quads of three or more regions, whose three most frequent regions'
    // surfaces meet near the node (`corner_ok`).
    let corners: HashSet<u32> = if scope == CollapseScope::AtCorners {
        node_quads
            .iter()
            .filter_map(
                |(&v, qs)| match role_of(qs.iter().map(|&q| net.quad_region[q])) {
                    NodeRole::Corner(three) => {
                        corner_ok(&net.nodes[v as usize], &three).then_some(v)
                    }
                    _ => None,
                },
            )
            .collect()
    } else {
        HashSet::new()
    };
    let is_corner = |v: u32| corners.contains(&v);
    let other = |q: usize, a: u32, b: u32| -> Option<usize> {
        edge_quads
            .get(&key(a, b))
            .and_then(|qs| qs.iter().copied().find(|&o| o != q))
    };
    let neighbours = |v: u32| -> HashSet<u32> {
        let mut s = HashSet::new();
        for &q in node_quads.get(&v).map_or(&[][..], |v| v.as_slice()) {
            let quad = net.quads[q];
            if let Some(k) = quad.iter().position(|&x| x == v) {
                s.insert(quad[(k + 1) % 4]);
                s.insert(quad[(k + 3) % 4]);
            }
        }
        s
    };
    let mut touched: HashSet<u32> = HashSet::new();
    let mut removed = vec![false; net.quads.len()];
    // Node b -> node d it merges into.
    let mut merge: HashMap<u32, u32> = HashMap::new();
    for (q, removed_q) in removed.iter_mut().enumerate() {
        let quad = net.quads[q];
        let r = net.quad_region[q];
        if quad.iter().any(|v| touched.contains(v)) {
            continue;
        }
        for k in 0..4 {
            let (a, b, c, d) = (
                quad[(k + 3) % 4],
                quad[k],
                quad[(k + 1) % 4],
                quad[(k + 2) % 4],
            );
            let (Some(p1), Some(p2)) = (other(q, a, b), other(q, b, c)) else {
                continue;
            };
            let s = net.quad_region[p1];
            if s == r || net.quad_region[p2] != s {
                continue;
            }
            // A peninsula of r (three sides on s) is the relabelling's, not a step.
            if other(q, c, d).is_some_and(|o| net.quad_region[o] == s)
                || other(q, d, a).is_some_and(|o| net.quad_region[o] == s)
            {
                continue;
            }
            if pinned[b as usize] || pinned[d as usize] {
                continue;
            }
            if scope == CollapseScope::AtCorners && ![a, b, c].into_iter().any(is_corner) {
                continue;
            }
            let (nb, nd) = (neighbours(b), neighbours(d));
            let common: Vec<u32> = nb.intersection(&nd).copied().collect();
            if common.iter().any(|&x| x != a && x != c) {
                continue;
            }
            let (qb, qd) = (&node_quads[&b], &node_quads[&d]);
            if qb.iter().any(|o| *o != q && qd.contains(o)) {
                continue;
            }
            if qb.len() + qd.len() - 2 > MAX_VALENCE {
                continue;
            }
            // a and c lose a quad each: at valence 3 they would keep two, which share two
            // sides.
            if [a, c].iter().any(|v| node_quads[v].len() <= 3) {
                continue;
            }
            // The merged node at the midpoint (put on the crease by the caller).
            net.nodes[d as usize] =
                Point3::from((net.nodes[b as usize].coords + net.nodes[d as usize].coords) * 0.5);
            merge.insert(b, d);
            merged[d as usize] = true;
            *removed_q = true;
            for v in quad {
                touched.insert(v);
            }
            for &o in qb.iter().chain(qd.iter()) {
                for v in net.quads[o] {
                    touched.insert(v);
                }
            }
            break;
        }
    }
    if merge.is_empty() {
        return 0;
    }
    let n = merge.len();
    let mut quads = Vec::with_capacity(net.quads.len() - n);
    let mut regions = Vec::with_capacity(net.quads.len() - n);
    for (q, quad) in net.quads.iter().enumerate() {
        if removed[q] {
            continue;
        }
        quads.push(quad.map(|v| merge.get(&v).copied().unwrap_or(v)));
        regions.push(net.quad_region[q]);
    }
    net.quads = quads;
    net.quad_region = regions;
    n
}

/// Drops the nodes no quad uses, renumbering the quads' corners (and `flags`, one per node).
fn compact(net: &mut LabelledQuads, flags: &mut Vec<bool>) {
    let mut used = vec![false; net.nodes.len()];
    for quad in &net.quads {
        for &v in quad {
            used[v as usize] = true;
        }
    }
    let mut index = vec![u32::MAX; net.nodes.len()];
    let mut nodes = Vec::with_capacity(net.nodes.len());
    let mut kept_pins = Vec::with_capacity(net.nodes.len());
    for (i, p) in net.nodes.iter().enumerate() {
        if used[i] {
            index[i] = nodes.len() as u32;
            nodes.push(*p);
            kept_pins.push(flags[i]);
        }
    }
    for quad in &mut net.quads {
        *quad = quad.map(|v| index[v as usize]);
    }
    net.nodes = nodes;
    *flags = kept_pins;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n x n grid of unit quads in z = 0, labelled by which side of the line y = x + 0.5
    /// their centre lies on: a 45-degree crease, a staircase in the grid.
    fn diagonal_grid(n: usize) -> LabelledQuads {
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut nodes = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                nodes.push(Point3::new(i as f64, j as f64, 0.0));
            }
        }
        let mut quads = Vec::new();
        let mut quad_region = Vec::new();
        for j in 0..n {
            for i in 0..n {
                quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                let (cx, cy) = (i as f64 + 0.5, j as f64 + 0.5);
                quad_region.push(u32::from(cy > cx + 0.5));
            }
        }
        LabelledQuads {
            nodes,
            quads,
            quad_region,
        }
    }

    /// Quads with two consecutive sides bordering one same other region.
    fn steps(net: &LabelledQuads) -> usize {
        let mut edge: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
        for (q, quad) in net.quads.iter().enumerate() {
            for k in 0..4 {
                edge.entry(key(quad[k], quad[(k + 1) % 4]))
                    .or_default()
                    .push(q);
            }
        }
        let across = |q: usize, a: u32, b: u32| {
            edge[&key(a, b)]
                .iter()
                .copied()
                .find(|&o| o != q)
                .map(|o| net.quad_region[o])
        };
        net.quads
            .iter()
            .enumerate()
            .filter(|(q, quad)| {
                let r = net.quad_region[*q];
                (0..4).any(|k| {
                    let (a, b, c) = (quad[(k + 3) % 4], quad[k], quad[(k + 1) % 4]);
                    matches!((across(*q, a, b), across(*q, b, c)), (Some(s), Some(t)) if s != r && s == t)
                })
            })
            .count()
    }

    #[test]
    fn a_diagonal_staircase_collapses_to_a_manifold_net_without_steps() {
        let n = 10;
        let mut net = diagonal_grid(n);
        let before = steps(&net);
        assert!(before > 10, "{before} steps");
        let pinned = vec![false; net.nodes.len()];
        // Pin the grid's border, as an open net's boundary is.
        let pinned: Vec<bool> = net
            .nodes
            .iter()
            .zip(pinned)
            .map(|(p, _)| p.x == 0.0 || p.y == 0.0 || p.x == n as f64 || p.y == n as f64)
            .collect();
        let quads_before = net.quads.len();
        let (collapsed, merged) =
            collapse_staircases(&mut net, &pinned, CollapseScope::All, &|_, _| true);
        assert!(collapsed > 0);
        assert!(!merged.is_empty() && merged.len() <= collapsed);
        assert_eq!(net.quads.len(), quads_before - collapsed);
        // Still an open manifold of quads: every edge used once or twice, no repeated corner.
        let mut uses: HashMap<[u32; 2], usize> = HashMap::new();
        for quad in &net.quads {
            let set: HashSet<u32> = quad.iter().copied().collect();
            assert_eq!(set.len(), 4, "{quad:?}");
            for k in 0..4 {
                *uses.entry(key(quad[k], quad[(k + 1) % 4])).or_default() += 1;
            }
        }
        assert!(uses.values().all(|&u| u <= 2));
        // No node inside the grid is left with two quads (which would share two sides).
        let mut valence: HashMap<u32, usize> = HashMap::new();
        for quad in &net.quads {
            for &v in quad {
                *valence.entry(v).or_default() += 1;
            }
        }
        for (&v, &k) in &valence {
            let p = net.nodes[v as usize];
            let inside = p.x > 0.0 && p.y > 0.0 && p.x < n as f64 && p.y < n as f64;
            assert!(!inside || k >= 3, "node {v} at {p:?} with {k} quads");
        }
        crate::polygonize::QuadNet::new_open(net.nodes.clone(), net.quads.clone()).unwrap();
        // Most steps go (measured: 17 -> 7; the others are at the pinned border or would give
        // a node of valence above MAX_VALENCE, on this grid whose merged nodes stay at
        // midpoints rather than on the crease).
        let after = steps(&net);
        assert!(2 * after < before, "{after} steps left of {before}");
    }
}
