//! Segmentation of an oriented point cloud into smooth regions: the faces of a machined part,
//! separated by its creases (normal discontinuities), for a cloud with noise and no reliable
//! normals near the creases.
//!
//! 1. **Smoothness.** Every point gets a quadratic height function fitted to its k nearest
//!    neighbours ([`super::local_fit`]); its rms residual r_i is about the noise sigma on a
//!    smooth surface and about the kink's depth where the neighbourhood straddles a crease.
//!    sigma is taken as the median r_i (creases are a small part of any surface), and a point is
//!    *smooth* when r_i < `smooth_factor` sigma. The fit also gives a normal m_i far less
//!    blurred than a PCA normal on curved parts.
//! 2. **Region growing** (Rabbani et al. 2006, "Segmentation of point clouds using smoothness
//!    constraint"): from the smoothest unlabelled point, a breadth-first walk over the
//!    neighbour graph joins smooth neighbours whose normals m differ by less than `link_deg`.
//!    Near a crease the points are not smooth, so the walk stops there. Regions under
//!    `min_region` points are dissolved.
//! 3. **Assignment of the crease band.** Points left over (the band along every crease, about a
//!    neighbourhood wide) are given, round after round, to the region whose local surface
//!    passes nearest to them: for every region with at least [`MIN_SUPPORT`] labelled points
//!    among the point's `gather` nearest, a quadratic is fitted to those points and the point
//!    goes to the one with the smallest |distance|. A band point on B's side at distance d from
//!    the crease lies d sin(theta) from A's surface (theta the dihedral), so only points within
//!    a few sigma / sin(theta) of the crease can go to the wrong side. Each round decides from
//!    the labels of the round before (parallel, deterministic); points without support wait
//!    until the fronts reach them, and so do points the fronts so far would take across a
//!    corner ([`BAND_WAIT`]).
//! 4. **Merging smooth joins.** Two regions separated by a band of high residual on a surface
//!    that is smooth there after all (a fillet of small radius, a curved spot of an organic
//!    scan) meet at a small angle: at sample points of their common boundary, each side's
//!    quadratic (from its own points) gives a normal, and when the median angle between them is
//!    under `crease_deg` the two regions are one. What is left apart meets at a crease.
//! 5. **One-sided normals.** Every point's normal is re-fitted from the neighbours of its own
//!    region, so normals beside a crease are no longer a blend of both faces, and oriented
//!    within its region ([`super::side_orientation`]): the sign travels from point to point
//!    of one region and each region's connected part agrees with the input normals summed
//!    over it, so a strip of estimated normals flipped beside an acute crease does not flip
//!    its one-sided normals.

use super::local_fit::{region_fit, region_fit_trimmed, LocalQuadric, Support, FIT, MIN_SUPPORT};
use super::merge::{merge_smooth, Boundaries, Labelled};
use super::side_orientation::orient_within_regions;
use super::RegionPair;
use crate::spatial::KdTree;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::collections::{BTreeMap, VecDeque};

/// No region.
pub const NONE: u32 = u32::MAX;

/// Waiting band points (step 3). A band point waits for the other fronts when the nearest
/// surface of the regions that reached it misses it by more than `BAND_WAIT` times the
/// growth's acceptance *and* by more than `BAND_SLOPE` times its distance to that region's
/// nearest labelled point, *and* its own normal turns from that surface's by more than 30
/// degrees (`BAND_TURN_COS`). A point of another face beside a corner is such a point (it lies
/// off the surface by about the sine of the dihedral times that distance); a point of a curved
/// surface is not (the quadric's extrapolation error is small and the normals agree). When no
/// point is within the limit the limit doubles, so the nearest still go first. Near a corner the
/// growth stops well short of it on every face (the neighbourhoods straddle two creases), and
/// without the wait the first front to arrive took the whole corner: make_parts' cornerblock
/// cloud had bottom-face points 1.2 mm from the side wall labelled as the wall, whose sharp
/// function then cut the corner 0.13 mm. Without the turn test the Stanford bunny's vertices
/// got a crease of a fifth of its diagonal.
const BAND_WAIT: f64 = 2.0;

