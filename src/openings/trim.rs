//! The closed voxel net cut to the quads the data support (`--close open`).
//!
//! Input: a closed quad net and a per-quad *keep* flag (the support of [`super::decide`]).
//! The kept set is cleaned into a 2-manifold with boundary, in passes until nothing changes:
//! 1. *notches*: a dropped quad with three or four kept edge-neighbours is kept (a missing
//!    point under one node should not punch a hole or a one-quad bite into the rim);
//! 2. *spurs*: a kept quad with at most one kept edge-neighbour is dropped (a finger one quad
//!    wide has no interior and makes a poor patch strip);
//! 3. *pinches*: around every node the kept quads, in the node's fan (a cycle, or a chain at a
//!    node already on the boundary of an open input net), must form one run (the node then
//!    lies inside the net or on one boundary loop); where they form several (two pieces
//!    touching at a node), all runs but the longest are dropped.
//!
//! After 8 mixed passes only drops are made (spurs and pinches), which shrinks the kept set
//! monotonically and so ends. Components with fewer than [`MIN_COMPONENT_SHARE`] of the largest
//! one's quads are dropped: flakes of the implicit beside the data, not scanned surface.

use crate::polygonize::QuadNet;
use crate::{Error, Result};

/// Components smaller than this share of the largest are dropped.
pub const MIN_COMPONENT_SHARE: f64 = 0.05;
/// Passes that may add quads (notches) before only drops are made.
const MIXED_PASSES: usize = 8;

/// What the trimming did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct TrimReport {
    /// Quads of the closed net.
    pub quads_before: usize,
    /// Quads the data support.
    pub quads_supported: usize,
    /// Quads of the trimmed net.
    pub quads_kept: usize,
    pub notches_filled: usize,
    pub spurs_dropped: usize,
    pub pinch_quads_dropped: usize,
    /// Quads of components under [`MIN_COMPONENT_SHARE`] of the largest.
    pub small_component_quads_dropped: usize,
    pub components: usize,
    pub boundary_loops: usize,
}

/// Edge-neighbours of quad `q` in a closed net.
fn neighbours(net: &QuadNet, q: usize) -> impl Iterator<Item = usize> + '_ {
    net.quad_edges[q]
        .iter()
        .flat_map(move |&e| net.quads_of_edge(e as usize))
        .filter(move |&o| o as usize != q)
        .map(|o| o as usize)
}

/// Cuts `net` (closed, or open: [`super::rim`] cuts an open one again) to the quads flagged in
/// `keep`, cleaned as the module doc says.
/// Errors when nothing is left.
pub fn trim_to_data(net: &QuadNet, keep: &[bool]) -> Result<(QuadNet, TrimReport)> {
    let mut rep = TrimReport {
        quads_before: net.quads.len(),
        quads_supported: keep.iter().filter(|&&k| k).count(),
        ..Default::default()
    };
    let mut k = keep.to_vec();
    let on_boundary = net.boundary_nodes();
    let mut pass = 0;
    loop {
        pass += 1;
        let mut changed = false;
        let kept_nb = |k: &[bool], q: usize| neighbours(net, q).filter(|&o| k[o]).count();
        if pass <= MIXED_PASSES {
            let add: Vec<usize> = (0..k.len())
                .filter(|&q| !k[q] && kept_nb(&k, q) >= 3)
                .collect();
            rep.notches_filled += add.len();
            changed |= !add.is_empty();
            for q in add {
                k[q] = true;
            }
        }
        let drop: Vec<usize> = (0..k.len())
            .filter(|&q| k[q] && kept_nb(&k, q) <= 1)
            .collect();
        rep.spurs_dropped += drop.len();
        changed |= !drop.is_empty();
        for q in drop {
            k[q] = false;
        }
        for (v, &b) in on_boundary.iter().enumerate() {
            let dropped = drop_pinch(net.node_quads(v), !b, &mut k);
            rep.pinch_quads_dropped += dropped;
            changed |= dropped > 0;
        }
        if !changed {
            break;
        }
    }
    rep.small_component_quads_dropped = drop_small_components(net, &mut k);
    let kept: Vec<usize> = (0..k.len()).filter(|&q| k[q]).collect();
    if kept.is_empty() {
        return Err(Error::Degenerate(
            "no part of the implicit's surface lies near the input points (nothing to fit with \
             --close open)"
                .into(),
        ));
    }
    let mut index = vec![u32::MAX; net.nodes.len()];
    let mut nodes = Vec::new();
    let mut quads = Vec::with_capacity(kept.len());
    for &q in &kept {
        quads.push(net.quads[q].map(|v| {
            if index[v as usize] == u32::MAX {
                index[v as usize] = nodes.len() as u32;
                nodes.push(net.nodes[v as usize]);
            }
            index[v as usize]
        }));
    }
    let out = QuadNet::new_open(nodes, quads)?;
    rep.quads_kept = out.quads.len();
    rep.components = out.components().1;
    rep.boundary_loops = out.boundary_loops().len();
    Ok((out, rep))
}

