//! Sub-voxel sheets and gaps, and the medial voxels of parts thinner than a voxel that the
//! first net misses ("Sub-voxel features" and "Parts the net misses" in the module doc of
//! [`super`]).

use super::{
    add, axis, leaves_side, Builder, Grid, Idx, Vox, LIPSCHITZ, MISSED, PATH_DEPTH, REACH,
};
use crate::implicit::Implicit;
use crate::polygonize::quad_net::QuadNet;
use crate::spatial::KdTree;
use crate::Result;
use nalgebra::Point3;
use rayon::prelude::*;

impl<I: Implicit + ?Sized> Builder<'_, I> {
    /// Sub-voxel sheets and gaps between face-adjacent voxels of the same class (module doc).
    pub(super) fn thin_features(&mut self) {
        let mut keys: Vec<u64> = self
            .vox
            .iter()
            .filter(|(_, v)| v.expanded)
            .map(|(&k, _)| k)
            .collect();
        keys.sort_unstable();
        let mut pairs = Vec::new();
        for &k in &keys {
            let i = Grid::unkey(k);
            for a in 0..3 {
                if let Some(n) = self.grid.key(add(i, axis(a))) {
                    if let (Some(u), Some(w)) = (self.vox.get(&k), self.vox.get(&n)) {
                        if u.inside == w.inside && u.active && w.active {
                            pairs.push((k, n, a, *u, *w));
                        }
                    }
                }
            }
        }
        let (f, grid) = (self.f, self.grid);
        let mut flips: Vec<(u64, Point3<f64>, f64)> = pairs
            .par_iter()
            .filter_map(|&(k, n, a, u, w)| thin_pair(f, &grid, k, n, a, &u, &w))
            .collect();
        flips.sort_unstable_by_key(|x| x.0);
        flips.dedup_by_key(|x| x.0);
        for (k, x, fx) in flips {
            if let Some(v) = self.vox.get_mut(&k) {
                v.inside = !v.inside;
                v.rep = x;
                v.frep = fx;
                self.stats.thin_flips += 1;
            }
        }
    }

    /// Thin parts (module doc): from each seed (one per cell of h/3), step into the material
    /// along -grad f in steps of h/8; when f turns positive again within h, the part is
    /// thinner than a voxel there and the point halfway across is a medial point. Its voxel
    /// is set inside and protected: the repair joins it to its diagonal neighbours instead of
    /// removing it, so a horn passing between the voxel centres becomes a face-connected
    /// string of voxels attached to the body.
    pub(super) fn medial_voxels(
        &mut self,
        seeds: &[Point3<f64>],
        net: &QuadNet,
        dropped: &[u64],
    ) -> Result<usize> {
        let (f, grid) = (self.f, self.grid);
        let h = grid.h;
        let cell = h / 3.0;
        let mut picked: Vec<([i64; 3], usize)> = seeds
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let r = (p - grid.origin) / cell;
                r.iter().all(|v| v.is_finite() && v.abs() < 1e15).then(|| {
                    (
                        [r.x.floor() as i64, r.y.floor() as i64, r.z.floor() as i64],
                        i,
                    )
                })
            })
            .collect();
        picked.sort_unstable();
        picked.dedup_by_key(|x| x.0);
        // Only where the net misses the data: seeds farther than MISSED h from every node
        // (a node of a represented surface is within about 0.75 h of its seeds), and the
        // seeds within REACH h of those, so that the string of voxels reaches the body.
        if net.nodes.is_empty() {
            return Ok(0);
        }
        let nodes = KdTree::build(&net.nodes)?;
        let missed: Vec<Point3<f64>> = picked
            .par_iter()
            .map(|x| seeds[x.1])
            .filter(|p| nodes.nearest(p).1 > MISSED * h)
            .collect();
        if missed.is_empty() {
            return Ok(0);
        }
        let missed = KdTree::build(&missed)?;
        picked.retain(|x| missed.nearest(&seeds[x.1]).1 <= REACH * h);
        let step = h / 8.0;
        let mut found: Vec<(u64, Point3<f64>, f64)> = picked
            .par_iter()
            .filter_map(|&(_, i)| {
                let q = seeds[i];
                let (v, g) = f.value_and_gradient(&q);
                let gn = g.norm();
                if !(v.is_finite() && gn > 0.0 && gn.is_finite()) {
                    return None;
                }
                let n = g / gn;
                let foot = q - n * (v / gn);
                if (foot - q).norm() > 0.5 * h {
                    return None;
                }
                let mut seen_inside = false;
                let mut exit = None;
                for k in 1..=8 {
                    let t = k as f64 * step;
                    let fx = f.value(&(foot - n * t));
                    if !fx.is_finite() {
                        return None;
                    }
                    if fx < 0.0 {
                        seen_inside = true;
                    } else if seen_inside {
                        exit = Some(t);
                        break;
                    }
                }
                let m = foot - n * (0.5 * (exit? - 0.5 * step));
                let fm = f.value(&m);
                (fm < 0.0).then_some((grid.voxel_of(&m)?, m, fm))
            })
            .collect();
        found.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.2.total_cmp(&b.2)));
        found.dedup_by_key(|x| x.0);
        // Not next to a component the support test dropped (a sheet of the implicit away from
        // the data, which a medial voxel would otherwise join to the surface).
        found.retain(|x| {
            !grid
                .block27(Grid::unkey(x.0))
                .any(|k| dropped.binary_search(&k).is_ok())
        });
        self.eval_many(found.iter().map(|x| x.0).collect())?;
        for &(k, m, fm) in &found {
            self.medial.push(k);
            self.stats.medial_voxels += 1;
            if let Some(v) = self.vox.get_mut(&k) {
                if !v.inside {
                    v.inside = true;
                    v.rep = m;
                    v.frep = fm;
                    self.stats.medial_flips += 1;
                }
            }
            self.expand(k)?;
        }
        Ok(self.stats.medial_flips)
    }

    fn is_medial(&self, i: Idx) -> bool {
        self.grid
            .key(i)
            .is_some_and(|k| self.medial.binary_search(&k).is_ok())
    }

    /// A seed lies in the voxel or one of its 26 neighbours.
    fn near_seeds(&self, i: Idx) -> bool {
        self.grid
            .block27(i)
            .any(|k| self.seed_voxels.binary_search(&k).is_ok())
    }

    /// Two inside voxels touching along an edge or at a vertex are joined without the path test
    /// when one holds a medial point of a thin part and both are next to the data (not a sheet
    /// the implicit has away from the points).
    pub(super) fn medial_pair(&self, pair: &[Idx; 2]) -> bool {
        pair.iter().any(|&i| self.is_medial(i)) && pair.iter().all(|&i| self.near_seeds(i))
    }
}

