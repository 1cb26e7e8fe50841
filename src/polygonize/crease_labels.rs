//! The regions of the quad net's quads and the roles of its nodes (`fit --sharp`, steps 1
//! and 2 of [`super::crease_nodes`]).
//!
//! 1. **First labels.** Each quad takes the region of its centroid (the caller's `region`: of
//!    the regions near it, the one whose surface passes nearest). A quad whose label differs
//!    from at least three of its edge neighbours' common label takes theirs (label noise beside
//!    a crease), round after round until none changes (at most [`RELABEL_ROUNDS`]).
//! 2. **Least moves** ([`refine_by_moves`], when asked). Along a crease the voxel net has a
//!    strip of quads cutting across it, two corners on each side; at a corner one quad cuts
//!    across three faces. Whichever side such a quad joins, the corners on the other side
//!    become the crease's nodes, and the centroid's region does not choose consistently: at
//!    a concave corner of make_parts' block the corner-cutting quad joins the wall while the
//!    strip beside it joins the floor, so the crease path steps from the floor's nodes to the
//!    wall's at the corner and the placed corner folds a quad. Here the labels of the quads
//!    beside a crease are chosen instead to minimize
//!
//!    E = sum_i d_i^2 + h^2 * (steps),
//!
//!    d_i the distance node i moves for its role (a crease or corner node to its crease point
//!    or corner, `h` when it has none within reach; a face node to its region's surface), and
//!    steps the quads with three consecutive corners on one crease (a triangle once placed).
//!    It is iterated conditional modes (Besag 1986): each quad in turn takes, of its own and
//!    its edge neighbours' labels, the one of least E (its four nodes' terms and the steps of
//!    the quads around them), until no label changes (at most [`MOVE_ROUNDS`]).
//!
//! A node's role follows from the labels of its quads: one region a face node, two a crease
//! node, three or more a corner (the rank of dual contouring's quadric error function at the
//! node, Ju, Losasso, Schaefer and Warren 2002, read off the labels).

use super::quad_net::QuadNet;
use nalgebra::Point3;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};

/// Most rounds of the lone-label relabelling (step 1).
pub const RELABEL_ROUNDS: usize = 4;
/// Most rounds of the least-move relabelling (step 2).
pub const MOVE_ROUNDS: usize = 8;

/// What a node of the net is, by the regions of its quads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NodeRole {
    /// Inside one region.
    Face(u32),
    /// On the crease between two regions (lower first).
    Crease([u32; 2]),
    /// Where three regions meet (the three with the most quads at the node, sorted).
    Corner([u32; 3]),
}

impl NodeRole {
    /// The regions the node lies on.
    pub fn regions(&self) -> &[u32] {
        match self {
            NodeRole::Face(r) => std::slice::from_ref(r),
            NodeRole::Crease(s) => s,
            NodeRole::Corner(s) => s,
        }
    }
}

/// Step 1: the region of each quad's centroid, with lone labels replaced by their neighbours'.
/// Returns the labels and how many quads were relabelled.
pub fn quad_regions(
    net: &QuadNet,
    region: &(dyn Fn(&Point3<f64>) -> u32 + Sync),
) -> (Vec<u32>, usize) {
    let mut label: Vec<u32> = net
        .quads
        .par_iter()
        .map(|q| {
            let c = q
                .iter()
                .map(|&i| net.nodes[i as usize].coords)
                .sum::<nalgebra::Vector3<f64>>()
                * 0.25;
            region(&Point3::from(c))
        })
        .collect();
    let first = label.clone();
    for _ in 0..RELABEL_ROUNDS {
        let next: Vec<u32> = (0..net.quads.len())
            .map(|q| {
                let mut votes: BTreeMap<u32, usize> = BTreeMap::new();
                for o in edge_neighbours(net, q) {
                    *votes.entry(label[o]).or_default() += 1;
                }
                match votes.iter().max_by_key(|(_, &n)| n) {
                    Some((&r, &n)) if n >= 3 && r != label[q] => r,
                    _ => label[q],
                }
            })
            .collect();
        if next == label {
            break;
        }
        label = next;
    }
    let changed = label.iter().zip(&first).filter(|(a, b)| a != b).count();
    (label, changed)
}

/// The quads sharing an edge with quad `q`.
fn edge_neighbours(net: &QuadNet, q: usize) -> impl Iterator<Item = usize> + '_ {
    net.quad_edges[q].iter().flat_map(move |&e| {
        net.quads_of_edge(e as usize)
            .map(|o| o as usize)
            .filter(move |&o| o != q)
    })
}

/// The role of node `i` by the regions of its quads.
pub fn node_role(net: &QuadNet, quad_region: &[u32], i: usize) -> NodeRole {
    role_with(net, quad_region, i, None)
}

/// [`node_role`] with quad `over.0` labelled `over.1`.
fn role_with(net: &QuadNet, quad_region: &[u32], i: usize, over: Option<(usize, u32)>) -> NodeRole {
    role_of(net.node_quads(i).iter().map(|&q| match over {
        Some((o, r)) if o == q as usize => r,
        _ => quad_region[q as usize],
    }))
}