/// Drops all runs but the longest (the first of equal ones) of kept quads in the `fan` of one
/// node (`cyclic`: its last quad is followed by its first); returns how many were dropped.
fn drop_pinch(fan: &[u32], cyclic: bool, k: &mut [bool]) -> usize {
    let n = fan.len();
    if n == 0 {
        return 0;
    }
    // Positions j = 1..=n along the fan. A cycle starts after a dropped quad so that no run
    // wraps around the start; a chain starts at its first quad.
    let start = if cyclic {
        match (0..n).find(|&i| !k[fan[i] as usize]) {
            Some(s) => s,
            None => return 0,
        }
    } else {
        n - 1
    };
    let pos = |j: usize| (start + j) % n;
    let on = |k: &[bool], j: usize| k[fan[pos(j)] as usize];
    let mut runs: Vec<(usize, usize)> = Vec::new(); // (first, length), positions from start + 1
    let mut i = 1;
    while i <= n {
        if on(k, i) {
            let first = i;
            while i <= n && on(k, i) {
                i += 1;
            }
            runs.push((first, i - first));
        } else {
            i += 1;
        }
    }
    if runs.len() < 2 {
        return 0;
    }
    let best = (0..runs.len())
        .max_by(|&a, &b| runs[a].1.cmp(&runs[b].1).then(b.cmp(&a)))
        .unwrap_or(0);
    let mut dropped = 0;
    for (r, &(first, len)) in runs.iter().enumerate() {
        if r == best {
            continue;
        }
        for j in first..first + len {
            k[fan[pos(j)] as usize] = false;
            dropped += 1;
        }
    }
    dropped
}

