//! Voxel size h for a target number of patches (`fit --patches N`).
//!
//! The quad count of a voxel net scales like F(h) ~ c A / h^2 (A the surface area, c about 1.5
//! for the staircase of a curved surface). Starting from h0 = diagonal / 20 (a cheap coarse net),
//! each step solves ln F = ln N on the secant through the last two (ln h, ln F) samples (slope
//! clamped to [-3, -1]; -2 after the first sample), until F is within `aim` of N. Every step is a
//! full [`build_voxel_net`], cheap because only near-surface voxels are visited. F(h) is a step
//! function with a little noise from the grid's offset (coarse nets of thin shapes jump by 20 %
//! between neighbouring h), so the iteration also stops at the 15 % bar after four nets, and the
//! net closest to N among those built is returned; [`PatchCountReport`] says whether it met the
//! 15 % bar.

use super::voxel_net::{build_voxel_net, VoxelNet, VoxelNetOptions};
use crate::implicit::Implicit;
use crate::mesh::Aabb;
use crate::{Error, Result};
use nalgebra::Point3;

/// How h was found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PatchCountReport {
    pub target: usize,
    /// (h, quad count) of every net built, in order.
    pub tries: Vec<(f64, usize)>,
    /// |F - N| / N of the returned net.
    pub relative_error: f64,
    /// True when within 15 % of the target.
    pub within_15_percent: bool,
}

/// Builds the voxel net whose quad count is closest to `target`, within `aim` (relative) if the
/// iteration gets there in `max_builds` nets. Errors: target 0, non-finite bounds, and whatever
/// [`build_voxel_net`] reports.
pub fn net_for_patch_count<I: Implicit + ?Sized>(
    f: &I,
    seeds: &[Point3<f64>],
    bounds: &Aabb,
    target: usize,
) -> Result<(VoxelNet, PatchCountReport)> {
    net_for_patch_count_by(f, seeds, bounds, target, &|v: &VoxelNet| v.net.quads.len())
}

/// [`net_for_patch_count`] with the patches a net will give counted by `count` (e.g. the
/// quads left after cutting the net to the data, `fit --close open`).
pub fn net_for_patch_count_by<I: Implicit + ?Sized>(
    f: &I,
    seeds: &[Point3<f64>],
    bounds: &Aabb,
    target: usize,
    count: &dyn Fn(&VoxelNet) -> usize,
) -> Result<(VoxelNet, PatchCountReport)> {
    const AIM: f64 = 0.05;
    const MAX_BUILDS: usize = 10;
    if target == 0 {
        return Err(Error::InvalidOption(
            "the number of patches must be positive".into(),
        ));
    }
    let diag = bounds.diagonal();
    if !(diag.is_finite() && diag > 0.0) {
        return Err(Error::Degenerate(
            "bounding box is empty or not finite".into(),
        ));
    }
    let n = target as f64;
    let mut h = diag / 20.0;
    let mut tries: Vec<(f64, usize)> = Vec::new();
    let mut best: Option<(f64, VoxelNet)> = None;
    for _ in 0..MAX_BUILDS {
        let v = build_voxel_net(f, seeds, bounds, &VoxelNetOptions::new(h))?;
        let count = count(&v).max(1);
        tries.push((h, count));
        let err = (count as f64 - n).abs() / n;
        if best.as_ref().is_none_or(|(e, _)| err < *e) {
            best = Some((err, v));
        }
        // Close enough, or within the 15 % bar once a few nets have shown how noisy F(h) is.
        if err <= AIM || (err <= 0.15 && tries.len() >= 4) {
            break;
        }
        let slope = match tries.len() {
            0 | 1 => -2.0,
            k => {
                let (h0, f0) = tries[k - 2];
                let (h1, f1) = tries[k - 1];
                let m = ((f1 as f64).ln() - (f0 as f64).ln()) / (h1.ln() - h0.ln());
                if m.is_finite() {
                    m.clamp(-3.0, -1.0)
                } else {
                    -2.0
                }
            }
        };
        let next = h * ((n.ln() - (count as f64).ln()) / slope).exp();
        // Never step by more than 4x at once, and avoid re-trying the same h.
        h = next.clamp(0.25 * h, 4.0 * h);
        if tries.iter().any(|(t, _)| ((t - h) / h).abs() < 1e-6) {
            h *= 1.01;
        }
    }
    let Some((err, v)) = best else {
        return Err(Error::Numerical("no voxel net was built".into()));
    };
    Ok((
        v,
        PatchCountReport {
            target,
            tries,
            relative_error: err,
            within_15_percent: err <= 0.15,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::super::test_shapes::*;
    use super::*;

    #[test]
    fn sphere_and_torus_hit_the_target() {
        let s = Sphere {
            c: Point3::new(0.03, 0.0, -0.02),
            r: 1.0,
        };
        let sb = aabb([-1.0; 3], [1.0; 3]);
        let ss = seeds_on(&s, s.c, 1.2, 20);
        let t = Torus {
            big: 1.0,
            small: 0.3,
        };
        let tb = aabb([-1.3, -1.3, -0.3], [1.3, 1.3, 0.3]);
        let ts = seeds_on(&t, Point3::origin(), 1.4, 60);
        for target in [300, 1500] {
            let (v, r) = net_for_patch_count(&s, &ss, &sb, target).unwrap();
            eprintln!("sphere N={target}: {:?}", r.tries);
            assert!(r.within_15_percent);
            assert!((v.net.quads.len() as f64 - target as f64).abs() <= 0.15 * target as f64);
            let (v, r) = net_for_patch_count(&t, &ts, &tb, target).unwrap();
            eprintln!("torus N={target}: {:?}", r.tries);
            assert!(r.within_15_percent);
            assert!((v.net.quads.len() as f64 - target as f64).abs() <= 0.15 * target as f64);
            assert_eq!(v.net.euler_characteristic(), 0);
        }
        assert!(net_for_patch_count(&s, &ss, &sb, 0).is_err());
    }
}