/// The role of a node whose quads carry `regions` (one entry per quad): one region a face,
/// two a crease, three or more a corner of the three with the most quads (ties by region).
pub fn role_of(regions: impl IntoIterator<Item = u32>) -> NodeRole {
    let mut n: BTreeMap<u32, usize> = BTreeMap::new();
    for r in regions {
        *n.entry(r).or_default() += 1;
    }
    let mut by_count: Vec<(u32, usize)> = n.into_iter().collect();
    // Most quads first, ties by region.
    by_count.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    match by_count.len() {
        0 => NodeRole::Face(u32::MAX),
        1 => NodeRole::Face(by_count[0].0),
        2 => {
            let (a, b) = (by_count[0].0, by_count[1].0);
            NodeRole::Crease([a.min(b), a.max(b)])
        }
        _ => {
            let mut s = [by_count[0].0, by_count[1].0, by_count[2].0];
            s.sort_unstable();
            NodeRole::Corner(s)
        }
    }
}

/// Every node's role.
pub fn node_roles(net: &QuadNet, quad_region: &[u32]) -> Vec<NodeRole> {
    (0..net.nodes.len())
        .map(|i| node_role(net, quad_region, i))
        .collect()
}

/// The distances of step 2's energy.
pub trait MoveCost: Sync {
    /// How far a node at `p` moves for `role`, or `None` when it has no place within reach
    /// (a crease or corner node whose sides do not meet near it).
    fn distance(&self, p: &Point3<f64>, role: &NodeRole) -> Option<f64>;
}

/// Step 2: the labels of the quads beside a crease chosen for the least node moves and steps
/// (module doc). Returns how many quads changed label.
pub fn refine_by_moves(
    net: &QuadNet,
    quad_region: &mut [u32],
    cost: &dyn MoveCost,
    h: f64,
) -> usize {
    let first = quad_region.to_vec();
    let node_cost = |i: usize, role: &NodeRole| -> f64 {
        let d = cost.distance(&net.nodes[i], role).unwrap_or(h);
        d * d
    };
    // The other labels quad q may take.
    let candidates = |q: usize, quad_region: &[u32]| -> Vec<u32> {
        let mut c: Vec<u32> = edge_neighbours(net, q)
            .map(|o| quad_region[o])
            .filter(|&r| r != quad_region[q])
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    };
    let mut cache: HashMap<(usize, NodeRole), f64> = HashMap::new();
    for _ in 0..MOVE_ROUNDS {
        // The node costs the round's evaluations ask for with the labels as they are, computed
        // in parallel (the fits to the data are the work); the few that labels changed earlier
        // in the round call for are computed as they come.
        let mut wanted: Vec<(usize, NodeRole)> = (0..net.quads.len())
            .into_par_iter()
            .flat_map_iter(|q| {
                let mut out = Vec::new();
                let labels = candidates(q, quad_region);
                if !labels.is_empty() {
                    for label in std::iter::once(quad_region[q]).chain(labels) {
                        for &i in &net.quads[q] {
                            let i = i as usize;
                            out.push((i, role_with(net, quad_region, i, Some((q, label)))));
                        }
                    }
                }
                out
            })
            .filter(|k| !cache.contains_key(k))
            .collect();
        wanted.sort_unstable();
        wanted.dedup();
        let fresh: Vec<((usize, NodeRole), f64)> = wanted
            .into_par_iter()
            .map(|(i, r)| ((i, r), node_cost(i, &r)))
            .collect();
        cache.extend(fresh);
        let mut changed = false;
        for q in 0..net.quads.len() {
            let labels = candidates(q, quad_region);
            if labels.is_empty() {
                continue;
            }
            let own = quad_region[q];
            let mut energy = |label: u32, quad_region: &mut [u32]| -> f64 {
                quad_region[q] = label;
                let corners = net.quads[q];
                let mut e = 0.0;
                for &i in &corners {
                    let i = i as usize;
                    let role = node_role(net, quad_region, i);
                    e += *cache
                        .entry((i, role))
                        .or_insert_with(|| node_cost(i, &role));
                }
                let mut around: Vec<u32> = corners
                    .iter()
                    .flat_map(|&i| net.node_quads(i as usize).iter().copied())
                    .collect();
                around.sort_unstable();
                around.dedup();
                let steps = around
                    .iter()
                    .filter(|&&o| is_step(net, quad_region, o as usize))
                    .count();
                e + h * h * steps as f64
            };
            let mut best = (energy(own, quad_region), own);
            for &r in &labels {
                let e = energy(r, quad_region);
                // Strictly less, so that the labels settle.
                if e < best.0 - 1e-12 * h * h {
                    best = (e, r);
                }
            }
            quad_region[q] = best.1;
            changed |= best.1 != own;
        }
        if !changed {
            break;
        }
    }
    quad_region
        .iter()
        .zip(&first)
        .filter(|(a, b)| a != b)
        .count()
}

/// Whether quad `q` has three consecutive corners on one crease of its region: the corners'
/// roles all hold the quad's region and one same other region.
pub fn is_step(net: &QuadNet, quad_region: &[u32], q: usize) -> bool {
    let r = quad_region[q];
    let quad = net.quads[q];
    let roles: Vec<NodeRole> = quad
        .iter()
        .map(|&i| node_role(net, quad_region, i as usize))
        .collect();
    (0..4).any(|k| {
        let (a, b, c) = (&roles[(k + 3) % 4], &roles[k], &roles[(k + 1) % 4]);
        if matches!(b, NodeRole::Face(_)) || !b.regions().contains(&r) {
            return false;
        }
        b.regions().iter().any(|&s| {
            s != r
                && [a, c]
                    .iter()
                    .all(|x| x.regions().contains(&r) && x.regions().contains(&s))
        })
    })
}
