//! Ribbons (quad strips) of a quad net: the classes of edges under "opposite sides of a quad".
//!
//! A tensor-product patch has one sample count per parameter direction, so the two opposite
//! sides of a quad carry the same count; a shared edge carries one count for both of its
//! quads. Chaining these constraints, every edge of a ribbon (the strip of quads crossed by a
//! dual loop, which closes on a closed net and may cross itself) gets the same count. The
//! classes are found with a union-find over edges: for each quad, union(side 0, side 2) and
//! union(side 1, side 3).

use crate::polygonize::QuadNet;

/// Ribbon membership of every edge and quad.
#[derive(Debug, Clone, PartialEq)]
pub struct Ribbons {
    /// Ribbon of each net edge (0..count), numbered in order of first appearance in the edge
    /// list, so deterministic.
    pub of_edge: Vec<u32>,
    /// Per quad: [ribbon of sides 0 and 2 (the u direction), ribbon of sides 1 and 3 (v)].
    pub of_quad: Vec<[u32; 2]>,
    /// Number of ribbons.
    pub count: usize,
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[i as usize];
        parent[i as usize] = parent[p as usize];
        i = p;
    }
    i
}

/// The ribbons of `net`.
pub fn ribbons(net: &QuadNet) -> Ribbons {
    let mut parent: Vec<u32> = (0..net.edges.len() as u32).collect();
    for qe in &net.quad_edges {
        for (a, b) in [(qe[0], qe[2]), (qe[1], qe[3])] {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    let mut id = vec![u32::MAX; net.edges.len()];
    let mut of_edge = vec![0u32; net.edges.len()];
    let mut count = 0u32;
    for (e, rib) in of_edge.iter_mut().enumerate() {
        let r = find(&mut parent, e as u32) as usize;
        if id[r] == u32::MAX {
            id[r] = count;
            count += 1;
        }
        *rib = id[r];
    }
    let of_quad = net
        .quad_edges
        .iter()
        .map(|qe| [of_edge[qe[0] as usize], of_edge[qe[1] as usize]])
        .collect();
    Ribbons {
        of_edge,
        of_quad,
        count: count as usize,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::quad_net::tests::cube;

    #[test]
    fn cube_has_three_ribbons_of_four_edges() {
        let (nodes, quads) = cube();
        let net = QuadNet::new(nodes, quads).unwrap();
        let r = ribbons(&net);
        assert_eq!(r.count, 3);
        for k in 0..3u32 {
            assert_eq!(r.of_edge.iter().filter(|&&x| x == k).count(), 4);
        }
        // Parallel edges share a ribbon: the direction of each ribbon's edges is one axis.
        for (e, &rb) in net.edges.iter().zip(&r.of_edge) {
            let d = net.nodes[e[1] as usize] - net.nodes[e[0] as usize];
            for (f, &rc) in net.edges.iter().zip(&r.of_edge) {
                let d2 = net.nodes[f[1] as usize] - net.nodes[f[0] as usize];
                assert_eq!(rb == rc, d.cross(&d2).norm() < 1e-12);
            }
        }
        for (q, qe) in net.quad_edges.iter().enumerate() {
            assert_eq!(r.of_edge[qe[0] as usize], r.of_edge[qe[2] as usize]);
            assert_eq!(r.of_quad[q][1], r.of_edge[qe[3] as usize]);
        }
    }
}
