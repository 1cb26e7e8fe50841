//! An oriented 2-manifold quad mesh (the "quad net" of seed 004 section 3) with the adjacency
//! that smoothing, sampling and export need: closed (the surface of a solid), or with a boundary
//! (the scanned part of a surface, `fit --close open`, [`crate::openings`]).
//!
//! Inputs: node positions and quads `[a, b, c, d]`, counter-clockwise seen from outside (the
//! outward normal is `(b - a) x (d - a)`). [`QuadNet::new`] builds and validates:
//! - every edge is used by exactly two quads, walking it in opposite directions (closed,
//!   consistently oriented, no edge shared by four quads);
//! - the quads around every node form one cycle (no vertex where two sheets touch);
//! - every node is used, no quad repeats a node.
//!
//! [`QuadNet::new_open`] accepts, in addition, *boundary edges* used by one quad; the quads
//! around a node then form one cycle (inner node) or one chain (boundary node: two boundary
//! edges, so the boundary is a set of simple loops).
//!
//! Outputs: `edges` (sorted `[lo, hi]` pairs), `edge_quads` (the quad walking the edge lo -> hi,
//! then the one walking it hi -> lo; [`NO_QUAD`] on the missing side of a boundary edge),
//! `quad_edges` (edge of side k, which runs from corner k to corner k + 1), and a node -> quads
//! table.

use crate::{Error, Result};
use nalgebra::Point3;

/// The missing quad of a boundary edge in [`QuadNet::edge_quads`].
pub const NO_QUAD: u32 = u32::MAX;

/// A closed, consistently oriented, 2-manifold quad mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadNet {
    /// Node positions.
    pub nodes: Vec<Point3<f64>>,
    /// Quads, counter-clockwise seen from outside.
    pub quads: Vec<[u32; 4]>,
    /// Undirected edges `[lo, hi]`, `lo < hi`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Per edge: `[quad walking lo -> hi, quad walking hi -> lo]`; [`NO_QUAD`] on the open side
    /// of a boundary edge.
    pub edge_quads: Vec<[u32; 2]>,
    /// Per quad: edge index of side k (from corner k to corner (k + 1) % 4).
    pub quad_edges: Vec<[u32; 4]>,
    /// Node -> incident quads as a compressed table: quads of node i are
    /// `node_quad_list[node_quad_offsets[i]..node_quad_offsets[i + 1]]`, in cyclic order
    /// (counter-clockwise seen from outside); at a boundary node the chain starts and ends at
    /// the node's two boundary quads.
    pub node_quad_offsets: Vec<u32>,
    pub node_quad_list: Vec<u32>,
}

impl QuadNet {
    /// Builds the adjacency and checks that the quads form a closed, consistently oriented
    /// 2-manifold. Errors name the first offending edge or node.
    pub fn new(nodes: Vec<Point3<f64>>, quads: Vec<[u32; 4]>) -> Result<QuadNet> {
        Self::build(nodes, quads, false)
    }

    /// [`QuadNet::new`] for a net that may have a boundary: edges used by one quad are allowed,
    /// every node's quads must form one cycle or one chain.
    pub fn new_open(nodes: Vec<Point3<f64>>, quads: Vec<[u32; 4]>) -> Result<QuadNet> {
        Self::build(nodes, quads, true)
    }

