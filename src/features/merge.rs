//! Regions that meet smoothly become one; what stays apart meets at a crease.
//!
//! A segmentation can cut a smooth surface where its evidence is weak: a cloud's region growing
//! stops at a band of high residual on a fillet of small radius, a coarse mesh has rings of
//! edges bent by more than the crease angle along a curved limb. Across a true crease the two
//! sides' surfaces meet at the dihedral angle; across such a cut they continue each other. So at
//! sample points x of every common boundary, each side's local quadratic is fitted to its own
//! labelled points among the `k` nearest to x ([`super::local_fit::region_fit`]), and the angle
//! between the two normals at x is taken; when the median over the samples is under
//! `crease_deg` the two regions are merged (transitively). The median of what remains apart is
//! the pair's dihedral angle.

use super::local_fit::{region_fit, FIT};
use super::union_find::DisjointSets;
use super::RegionPair;
use crate::spatial::KdTree;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Points labelled with regions, their unit outward normals and their tree (a point on a
/// crease may appear once per region).
pub struct Labelled<'a> {
    pub points: &'a [Point3<f64>],
    pub normals: &'a [Vector3<f64>],
    pub label: &'a [u32],
    pub kd: &'a KdTree,
}

/// Sample points on the common boundary of each region pair `(a, b)`, `a < b`, and how much
/// boundary there is (point pairs or edges).
pub type Boundaries = BTreeMap<(u32, u32), (Vec<Point3<f64>>, usize)>;

/// The result of [`merge_smooth`]: new region per old one, the new count, and the pairs that
/// meet at creases.
pub struct Merged {
    pub map: Vec<u32>,
    pub regions: usize,
    pub pairs: Vec<RegionPair>,
}

/// Median over the samples of the cosine between the two sides' normals; -1 (no evidence of
/// a smooth join, so no merge) when fewer than [`MIN_SAMPLES`] samples could be fitted on both
/// sides: a strip of crease points one neighbourhood wide gives no trustworthy surface, and
/// merging on no evidence once joined a hole's wall to the face around it through such a
/// strip.
fn median_cosine(lab: &Labelled, a: u32, b: u32, samples: &[Point3<f64>], k: usize) -> f64 {
    let mut c: Vec<f64> = samples
        .iter()
        .filter_map(|x| {
            let idx: Vec<usize> = lab.kd.knn(x, k).into_iter().map(|v| v.0).collect();
            let qa = region_fit(*x, &idx, lab.label, a, lab.points, lab.normals, FIT)?;
            let qb = region_fit(*x, &idx, lab.label, b, lab.points, lab.normals, FIT)?;
            Some(qa.normal(x).dot(&qb.normal(x)).clamp(-1.0, 1.0))
        })
        .collect();
    if c.len() < MIN_SAMPLES {
        return -1.0;
    }
    let mid = c.len() / 2;
    *c.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Fewest boundary samples fitted on both sides for a merge.
const MIN_SAMPLES: usize = 3;

/// Merges the regions of `boundaries` whose sides continue each other (module doc).
/// `regions` is the number of regions before; `samples` caps the samples per pair.
pub fn merge_smooth(
    lab: &Labelled,
    boundaries: &Boundaries,
    regions: usize,
    k: usize,
    samples: usize,
    crease_deg: f64,
) -> Merged {
    let measured: Vec<((u32, u32), f64, usize)> = boundaries
        .par_iter()
        .map(|(&(a, b), (pts, amount))| {
            let step = (pts.len() / samples.max(1)).max(1);
            let some: Vec<Point3<f64>> = pts.iter().step_by(step).copied().collect();
            ((a, b), median_cosine(lab, a, b, &some, k), *amount)
        })
        .collect();
    let cos_crease = crease_deg.to_radians().cos();
    let mut sets = DisjointSets::new(regions);
    for &((a, b), c, _) in &measured {
        if c > cos_crease {
            sets.union(a, b);
        }
    }
    let (map, count) = sets.labels();
    let mut pairs: BTreeMap<(u32, u32), RegionPair> = BTreeMap::new();
    for ((a, b), c, amount) in measured {
        let (a, b) = (map[a as usize], map[b as usize]);
        if a == b {
            continue;
        }
        let key = (a.min(b), a.max(b));
        let e = pairs.entry(key).or_insert(RegionPair {
            a: key.0,
            b: key.1,
            dihedral_deg: 0.0,
            boundary_samples: 0,
        });
        // The longest boundary's estimate stands for the pair.
        if amount > e.boundary_samples {
            e.dihedral_deg = c.acos().to_degrees();
            e.boundary_samples = amount;
        }
    }
    Merged {
        map,
        regions: count,
        pairs: pairs.into_values().collect(),
    }
}
