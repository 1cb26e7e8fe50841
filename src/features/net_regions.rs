//! The quads of a patch network labelled by smooth region, and the net edges and nodes that lie
//! between regions (`fit --features`; issue 36 item 3, for the crease-aligned net and the G0
//! patches that follow).
//!
//! - **Quad region**: the majority label of the [`VOTERS`] labelled input points nearest to the
//!   patch's centre S(u_mid, v_mid) (the segmentation's labels, [`super::detect::Features`]);
//!   unlabelled when none of them has a label.
//! - **Crease edge**: a net edge whose two quads carry different regions.
//! - **Crease node** / **corner node**: a node whose quads carry two / three or more regions.
//! - **Staircase quad**: a quad of region r with three or four corners that are crease nodes
//!   between r and one same other region s. On today's voxel net a crease that is not along a
//!   grid axis runs through such quads (the net's edges step around it); the crease-aligned
//!   net of issue 36 must have none.

use super::detect::{Features, UNLABELLED};
use crate::nurbs::PatchNetwork;
use crate::spatial::KdTree;
use nalgebra::Point3;
use std::collections::{BTreeSet, HashMap};

/// Labelled points consulted per quad.
pub const VOTERS: usize = 8;

/// Region of a quad no labelled point near it decided: the segmentation's own label of a
/// point no region took.
pub const NO_REGION: u32 = UNLABELLED;

/// The labels and what they show (the report's `net_regions`).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct NetRegions {
    /// Region of each quad (patch), in the network's face order; [`NO_REGION`] for none.
    #[serde(skip)]
    pub quad_region: Vec<u32>,
    /// Net edges between quads of two regions, as node pairs (lower index first), sorted.
    #[serde(skip)]
    pub crease_edges: Vec<[u32; 2]>,
    /// Regions that label at least one quad.
    pub regions: usize,
    /// Quads per region (indexed by the segmentation's region number).
    pub quads_per_region: Vec<usize>,
    pub unlabelled_quads: usize,
    pub crease_edges_count: usize,
    pub crease_nodes: usize,
    pub corner_nodes: usize,
    pub staircase_quads: usize,
}

/// Labels the quads of `network` (their corner nodes as [`PatchNetwork::quads`] gives them)
/// by the regions of `features`.
pub fn label_network(network: &PatchNetwork, features: &Features) -> NetRegions {
    let labelled: Vec<(Point3<f64>, u32)> = features
        .points
        .iter()
        .zip(&features.label)
        .filter(|(_, &l)| l != UNLABELLED)
        .map(|(p, &l)| (*p, l))
        .collect();
    let points: Vec<Point3<f64>> = labelled.iter().map(|x| x.0).collect();
    let tree = KdTree::build(&points).ok();
    let quad_region: Vec<u32> = network
        .faces
        .iter()
        .map(|f| {
            let Some(tree) = &tree else {
                return NO_REGION;
            };
            let (u0, u1) = f.surface.domain_u();
            let (v0, v1) = f.surface.domain_v();
            let c = f.surface.evaluate(0.5 * (u0 + u1), 0.5 * (v0 + v1));
            majority(tree.knn(&c, VOTERS).iter().map(|&(i, _)| labelled[i].1))
        })
        .collect();
    from_labels(&network.quads(), quad_region, features.regions)
}

/// The most frequent of `labels` (the smallest on a tie); [`NO_REGION`] for none.
fn majority(labels: impl Iterator<Item = u32>) -> u32 {
    let mut count: HashMap<u32, usize> = HashMap::new();
    for l in labels {
        *count.entry(l).or_default() += 1;
    }
    count
        .into_iter()
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
        .map_or(NO_REGION, |(l, _)| l)
}