    fn build(nodes: Vec<Point3<f64>>, quads: Vec<[u32; 4]>, open: bool) -> Result<QuadNet> {
        let n = nodes.len();
        if quads.is_empty() {
            return Err(Error::Degenerate("quad net has no quads".into()));
        }
        if n > u32::MAX as usize || quads.len() > u32::MAX as usize / 4 {
            return Err(Error::Degenerate(
                "quad net too large for u32 indices".into(),
            ));
        }
        for (q, quad) in quads.iter().enumerate() {
            for k in 0..4 {
                if quad[k] as usize >= n {
                    return Err(Error::Degenerate(format!(
                        "quad {q} uses node {} past the {n} nodes",
                        quad[k]
                    )));
                }
                for l in k + 1..4 {
                    if quad[k] == quad[l] {
                        return Err(Error::Degenerate(format!(
                            "quad {q} repeats node {}",
                            quad[k]
                        )));
                    }
                }
            }
        }
        // Directed half-edges (lo, hi, forward?, quad, side), sorted: the two uses of an
        // undirected edge become neighbours.
        let mut half: Vec<(u32, u32, bool, u32, u8)> = Vec::with_capacity(quads.len() * 4);
        for (q, quad) in quads.iter().enumerate() {
            for k in 0..4 {
                let (a, b) = (quad[k], quad[(k + 1) % 4]);
                half.push((a.min(b), a.max(b), a < b, q as u32, k as u8));
            }
        }
        half.sort_unstable();
        let mut edges = Vec::with_capacity(half.len() / 2);
        let mut edge_quads = Vec::with_capacity(half.len() / 2);
        let mut quad_edges = vec![[u32::MAX; 4]; quads.len()];
        let mut i = 0;
        while i < half.len() {
            let (lo, hi) = (half[i].0, half[i].1);
            let mut j = i;
            while j < half.len() && half[j].0 == lo && half[j].1 == hi {
                j += 1;
            }
            let uses = j - i;
            if open && uses == 1 {
                let one = half[i];
                let e = edges.len() as u32;
                edges.push([lo, hi]);
                edge_quads.push(if one.2 {
                    [one.3, NO_QUAD]
                } else {
                    [NO_QUAD, one.3]
                });
                quad_edges[one.3 as usize][one.4 as usize] = e;
                i = j;
                continue;
            }
            if uses != 2 {
                let needs = if open { "1 or 2" } else { "2" };
                return Err(Error::Degenerate(format!(
                    "edge {lo}-{hi} is used by {uses} quads (a 2-manifold needs {needs})"
                )));
            }
            // Sorted by `forward`: false (hi -> lo) first, then true (lo -> hi).
            let (bwd, fwd) = (half[i], half[i + 1]);
            if !fwd.2 || bwd.2 {
                return Err(Error::Degenerate(format!(
                    "edge {lo}-{hi}: its two quads walk it in the same direction (inconsistent orientation)"
                )));
            }
            let e = edges.len() as u32;
            edges.push([lo, hi]);
            edge_quads.push([fwd.3, bwd.3]);
            quad_edges[fwd.3 as usize][fwd.4 as usize] = e;
            quad_edges[bwd.3 as usize][bwd.4 as usize] = e;
            i = j;
        }
        let (node_quad_offsets, node_quad_list) = node_fans(n, &quads, open)?;
        Ok(QuadNet {
            nodes,
            quads,
            edges,
            edge_quads,
            quad_edges,
            node_quad_offsets,
            node_quad_list,
        })
    }

    /// Quads around node `i`, counter-clockwise seen from outside.
    pub fn node_quads(&self, i: usize) -> &[u32] {
        let (a, b) = (
            self.node_quad_offsets[i] as usize,
            self.node_quad_offsets[i + 1] as usize,
        );
        &self.node_quad_list[a..b]
    }

    /// Number of edges (= number of quads) at node `i`.
    pub fn valence(&self, i: usize) -> usize {
        self.node_quads(i).len()
    }

    /// Corner index (0..4) of node `i` in quad `q`.
    pub fn corner_of(&self, q: usize, i: u32) -> Option<usize> {
        self.quads[q].iter().position(|&v| v == i)
    }

    /// Whether edge `e` is used by one quad only.
    pub fn is_boundary_edge(&self, e: usize) -> bool {
        self.edge_quads[e].contains(&NO_QUAD)
    }

    /// Whether the net has boundary edges.
    pub fn is_open(&self) -> bool {
        self.edge_quads.iter().any(|q| q.contains(&NO_QUAD))
    }

    /// Per node: whether it lies on a boundary edge.
    pub fn boundary_nodes(&self) -> Vec<bool> {
        let mut b = vec![false; self.nodes.len()];
        for (e, ends) in self.edges.iter().enumerate() {
            if self.is_boundary_edge(e) {
                b[ends[0] as usize] = true;
                b[ends[1] as usize] = true;
            }
        }
        b
    }

