//! The sparse flood from the seeds and the support test that keeps the net components the
//! seeds describe ("Sparse flood" and "Support" in the module doc of [`super`]).

use super::{Builder, MIN_KEPT_NODES};
use crate::implicit::Implicit;
use crate::polygonize::quad_net::QuadNet;
use crate::{Error, Result};
use nalgebra::Point3;
use rayon::prelude::*;

impl<I: Implicit + ?Sized> Builder<'_, I> {
    /// Flood from the seeds; returns the sorted seed voxels.
    pub(super) fn flood(&mut self, seeds: &[Point3<f64>]) -> Result<Vec<u64>> {
        let grid = self.grid;
        let mut frontier: Vec<u64> = seeds.par_iter().filter_map(|p| grid.voxel_of(p)).collect();
        frontier.par_sort_unstable();
        frontier.dedup();
        let seed_voxels = frontier.clone();
        let mut any = false;
        while !frontier.is_empty() {
            self.eval_many(frontier.clone())?;
            let mut next = Vec::new();
            for &k in &frontier {
                let Some(v) = self.vox.get_mut(&k) else {
                    continue;
                };
                if !v.active || v.expanded {
                    continue;
                }
                v.expanded = true;
                any = true;
                for n in self.neighbours26(k) {
                    match self.vox.get(&n) {
                        Some(w) if w.expanded || !w.active => {}
                        _ => next.push(n),
                    }
                }
            }
            next.sort_unstable();
            next.dedup();
            frontier = next;
        }
        if !any {
            return Err(Error::Degenerate(
                "no seed point lies near the implicit surface (within 2.5 voxels)".into(),
            ));
        }
        Ok(seed_voxels)
    }

    /// Keeps the net components supported by the seeds (module doc). Nodes are still one per
    /// grid vertex here.
    /// Also returns the sorted inside voxels around the nodes of the dropped components that
    /// lie away from the data (support share under half the best; not the small pieces of a
    /// thin part, which are supported but too small to keep).
    pub(super) fn keep_supported(
        &mut self,
        net: QuadNet,
        seed_voxels: &[u64],
    ) -> Result<(QuadNet, Vec<u64>)> {
        let (comp, count) = net.components();
        if count == 0 {
            return Ok((net, Vec::new()));
        }
        let node_supported: Vec<bool> = self
            .node_vertex
            .par_iter()
            .map(|&v| {
                self.grid
                    .around_vertex(v)
                    .any(|k| seed_voxels.binary_search(&k).is_ok())
            })
            .collect();
        let mut node_comp = vec![0u32; net.nodes.len()];
        for (q, quad) in net.quads.iter().enumerate() {
            for &n in quad {
                node_comp[n as usize] = comp[q];
            }
        }
        let mut tally = vec![(0usize, 0usize); count];
        for (n, &c) in node_comp.iter().enumerate() {
            tally[c as usize].0 += 1;
            tally[c as usize].1 += node_supported[n] as usize;
        }
        let share: Vec<f64> = tally
            .iter()
            .map(|&(all, sup)| sup as f64 / all as f64)
            .collect();
        // The reference share: the best of the components large enough to keep (a single
        // voxel around the tip of a horn can be fully supported, but says nothing about the
        // surface's own share).
        let best_of = |min_nodes: usize| {
            share
                .iter()
                .zip(&tally)
                .filter(|(_, &(nodes, _))| nodes >= min_nodes)
                .fold(0.0f64, |a, (&b, _)| a.max(b))
        };
        let best = match best_of(MIN_KEPT_NODES) {
            b if b > 0.0 => b,
            _ => best_of(0),
        };
        // Dense seeds (a point cloud): the surface's own components are supported almost
        // everywhere. Sparse seeds (a few points per component): any support counts.
        let dense = best >= 0.5;
        let supported: Vec<bool> = share
            .iter()
            .zip(&tally)
            .map(|(&s, &(nodes, _))| {
                s > 0.0 && (!dense || (s >= 0.75 * best && nodes >= MIN_KEPT_NODES))
            })
            .collect();
        if supported.iter().all(|&s| s) {
            return Ok((net, Vec::new()));
        }
        if !supported.contains(&true) {
            return Err(Error::Degenerate(
                "no component of the quad net lies near the seed points: the implicit's zero \
                 set does not follow the input (an open sheet of points, such as one side of a \
                 part, can give an implicit that closes away from the data; `scansurf \
                 reconstruct` shows it)"
                    .into(),
            ));
        }
        self.stats.dropped_components = supported.iter().filter(|&&s| !s).count();
        let (grid, vox, node_vertex) = (self.grid, &self.vox, &self.node_vertex);
        let mut dropped: Vec<u64> = node_comp
            .iter()
            .enumerate()
            .filter(|(_, &c)| !supported[c as usize] && share[c as usize] < 0.5 * best)
            .flat_map(|(n, _)| grid.around_vertex(node_vertex[n]))
            .filter(|k| vox.get(k).is_some_and(|v| v.inside))
            .collect();
        dropped.sort_unstable();
        dropped.dedup();
        let kept: Vec<[u32; 4]> = net
            .quads
            .iter()
            .zip(&comp)
            .filter(|(_, &c)| supported[c as usize])
            .map(|(q, _)| *q)
            .collect();
        self.stats.dropped_quads = net.quads.len() - kept.len();
        let mut used = vec![u32::MAX; net.nodes.len()];
        let mut nodes = Vec::new();
        let mut vertex = Vec::new();
        let quads = kept
            .iter()
            .map(|q| {
                q.map(|n| {
                    if used[n as usize] == u32::MAX {
                        used[n as usize] = nodes.len() as u32;
                        nodes.push(net.nodes[n as usize]);
                        vertex.push(self.node_vertex[n as usize]);
                    }
                    used[n as usize]
                })
            })
            .collect();
        self.node_vertex = vertex;
        Ok((QuadNet::new(nodes, quads)?, dropped))
    }
}