/// The crease edges, nodes and staircase quads of quads labelled `quad_region` (`regions`:
/// the segmentation's region count).
pub fn from_labels(quads: &[[u32; 4]], quad_region: Vec<u32>, regions: usize) -> NetRegions {
    // Quads of each undirected edge, regions of each node.
    let mut edge_quads: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    let mut node_regions: HashMap<u32, BTreeSet<u32>> = HashMap::new();
    for (q, quad) in quads.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (quad[k], quad[(k + 1) % 4]);
            edge_quads.entry([a.min(b), a.max(b)]).or_default().push(q);
            if quad_region[q] != NO_REGION {
                node_regions.entry(a).or_default().insert(quad_region[q]);
            }
        }
    }
    let mut crease_edges: Vec<[u32; 2]> = edge_quads
        .iter()
        .filter(|(_, qs)| {
            qs.len() == 2 && {
                let (a, b) = (quad_region[qs[0]], quad_region[qs[1]]);
                a != b && a != NO_REGION && b != NO_REGION
            }
        })
        .map(|(e, _)| *e)
        .collect();
    crease_edges.sort_unstable();
    let crease_nodes = node_regions.values().filter(|s| s.len() == 2).count();
    let corner_nodes = node_regions.values().filter(|s| s.len() >= 3).count();
    let staircase_quads = quads
        .iter()
        .zip(&quad_region)
        .filter(|(quad, &r)| {
            r != NO_REGION && {
                // Other regions met at the crease nodes among the corners.
                let mut others: HashMap<u32, usize> = HashMap::new();
                for v in quad.iter() {
                    let Some(s) = node_regions.get(v).filter(|s| s.len() == 2) else {
                        continue;
                    };
                    if let Some(&o) = s.iter().find(|&&o| o != r) {
                        *others.entry(o).or_default() += 1;
                    }
                }
                others.values().any(|&n| n >= 3)
            }
        })
        .count();
    let mut quads_per_region = vec![0usize; regions];
    let mut unlabelled_quads = 0;
    for &r in &quad_region {
        match quads_per_region.get_mut(r as usize) {
            Some(n) => *n += 1,
            None => unlabelled_quads += 1,
        }
    }
    NetRegions {
        regions: quads_per_region.iter().filter(|&&n| n > 0).count(),
        quads_per_region,
        unlabelled_quads,
        crease_edges_count: crease_edges.len(),
        crease_nodes,
        corner_nodes,
        staircase_quads,
        quad_region,
        crease_edges,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 x 2 grid of quads (nodes 0..12, row-major 4 x 3), regions split between columns.
    fn grid() -> Vec<[u32; 4]> {
        let mut q = Vec::new();
        for j in 0..2u32 {
            for i in 0..3u32 {
                let a = j * 4 + i;
                q.push([a, a + 1, a + 5, a + 4]);
            }
        }
        q
    }

    #[test]
    fn a_straight_crease_between_two_columns() {
        // Columns 0 and 1 region 0, column 2 region 1: the crease runs along node column 2.
        let r = from_labels(&grid(), vec![0, 0, 1, 0, 0, 1], 2);
        assert_eq!(r.quads_per_region, vec![4, 2]);
        assert_eq!(r.crease_edges, vec![[2, 6], [6, 10]]);
        assert_eq!(r.crease_nodes, 3);
        assert_eq!(r.corner_nodes, 0);
        assert_eq!(r.staircase_quads, 0);
    }

    #[test]
    fn a_stepped_crease_makes_staircase_quads_and_three_regions_a_corner() {
        // Region 1 takes the last quad of row 0 and the last two of row 1: the crease steps.
        let r = from_labels(&grid(), vec![0, 0, 1, 0, 1, 1], 2);
        assert_eq!(r.crease_edges_count, 3);
        // Quad 1 (region 0) has corners 1, 2, 5, 6: 2, 5 and 6 are on the crease with region 1.
        assert!(r.staircase_quads >= 1, "{r:?}");
        let three = from_labels(&grid(), vec![0, 0, 1, 2, 2, 1], 3);
        assert!(three.corner_nodes >= 1, "{three:?}");
        assert_eq!(three.regions, 3);
    }

    #[test]
    fn unlabelled_quads_make_no_crease() {
        let r = from_labels(&grid(), vec![0, NO_REGION, 1, 0, 0, 1], 2);
        assert_eq!(r.unlabelled_quads, 1);
        assert!(r.crease_edges.iter().all(|e| *e != [1, 5] && *e != [2, 6]));
        assert_eq!(majority([3, 1, 3, 1].into_iter()), 1);
        assert_eq!(majority(std::iter::empty()), NO_REGION);
    }
}