    /// The quads of edge `e` (one for a boundary edge, else two).
    pub fn quads_of_edge(&self, e: usize) -> impl Iterator<Item = u32> + '_ {
        self.edge_quads[e].iter().copied().filter(|&q| q != NO_QUAD)
    }

    /// The boundary as closed loops of nodes, each walked with the net on its left seen from
    /// outside (the direction its quad walks the edge), in a deterministic order.
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        // Directed boundary edges a -> b as their quad walks them.
        let mut next = std::collections::BTreeMap::new();
        for (e, &[lo, hi]) in self.edges.iter().enumerate() {
            match self.edge_quads[e] {
                [q, NO_QUAD] if q != NO_QUAD => {
                    next.insert(lo, hi);
                }
                [NO_QUAD, q] if q != NO_QUAD => {
                    next.insert(hi, lo);
                }
                _ => {}
            }
        }
        let mut loops = Vec::new();
        let mut seen = std::collections::BTreeSet::new();
        for (&start, _) in next.iter() {
            if !seen.insert(start) {
                continue;
            }
            let mut lp = vec![start];
            let mut cur = start;
            while let Some(&nx) = next.get(&cur) {
                if nx == start || !seen.insert(nx) {
                    break;
                }
                lp.push(nx);
                cur = nx;
            }
            loops.push(lp);
        }
        loops
    }

    /// V - E + F; 2 per sphere-like component, 2 - 2g for genus g (minus one per boundary
    /// loop).
    pub fn euler_characteristic(&self) -> i64 {
        self.nodes.len() as i64 - self.edges.len() as i64 + self.quads.len() as i64
    }

    /// Connected components (by shared edges): component id per quad and the count.
    pub fn components(&self) -> (Vec<u32>, usize) {
        let mut comp = vec![u32::MAX; self.quads.len()];
        let mut count = 0u32;
        let mut stack = Vec::new();
        for start in 0..self.quads.len() {
            if comp[start] != u32::MAX {
                continue;
            }
            comp[start] = count;
            stack.push(start);
            while let Some(q) = stack.pop() {
                for &e in &self.quad_edges[q] {
                    for o in self.quads_of_edge(e as usize) {
                        if comp[o as usize] == u32::MAX {
                            comp[o as usize] = count;
                            stack.push(o as usize);
                        }
                    }
                }
            }
            count += 1;
        }
        (comp, count as usize)
    }

    /// Histogram of node valences: entry k counts nodes of valence k.
    pub fn valence_histogram(&self) -> Vec<usize> {
        let mut h = Vec::new();
        for i in 0..self.nodes.len() {
            let v = self.valence(i);
            if h.len() <= v {
                h.resize(v + 1, 0);
            }
            h[v] += 1;
        }
        h
    }
}