/// See [`BAND_WAIT`].
const BAND_SLOPE: f64 = 0.1;

/// See [`BAND_WAIT`]: cos 30 degrees.
const BAND_TURN_COS: f64 = 0.866;

/// Fewest labelled points of the growing region around a candidate for the acceptance test.
pub const GROW_SUPPORT: usize = 5;

/// Options of [`segment_cloud`], with documented defaults.
#[derive(Debug, Clone, Copy)]
pub struct CloudOptions {
    /// Neighbours of the smoothness fit (default 16).
    pub neighbours: usize,
    /// Neighbours linked by region growing (default 8, the nearest of the `neighbours`).
    pub link: usize,
    /// Largest angle between linked neighbours' normals, degrees (default 30: a loose guard;
    /// the distance test `accept_factor` decides).
    pub link_deg: f64,
    /// A neighbour joins a region when it lies within this many sigma of the region's local
    /// quadric (default 3).
    pub accept_factor: f64,
    /// A point is smooth below this many times the median residual (default 2.5).
    pub smooth_factor: f64,
    /// A point is smooth only where its quadratic's normal turns by less than this across the
    /// neighbourhood, degrees (default 15; 0 turns the test off). A quadratic over 16 noisy
    /// neighbours absorbs a 45-degree crease with a residual near the noise, so the residual
    /// alone lets regions grow across such creases; the bend it needs to do so does not hide.
    pub bend_deg: f64,
    /// Regions with fewer points are dissolved before the band is assigned (default 40).
    pub min_region: usize,
    /// Neighbours looked at when assigning a band point (default 32).
    pub gather: usize,
    /// Regions meeting at a median angle under this are merged, degrees (default 20).
    pub crease_deg: f64,
    /// Boundary samples per region pair for the merge test (default 48).
    pub pair_samples: usize,
}

impl Default for CloudOptions {
    fn default() -> Self {
        CloudOptions {
            neighbours: 16,
            link: 8,
            link_deg: 30.0,
            accept_factor: 3.0,
            smooth_factor: 2.5,
            bend_deg: 15.0,
            min_region: 40,
            gather: 32,
            crease_deg: 20.0,
            pair_samples: 48,
        }
    }
}

/// A labelling of the points into smooth regions.
#[derive(Debug, Clone)]
pub struct CloudLabels {
    /// Region per point, [`NONE`] for the few points no region took.
    pub label: Vec<u32>,
    pub regions: usize,
    /// One-sided unit normals (step 5), oriented like the input normals.
    pub normals: Vec<Vector3<f64>>,
    /// Median residual of the smoothness fits (about the noise sigma).
    pub sigma: f64,
    /// Points found smooth in step 1.
    pub smooth_points: usize,
    /// Regions meeting at a crease, with their dihedral angles.
    pub pairs: Vec<RegionPair>,
}

/// The k nearest neighbours of every point, flattened (k per point; the point itself first).
fn neighbour_table(points: &[Point3<f64>], kd: &KdTree, k: usize) -> Vec<u32> {
    points
        .par_iter()
        .flat_map_iter(|p| {
            let mut v: Vec<u32> = kd.knn(p, k).into_iter().map(|(j, _)| j as u32).collect();
            // Fewer points than k: repeat the last (only ever happens on tiny inputs).
            while v.len() < k {
                v.push(*v.last().unwrap_or(&0));
            }
            v
        })
        .collect()
}

/// Region growing: a plane from as few as [`GROW_SUPPORT`] points at the front (a quadratic
/// extrapolated from few points scatters by several sigma), a quadratic from 16, and never
/// from points strung along a line.
const GROW: Support = Support {
    points: GROW_SUPPORT,
    quadratic_from: 16,
    spread: 0.3,
};

/// Neighbours of the boundary re-examination (step 3b).
const REASSIGN_NEIGHBOURS: usize = 64;

/// Rounds of the boundary re-examination (step 3b).
const REASSIGN_ROUNDS: usize = 3;