/// Sub-voxel feature test for face-adjacent voxels `k` (lower) and `n` = k + e_a of the same
/// class: when both gradients point at a crossing predicted within the pair, the segment between
/// the centres is searched for the other sign. Returns the voxel to flip (the one with the
/// smaller |f|) and the point of the other sign found.
fn thin_pair<I: Implicit + ?Sized>(
    f: &I,
    grid: &Grid,
    k: u64,
    n: u64,
    a: usize,
    u: &Vox,
    w: &Vox,
) -> Option<(u64, Point3<f64>, f64)> {
    let h = grid.h;
    // sgn * f > 0 on the voxels' side; look for sgn * f <= 0 between them.
    let sgn = if u.inside { -1.0 } else { 1.0 };
    let (fu, fw) = (sgn * u.f, sgn * w.f);
    let (du, dw) = (sgn * u.g[a], -sgn * w.g[a]);
    if !(du < 0.0 && dw < 0.0 && fu.is_finite() && fw.is_finite()) {
        return None;
    }
    let (su, sw) = (fu / -du, fw / -dw);
    if !(su < h && sw < h && su + sw < 1.25 * h) {
        return None;
    }
    let (cu, cw) = (grid.centre(Grid::unkey(k)), grid.centre(Grid::unkey(n)));
    let lip = LIPSCHITZ * u.g.norm().max(w.g.norm());
    let (x, fx) = leaves_side(f, cu, u.f, cw, w.f, sgn, lip, PATH_DEPTH)?;
    Some((if fu <= fw { k } else { n }, x, fx))
}