/// Node -> quads in cyclic order, checking that each node's quads form exactly one fan.
///
/// Around node v, quad q = [.., prev, v, next, ..] is followed (counter-clockwise seen from
/// outside) by the quad whose `next` is q's `prev`: walk that map from one quad and require
/// that it returns after visiting every incident quad. With `open`, a fan may also be one
/// chain: the walk starts at the quad no other quad is followed by and must visit all.
fn node_fans(n: usize, quads: &[[u32; 4]], open: bool) -> Result<(Vec<u32>, Vec<u32>)> {
    let mut count = vec![0u32; n + 1];
    for quad in quads {
        for &v in quad {
            count[v as usize + 1] += 1;
        }
    }
    for i in 0..n {
        if count[i + 1] == 0 {
            return Err(Error::Degenerate(format!("node {i} is used by no quad")));
        }
        count[i + 1] += count[i];
    }
    let offsets = count;
    let mut fill = offsets.clone();
    let mut list = vec![0u32; quads.len() * 4];
    for (q, quad) in quads.iter().enumerate() {
        for &v in quad {
            list[fill[v as usize] as usize] = q as u32;
            fill[v as usize] += 1;
        }
    }
    // Order each fan.
    let mut fan: Vec<(u32, u32, u32)> = Vec::new(); // (quad, prev, next)
    for v in 0..n {
        let (a, b) = (offsets[v] as usize, offsets[v + 1] as usize);
        fan.clear();
        for &q in &list[a..b] {
            let quad = quads[q as usize];
            let k = quad.iter().position(|&x| x as usize == v).unwrap_or(0);
            fan.push((q, quad[(k + 3) % 4], quad[(k + 1) % 4]));
        }
        let mut ordered = Vec::with_capacity(fan.len());
        let mut used = vec![false; fan.len()];
        // A chain starts at the quad that follows no other: no quad's `prev` is its `next`.
        let start = if open {
            (0..fan.len())
                .find(|&s| !fan.iter().any(|f| f.1 == fan[s].2))
                .unwrap_or(0)
        } else {
            0
        };
        let chain = open && !fan.iter().any(|f| f.1 == fan[start].2);
        let mut cur = start;
        for _ in 0..fan.len() {
            if used[cur] {
                break;
            }
            used[cur] = true;
            ordered.push(fan[cur].0);
            let want = fan[cur].1;
            match fan.iter().position(|f| f.2 == want) {
                Some(nx) => cur = nx,
                None => {
                    cur = usize::MAX;
                    break;
                }
            }
        }
        let ends_right = if chain {
            cur == usize::MAX
        } else {
            cur == start
        };
        if ordered.len() != fan.len() || !ends_right {
            return Err(Error::Degenerate(format!(
                "node {v}: its {} quads do not form a single fan (two sheets touch there)",
                fan.len()
            )));
        }
        list[a..b].copy_from_slice(&ordered);
    }
    Ok((offsets, list))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The six faces of the unit cube, outward.
    pub(crate) fn cube() -> (Vec<Point3<f64>>, Vec<[u32; 4]>) {
        let mut nodes = Vec::new();
        for k in 0..8u32 {
            nodes.push(Point3::new(
                (k & 1) as f64,
                ((k >> 1) & 1) as f64,
                ((k >> 2) & 1) as f64,
            ));
        }
        let quads = vec![
            [0, 2, 3, 1], // z = 0, normal -z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        (nodes, quads)
    }

    #[test]
    fn cube_is_a_closed_manifold() {
        let (nodes, quads) = cube();
        let net = QuadNet::new(nodes, quads).unwrap();
        assert_eq!(net.edges.len(), 12);
        assert_eq!(net.euler_characteristic(), 2);
        assert!((0..8).all(|i| net.valence(i) == 3));
        assert_eq!(net.components().1, 1);
        // Outward orientation: (b - a) x (d - a) points away from the centre.
        for q in &net.quads {
            let p: Vec<_> = q.iter().map(|&i| net.nodes[i as usize]).collect();
            let nrm = (p[1] - p[0]).cross(&(p[3] - p[0]));
            let c = (p[0].coords + p[2].coords) * 0.5 - nalgebra::Vector3::repeat(0.5);
            assert!(nrm.dot(&c) > 0.0);
        }
        // Side k of quad q is the edge quads[q][k] - quads[q][k+1].
        for (q, quad) in net.quads.iter().enumerate() {
            for k in 0..4 {
                let e = net.edges[net.quad_edges[q][k] as usize];
                let (a, b) = (quad[k], quad[(k + 1) % 4]);
                assert_eq!(e, [a.min(b), a.max(b)]);
            }
        }
    }

    #[test]
    fn open_flipped_and_pinched_nets_are_rejected() {
        let (nodes, mut quads) = cube();
        quads.pop();
        assert!(QuadNet::new(nodes.clone(), quads).is_err());
        let (_, mut quads) = cube();
        quads[0] = [0, 1, 3, 2];
        assert!(QuadNet::new(nodes.clone(), quads).is_err());
        // Two cubes sharing only node 7: a pinched vertex.
        let (_, quads) = cube();
        let mut nodes2 = nodes.clone();
        let mut quads2 = quads.clone();
        // Second cube shifted by (1, 1, 1): its node 0 is the first cube's node 7.
        for p in &nodes[1..] {
            nodes2.push(Point3::new(p.x + 1.0, p.y + 1.0, p.z + 1.0));
        }
        for q in &quads {
            quads2.push(q.map(|i| if i == 0 { 7 } else { i + 7 }));
        }
        let err = QuadNet::new(nodes2.clone(), quads2.clone())
            .unwrap_err()
            .to_string();
        assert!(err.contains("node 7"), "{err}");
        // Open nets reject the pinched vertex too.
        assert!(QuadNet::new_open(nodes2, quads2).is_err());
    }

    #[test]
    fn open_box_has_one_boundary_loop_and_chains_at_its_nodes() {
        let (nodes, mut quads) = cube();
        quads.remove(0); // no bottom (z = 0)
        let net = QuadNet::new_open(nodes, quads).unwrap();
        assert!(net.is_open());
        assert_eq!(net.edges.len(), 12);
        assert_eq!(net.euler_characteristic(), 1);
        let loops = net.boundary_loops();
        assert_eq!(loops.len(), 1);
        let mut lp = loops[0].clone();
        lp.sort_unstable();
        assert_eq!(lp, vec![0, 1, 2, 3]);
        // Walked with the net on the left: the side quad walks 0 -> 1 (quad [0, 1, 5, 4]).
        let i0 = loops[0].iter().position(|&v| v == 0).unwrap();
        assert_eq!(loops[0][(i0 + 1) % 4], 1);
        let b = net.boundary_nodes();
        assert_eq!(b, vec![true, true, true, true, false, false, false, false]);
        assert_eq!((0..12).filter(|&e| net.is_boundary_edge(e)).count(), 4);
        // A bottom node's two quads form a chain from one boundary quad to the other, each
        // following the previous counter-clockwise.
        for v in 0..4u32 {
            let fan = net.node_quads(v as usize);
            assert_eq!(fan.len(), 2);
            let prev_of = |q: u32| {
                let quad = net.quads[q as usize];
                let k = quad.iter().position(|&x| x == v).unwrap();
                (quad[(k + 3) % 4], quad[(k + 1) % 4])
            };
            assert_eq!(prev_of(fan[1]).1, prev_of(fan[0]).0);
        }
        assert_eq!(net.components().1, 1);
        // The closed constructor refuses it.
        assert!(QuadNet::new(net.nodes.clone(), net.quads.clone()).is_err());
    }
}