/// Drops the kept components under [`MIN_COMPONENT_SHARE`] of the largest; returns the quads
/// dropped.
fn drop_small_components(net: &QuadNet, k: &mut [bool]) -> usize {
    let mut comp = vec![usize::MAX; k.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for s in 0..k.len() {
        if !k[s] || comp[s] != usize::MAX {
            continue;
        }
        let c = sizes.len();
        let mut size = 0;
        comp[s] = c;
        stack.push(s);
        while let Some(q) = stack.pop() {
            size += 1;
            for o in neighbours(net, q) {
                if k[o] && comp[o] == usize::MAX {
                    comp[o] = c;
                    stack.push(o);
                }
            }
        }
        sizes.push(size);
    }
    let largest = sizes.iter().copied().max().unwrap_or(0) as f64;
    let mut dropped = 0;
    for q in 0..k.len() {
        if k[q] && (sizes[comp[q]] as f64) < MIN_COMPONENT_SHARE * largest {
            k[q] = false;
            dropped += 1;
        }
    }
    dropped
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::test_shapes::*;
    use crate::polygonize::voxel_net::{build_voxel_net, VoxelNetOptions};
    use nalgebra::Point3;

    fn sphere_net() -> QuadNet {
        let s = Sphere {
            c: Point3::new(0.01, -0.02, 0.015),
            r: 1.0,
        };
        let b = crate::mesh::Aabb {
            min: Point3::new(-1.2, -1.2, -1.2),
            max: Point3::new(1.2, 1.2, 1.2),
        };
        build_voxel_net(
            &s,
            &seeds_on(&s, s.c, 1.2, 10),
            &b,
            &VoxelNetOptions::new(0.2),
        )
        .unwrap()
        .net
    }

    #[test]
    fn upper_half_of_a_sphere_is_one_disc() {
        let net = sphere_net();
        let keep: Vec<bool> = net
            .quads
            .iter()
            .map(|q| q.iter().all(|&v| net.nodes[v as usize].z > -0.05))
            .collect();
        let (open, rep) = trim_to_data(&net, &keep).unwrap();
        assert!(open.is_open());
        assert_eq!(rep.components, 1);
        assert_eq!(rep.boundary_loops, 1);
        // A disc: V - E + F = 1.
        assert_eq!(open.euler_characteristic(), 1);
        assert!(rep.quads_kept > net.quads.len() / 3 && rep.quads_kept < net.quads.len() * 2 / 3);
        // Every node's fan is one run (QuadNet::new_open checked it); every node above the cut.
        assert!(open.nodes.iter().all(|p| p.z > -0.05 - 1e-12));
    }

    #[test]
    fn pinches_spurs_notches_and_flakes_are_cleaned() {
        let net = sphere_net();
        let mut keep: Vec<bool> = net
            .quads
            .iter()
            .map(|q| q.iter().all(|&v| net.nodes[v as usize].z > 0.0))
            .collect();
        // A notch: one interior quad dropped (all four neighbours kept).
        let inner = (0..keep.len())
            .find(|&q| keep[q] && neighbours(&net, q).all(|o| keep[o]))
            .unwrap();
        keep[inner] = false;
        // A flake: one far quad kept alone at the bottom.
        let flake = (0..keep.len())
            .find(|&q| net.quads[q].iter().all(|&v| net.nodes[v as usize].z < -0.9))
            .unwrap();
        keep[flake] = true;
        let (open, rep) = trim_to_data(&net, &keep).unwrap();
        assert!(rep.notches_filled >= 1);
        assert!(rep.spurs_dropped >= 1, "{rep:?}");
        assert_eq!(rep.components, 1);
        assert_eq!(rep.boundary_loops, 1);
        assert_eq!(open.euler_characteristic(), 1);
        // Nothing kept is an error; everything kept gives back the closed net.
        assert!(trim_to_data(&net, &vec![false; net.quads.len()]).is_err());
        let (all, r) = trim_to_data(&net, &vec![true; net.quads.len()]).unwrap();
        assert!(!all.is_open());
        assert_eq!(r.boundary_loops, 0);
        assert_eq!(all.quads.len(), net.quads.len());
    }

    #[test]
    fn two_pieces_touching_at_a_node_keep_the_longer_run() {
        // Fan of 6 quads around a node, kept: on off on on off off.
        let fan = [10u32, 11, 12, 13, 14, 15];
        let mut k = vec![false; 16];
        for q in [10, 12, 13] {
            k[q] = true;
        }
        assert_eq!(drop_pinch(&fan, true, &mut k), 1);
        assert!(!k[10] && k[12] && k[13]);
        // One run wrapping around the fan's start is one run.
        let mut k = vec![false; 16];
        for q in [10, 11, 15] {
            k[q] = true;
        }
        assert_eq!(drop_pinch(&fan, true, &mut k), 0);
        // In a chain (a boundary node) the two ends are two runs: the longer stays.
        assert_eq!(drop_pinch(&fan, false, &mut k), 1);
        assert!(k[10] && k[11] && !k[15]);
    }
}