/// Boundary re-examination: a plane below 16 points (extrapolating to the point examined), a
/// quadratic from 16.
const REASSIGN: Support = Support {
    points: MIN_SUPPORT,
    quadratic_from: 16,
    spread: 0.0,
};

/// Segments `points` (unit outward `normals`, `kd` their tree) into smooth regions.
pub fn segment_cloud(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    kd: &KdTree,
    opt: &CloudOptions,
) -> CloudLabels {
    let n = points.len();
    let k = opt.neighbours.clamp(4, n.max(4));
    if n < 2 * k {
        return CloudLabels {
            label: vec![0; n],
            regions: usize::from(n > 0),
            normals: normals.to_vec(),
            sigma: 0.0,
            smooth_points: n,
            pairs: Vec::new(),
        };
    }
    // One table of the `gather` nearest: its first k are the smoothness neighbourhood.
    let gather = opt.gather.max(k).min(n);
    let table = neighbour_table(points, kd, gather);
    let nbrs = |i: usize| &table[i * gather..i * gather + k];
    let wide = |i: usize| &table[i * gather..(i + 1) * gather];

    // 1. Smoothness fits: residual, normal and bend (largest angle between the normal at the
    // point and at its neighbours) per point.
    let fits: Vec<(f64, Vector3<f64>, f64)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let pts: Vec<Point3<f64>> = nbrs(i).iter().map(|&j| points[j as usize]).collect();
            match LocalQuadric::fit(points[i], normals[i], &pts) {
                Some(q) => {
                    let m = q.normal(&points[i]);
                    let bend = pts.iter().map(|p| m.dot(&q.normal(p))).fold(1.0, f64::min);
                    (q.rms(&pts), m, bend)
                }
                None => (f64::INFINITY, normals[i], -1.0),
            }
        })
        .collect();
    let mut res: Vec<f64> = fits.iter().map(|f| f.0).filter(|r| r.is_finite()).collect();
    let sigma = if res.is_empty() {
        0.0
    } else {
        let m = res.len() / 2;
        *res.select_nth_unstable_by(m, f64::total_cmp).1
    };
    // Exact data: the median residual is rounding; a floor of a millionth of the
    // neighbourhood's size keeps the test meaningful.
    let radius = (0..n.min(1000))
        .map(|i| (points[nbrs(i)[k - 1] as usize] - points[i]).norm())
        .sum::<f64>()
        / n.min(1000) as f64;
    let tau = (opt.smooth_factor * sigma).max(1e-6 * radius);
    let cos_bend = if opt.bend_deg > 0.0 {
        opt.bend_deg.to_radians().cos()
    } else {
        -2.0
    };
    let smooth: Vec<bool> = fits.iter().map(|f| f.0 < tau && f.2 > cos_bend).collect();
    let m: Vec<Vector3<f64>> = fits.iter().map(|f| f.1).collect();

    // 2. Region growing from the smoothest points: a neighbour joins when it lies within
    // `accept` of the quadric fitted to the region's points around it (model-checked, so the
    // growth stops a few sigma / sin(theta) past a crease however gradually the normals turn).
    let mut order: Vec<u32> = (0..n as u32).filter(|&i| smooth[i as usize]).collect();
    order.sort_by(|&a, &b| {
        fits[a as usize]
            .0
            .total_cmp(&fits[b as usize].0)
            .then(a.cmp(&b))
    });
    let cos_link = opt.link_deg.to_radians().cos();
    let link = opt.link.clamp(1, k);
    let accept = (opt.accept_factor * sigma).max(1e-3 * radius);

    let mut label = vec![NONE; n];
    let mut sizes: Vec<usize> = Vec::new();
    let mut queue = VecDeque::new();
    let mut idx: Vec<usize> = Vec::with_capacity(gather);

    for &s in &order {
        if label[s as usize] != NONE {
            continue;
        }
        let id = sizes.len() as u32;
        label[s as usize] = id;
        // The seed's own neighbourhood starts the region where it fits the seed's quadric.
        let su = s as usize;
        let pts: Vec<Point3<f64>> = nbrs(su).iter().map(|&j| points[j as usize]).collect();
        let Some(q) = LocalQuadric::fit(points[su], m[su], &pts) else {
            sizes.push(1);
            continue;
        };
        let mut size = 1;
        for &j in &nbrs(su)[1..] {
            let ju = j as usize;
            if label[ju] == NONE && q.distance(&points[ju]).abs() < accept {
                label[ju] = id;
                if smooth[ju] {
                    queue.push_back(j);
                }
                size += 1;
            }
        }
        while let Some(i) = queue.pop_front() {
            let i = i as usize;
            for &j in &nbrs(i)[..link] {
                let ju = j as usize;
                if label[ju] != NONE || m[i].dot(&m[ju]).abs() < cos_link {
                    continue;
                }
                idx.clear();
                idx.extend(wide(ju).iter().map(|&x| x as usize));
                let Some(q) = region_fit(points[ju], &idx, &label, id, points, &m, GROW) else {
                    continue;
                };
                if q.distance(&points[ju]).abs() < accept {
                    label[ju] = id;
                    // Only smooth points carry the growth on (Rabbani et al.): a crease point
                    // joins but does not lead the region along the crease.
                    if smooth[ju] {
                        queue.push_back(j);
                    }
                    size += 1;
                }
            }
        }
        sizes.push(size);
    }

    // Small regions dissolved; the rest renumbered in order.
    let mut renum = vec![NONE; sizes.len()];
    let mut count = 0u32;
    for (r, &s) in sizes.iter().enumerate() {
        if s >= opt.min_region {
            renum[r] = count;
            count += 1;
        }
    }
    for l in label.iter_mut() {
        if *l != NONE {
            *l = renum[*l as usize];
        }
    }
    // No region large enough (a cloud so sparse or curved that hardly a point is smooth, like
    // the vertices of a coarse mesh): one region, as nothing separates the points.
    if count == 0 {
        label.fill(0);
        count = 1;
    }

    // 3. The band, round by round from the regions inwards.
    loop {
        let todo: Vec<usize> = (0..n).filter(|&i| label[i] == NONE).collect();
        if todo.is_empty() {
            break;
        }
        // Each point's nearest region surface, and how far off it lies relative to what that
        // surface may miss by: noise, or the bend of a curved surface extrapolated from its
        // nearest labelled point r away.
        let best: Vec<(usize, f64, u32)> = todo
            .par_iter()
            .filter_map(|&i| {
                let idx: Vec<usize> = wide(i).iter().map(|&x| x as usize).collect();
                let cands = labels_among(&idx, &label);
                let mut best: Option<(f64, f64, u32)> = None;
                for l in cands {
                    let Some(q) = region_fit(points[i], &idx, &label, l, points, &m, FIT) else {
                        continue;
                    };
                    let d = q.distance(&points[i]).abs();
                    if best.is_none_or(|b| d < b.0) {
                        let r = idx
                            .iter()
                            .filter(|&&j| label[j] == l)
                            .map(|&j| (points[j] - points[i]).norm())
                            .fold(f64::INFINITY, f64::min);
                        // Only a point whose own normal turns away from the surface waits.
                        let turned = q.normal(&points[i]).dot(&m[i]).abs() < BAND_TURN_COS;
                        let score = if turned {
                            d / (BAND_WAIT * accept).max(BAND_SLOPE * r)
                        } else {
                            0.0
                        };
                        best = Some((d, score, l));
                    }
                }
                best.map(|b| (i, b.1, b.2))
            })
            .collect();
        if best.is_empty() {
            break;
        }
        // Those within the limit; when none is, the limit doubles until some are (the nearest
        // go first, and the next round's fronts have moved).
        let nearest = best.iter().map(|b| b.1).fold(f64::INFINITY, f64::min);
        let mut limit = 1.0;
        while limit < nearest {
            limit *= 2.0;
        }
        let decided: Vec<(usize, u32)> = best
            .iter()
            .filter(|b| b.1 <= limit)
            .map(|b| (b.0, b.2))
            .collect();
        // Only scores that are not numbers (0 / 0 on degenerate data) are left: nothing moves.
        if decided.is_empty() {
            break;
        }
        for (i, l) in decided {
            label[i] = l;
        }
    }

    // 3b. Boundary points re-examined: each goes to the region whose local surface (fitted to
    // that region's other points nearby) passes nearest, when its own misses it by more than
    // the growth's acceptance and another does better by half. The fronts of step 3 and the
    // growth's quadratics can carry a few points a tenth of a millimetre past a crease; on
    // their region's implicit they would pull the crease off its place.
    for _ in 0..REASSIGN_ROUNDS {
        let moves: Vec<(usize, u32)> = (0..n)
            .into_par_iter()
            .filter(|&i| {
                label[i] != NONE
                    && nbrs(i)
                        .iter()
                        .any(|&j| label[j as usize] != label[i] && label[j as usize] != NONE)
            })
            .filter_map(|i| {
                // A wider neighbourhood than the growth's, the point itself left out, each
                // region's fit trimmed of its own outliers.
                let idx: Vec<usize> = kd
                    .knn(&points[i], REASSIGN_NEIGHBOURS)
                    .into_iter()
                    .map(|x| x.0)
                    .filter(|&j| j != i)
                    .collect();
                let cands = labels_among(&idx, &label);
                let dist = |l: u32| {
                    region_fit_trimmed(points[i], &idx, &label, l, points, &m, REASSIGN, accept)
                        .map(|q| q.distance(&points[i]).abs())
                };
                let own = dist(label[i])?;
                if own <= accept {
                    return None;
                }
                let best = cands
                    .iter()
                    .filter(|&&l| l != label[i])
                    .filter_map(|&l| dist(l).map(|d| (d, l)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                match best {
                    Some((d, l)) if d < 0.5 * own => Some((i, l)),
                    // Far from its own surface and no better on another: an outlier, left out.
                    _ if own > 2.0 * accept => Some((i, NONE)),
                    _ => None,
                }
            })
            .collect();
        if moves.is_empty() {
            break;
        }
        for (i, l) in moves {
            label[i] = l;
        }
    }

    // 4. Merge regions that meet smoothly.
    let mut boundaries: Boundaries = BTreeMap::new();
    for i in 0..n {
        let a = label[i];
        if a == NONE {
            continue;
        }
        for &j in &nbrs(i)[1..link] {
            let b = label[j as usize];
            if b != NONE && b > a {
                let e = boundaries.entry((a, b)).or_default();
                e.0.push(nalgebra::center(&points[i], &points[j as usize]));
                e.1 += 1;
            }
        }
    }
    let lab = Labelled {
        points,
        normals: &m,
        label: &label,
        kd,
    };
    let merged = merge_smooth(
        &lab,
        &boundaries,
        count as usize,
        gather,
        opt.pair_samples,
        opt.crease_deg,
    );
    for l in label.iter_mut() {
        if *l != NONE {
            *l = merged.map[*l as usize];
        }
    }
    let (regions, pairs) = (merged.regions, merged.pairs);

    // 5. One-sided normals, oriented within their regions.
    let mut one_sided: Vec<Vector3<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let l = label[i];
            if l == NONE {
                return normals[i];
            }
            let idx: Vec<usize> = nbrs(i).iter().map(|&j| j as usize).collect();
            region_fit(points[i], &idx, &label, l, points, &m, FIT)
                .map_or(m[i], |q| q.normal(&points[i]))
        })
        .collect();
    orient_within_regions(&mut one_sided, &label, normals, |i| &nbrs(i)[..link]);
    CloudLabels {
        label,
        regions,
        normals: one_sided,
        sigma,
        smooth_points: smooth.iter().filter(|&&s| s).count(),
        pairs,
    }
}

/// The distinct region labels (not [`NONE`]) of the points `idx`, sorted.
fn labels_among(idx: &[usize], label: &[u32]) -> Vec<u32> {
    let mut cands: Vec<u32> = idx
        .iter()
        .map(|&j| label[j])
        .filter(|&l| l != NONE)
        .collect();
    cands.sort_unstable();
    cands.dedup();
    cands
}
