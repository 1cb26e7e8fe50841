//! Crease polylines and corners of a noisy point cloud from its smooth regions
//! ([`super::segment_cloud`]). A cloud has no edge on the crease: its points lie on the faces
//! around it, scattered by the noise, so the crease is placed where the two faces' surfaces
//! meet, extended from each side's own points.
//!
//! 1. **Samples.** A point of region A with a point of region B among its `link` nearest (A and
//!    B meeting at a crease) is a boundary point. Around it, a plane is fitted to A's points and
//!    one to B's among the `gather` nearest (principal components, each at least
//!    `MIN_SIDE` points), and the crease sample is the point of their intersection line in
//!    the plane through the boundary point across the line:
//!
//!      n_A . x = n_A . c_A,   n_B . x = n_B . c_B,   d . x = d . p,   d = n_A x n_B,
//!
//!    kept when the planes meet at `min_angle` degrees or more and the sample lies within
//!    `reach` spacings of p (a plane tilted by a few stray points puts it far away).
//! 2. **Thinning.** Samples are averaged per region pair and grid cell of `cell` spacings.
//! 3. **Chaining.** From the first unvisited sample of a pair, a walk goes to the nearest
//!    unvisited sample of the pair within `step` cells that lies ahead (within 60 degrees of
//!    the current direction), marking the samples beside its path as visited, then back the
//!    other way from the start; a walk that comes back to its start closes a loop. Chains of
//!    fewer than three samples are dropped (noise), the rest smoothed by two passes of
//!    neighbour averaging (ends kept).
//! 4. **Corners.** A point with three or more regions among its `gather` nearest (each at least
//!    `MIN_SIDE` points) gives a corner candidate where the three largest sides' planes meet
//!    (kept when they are not near parallel and the point lies within `reach` spacings);
//!    candidates within a few spacings are one corner, and crease ends near a corner are
//!    joined to it.
//!
//! Step 1 is [`boundary_points`], kept apart so that [`super::folds`] can first measure how
//! much of each pair's common boundary it creases (and merge the pairs that only fold in
//! places); [`creases_from`] does steps 2-4.
//!
//! Every step is a parallel map over points or a sequential walk in index order, so the
//! result does not depend on the thread count.

use super::lines::{cluster, corners_from_ends, fit_plane, join_ends_to_corners, meet, Crease};
use super::segment_cloud::{CloudLabels, NONE};
use crate::spatial::KdTree;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};

/// Fewest points of one side for its plane.
const MIN_SIDE: usize = 5;

/// Options of [`boundary_points`] and [`creases_from`], in multiples of the point spacing where they are lengths.
#[derive(Debug, Clone, Copy)]
pub struct CreaseOptions {
    /// Neighbours that make a point a boundary point (default 10).
    pub link: usize,
    /// Neighbours of the side planes and the corner test (default 40).
    pub gather: usize,
    /// Smallest angle between the side planes for a sample, degrees (default 15).
    pub min_angle: f64,
    /// Largest distance of a sample from its boundary point, spacings (default 4).
    pub reach: f64,
    /// Largest fraction of unlabelled points around a sample (default 0.2).
    pub max_loose: f64,
    /// Each side must have a point this close to a sample, spacings (default 2).
    pub touch: f64,
    /// Thinning cell, spacings (default 2).
    pub cell: f64,
    /// Longest step of a chain, cells (default 3).
    pub step: f64,
}

impl Default for CreaseOptions {
    fn default() -> Self {
        CreaseOptions {
            link: 10,
            gather: 40,
            min_angle: 15.0,
            reach: 4.0,
            max_loose: 0.2,
            touch: 2.0,
            cell: 2.0,
            step: 3.0,
        }
    }
}

/// What one point gives when it lies on the boundary between two regions that meet at a
/// crease (step 1); every field is `None` for the other points.
#[derive(Debug, Clone, Copy, Default)]
pub struct BoundaryPoint {
    /// The region pair (smaller id first) whose common boundary the point lies on.
    pub pair: Option<(u32, u32)>,
    /// The crease sample found there (the pair's side planes meet near the point).
    sample: Option<Sample>,
    /// A corner candidate (three sides' planes meet near the point).
    corner: Option<Point3<f64>>,
}

impl BoundaryPoint {
    /// True when the two sides meet at a crease at this point (a crease sample was found).
    pub fn creased(&self) -> bool {
        self.sample.is_some()
    }
}

/// Running sums of a thinning cell: positions, directions, angles, count.
type CellSum = (Vector3<f64>, Vector3<f64>, f64, f64);

/// A crease sample: position, unit direction along the crease, dihedral angle (degrees).
#[derive(Debug, Clone, Copy)]
struct Sample {
    p: Point3<f64>,
    d: Vector3<f64>,
    angle: f64,
}

/// The points of one region around a boundary point and their plane.
struct Side {
    region: u32,
    centre: Point3<f64>,
    normal: Vector3<f64>,
    count: usize,
}

/// Side planes of the labelled points among `idx`, largest sides first (ties by region id);
/// each fitted twice, the second time without the points farther than `trim` from the first
/// plane.
fn side_planes(
    idx: &[usize],
    points: &[Point3<f64>],
    labels: &CloudLabels,
    trim: f64,
) -> Vec<Side> {
    let mut by: BTreeMap<u32, (Vec<Point3<f64>>, Vector3<f64>)> = BTreeMap::new();
    for &j in idx {
        let l = labels.label[j];
        if l != NONE {
            let e = by.entry(l).or_default();
            e.0.push(points[j]);
            e.1 += labels.normals[j];
        }
    }
    let mut out: Vec<_> = by
        .into_iter()
        .filter(|(_, (p, _))| p.len() >= MIN_SIDE)
        .filter_map(|(l, (p, n))| {
            // Trimmed: the points farther than `trim` from the first plane (a few of another
            // face given to this region near a corner) are left out of the second.
            let (c, m) = fit_plane(&p, &n)?;
            let kept: Vec<Point3<f64>> = p
                .iter()
                .copied()
                .filter(|x| (x - c).dot(&m).abs() <= trim)
                .collect();
            let (c, m) = if kept.len() >= MIN_SIDE && kept.len() < p.len() {
                fit_plane(&kept, &n).unwrap_or((c, m))
            } else {
                (c, m)
            };
            Some(Side {
                region: l,
                centre: c,
                normal: m,
                count: p.len(),
            })
        })
        .collect();
    out.sort_by(|a, b| b.count.cmp(&a.count).then(a.region.cmp(&b.region)));
    out
}

/// Step 1 of the module doc: per point (in order), the region pair whose boundary it lies on,
/// and the crease sample and corner candidate found there; `spacing` is the cloud's typical
/// point spacing.
pub fn boundary_points(
    points: &[Point3<f64>],
    labels: &CloudLabels,
    kd: &KdTree,
    spacing: f64,
    opts: &CreaseOptions,
) -> Vec<BoundaryPoint> {
    let pairs: BTreeSet<(u32, u32)> = labels
        .pairs
        .iter()
        .map(|p| (p.a.min(p.b), p.a.max(p.b)))
        .collect();
    let cos_min = opts.min_angle.to_radians().cos();
    let reach = opts.reach * spacing;
    // Plane fits keep the points within a few noise deviations (or a tenth of a spacing, for
    // exact data) of their first fit.
    let trim = (3.0 * labels.sigma).max(0.1 * spacing);
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            let a = labels.label[i];
            if a == NONE {
                return BoundaryPoint::default();
            }
            let near = kd.knn(&points[i], opts.link);
            let other = near
                .iter()
                .map(|&(j, _)| labels.label[j])
                .filter(|&b| b != a && b != NONE && pairs.contains(&(a.min(b), a.max(b))))
                .min();
            let Some(b) = other else {
                return BoundaryPoint::default();
            };
            let pair = Some((a.min(b), a.max(b)));
            let idx: Vec<usize> = kd
                .knn(&points[i], opts.gather)
                .into_iter()
                .map(|(j, _)| j)
                .collect();
            // Where many points belong to no region the surface is neither of the two faces
            // (a rounded rim, a thin fold): no crease sample there.
            let loose = idx.iter().filter(|&&j| labels.label[j] == NONE).count();
            if loose as f64 > opts.max_loose * idx.len() as f64 {
                return BoundaryPoint {
                    pair,
                    ..BoundaryPoint::default()
                };
            }
            let sides = side_planes(&idx, points, labels, trim);
            let side = |l: u32| sides.iter().find(|s| s.region == l);
            let sample = match (side(a), side(b)) {
                (Some(sa), Some(sb)) if sa.normal.dot(&sb.normal) < cos_min => {
                    let (pa, pb) = ((sa.centre, sa.normal), (sb.centre, sb.normal));
                    let d = pa.1.cross(&pb.1).normalize();
                    // Both faces must come near the sample: near a corner a plane fitted to
                    // a few points of one face can put it off the edge, beside a third face.
                    let near_side = |x: &Point3<f64>, l: u32| {
                        idx.iter()
                            .filter(|&&j| labels.label[j] == l)
                            .any(|&j| (points[j] - x).norm() <= opts.touch * spacing)
                    };
                    meet(&[pa, pb, (points[i], d)], 1e-6)
                        .filter(|x| (x - points[i]).norm() <= reach)
                        .filter(|x| near_side(x, a) && near_side(x, b))
                        .map(|x| {
                            let angle = pa.1.dot(&pb.1).clamp(-1.0, 1.0).acos().to_degrees();
                            Sample { p: x, d, angle }
                        })
                }
                _ => None,
            };
            let corner = if sides.len() >= 3 {
                let planes: Vec<_> = sides[..3].iter().map(|s| (s.centre, s.normal)).collect();
                meet(&planes, 0.1).filter(|x| (x - points[i]).norm() <= reach)
            } else {
                None
            };
            BoundaryPoint {
                pair,
                sample,
                corner,
            }
        })
        .collect()
}

/// Steps 2-4 of the module doc: the creases and corners from the boundary points.
pub fn creases_from(
    found: &[BoundaryPoint],
    spacing: f64,
    opts: &CreaseOptions,
) -> (Vec<Crease>, Vec<Point3<f64>>) {
    let reach = opts.reach * spacing;
    // 2. Thinning per pair and cell.
    let cell = opts.cell * spacing;
    // Per (pair, cell): sums of positions, directions, angles, and the count.
    let mut cells: BTreeMap<((u32, u32), [i64; 3]), CellSum> = BTreeMap::new();
    for (pair, s) in found.iter().filter_map(|f| Some((f.pair?, f.sample?))) {
        let key = s.p.coords.map(|x| (x / cell).floor() as i64);
        let e = cells.entry((pair, [key.x, key.y, key.z])).or_insert((
            Vector3::zeros(),
            Vector3::zeros(),
            0.0,
            0.0,
        ));
        // Directions are signless: align each with the cell's running sum.
        let d = if e.1.dot(&s.d) < 0.0 { -s.d } else { s.d };
        e.0 += s.p.coords;
        e.1 += d;
        e.2 += s.angle;
        e.3 += 1.0;
    }
    let mut by_pair: BTreeMap<(u32, u32), Vec<Sample>> = BTreeMap::new();
    for ((pair, _), (p, d, angle, n)) in cells {
        if let Some(d) = d.try_normalize(1e-300) {
            by_pair.entry(pair).or_default().push(Sample {
                p: Point3::from(p / n),
                d,
                angle: angle / n,
            });
        }
    }
    // 3. Chains.
    let mut creases = Vec::new();
    for (pair, samples) in &by_pair {
        for (chain, closed) in chain_samples(samples, cell, opts.step * cell) {
            if chain.len() < 3 {
                continue;
            }
            let angle = chain.iter().map(|&k| samples[k].angle).sum::<f64>() / chain.len() as f64;
            let mut pts: Vec<Point3<f64>> = chain.iter().map(|&k| samples[k].p).collect();
            smooth(&mut pts, closed, 2);
            if closed {
                pts.push(pts[0]);
            }
            creases.push(Crease {
                points: pts.iter().map(|p| [p.x, p.y, p.z]).collect(),
                angle_deg: angle,
                regions: [pair.0, pair.1],
                closed,
            });
        }
    }
    // 4. Corners.
    // Where creases run into each other their lines give the corner; the three-plane
    // candidates (fitted from the few points of each face right at the corner, so less
    // exact) fill in where a crease faded out before it.
    let mut corners = corners_from_ends(&creases, opts.step * cell);
    let candidates: Vec<Point3<f64>> = found.iter().filter_map(|f| f.corner).collect();
    for c in cluster(&candidates, 2.0 * reach) {
        if corners.iter().all(|e| (e - c).norm() > 2.0 * reach) {
            corners.push(c);
        }
    }
    join_ends_to_corners(&mut creases, &corners, opts.step * cell);
    (creases, corners)
}

/// Chains of sample indices (see the module doc, step 3), with whether each closes a loop.
fn chain_samples(samples: &[Sample], cell: f64, step: f64) -> Vec<(Vec<usize>, bool)> {
    let pts: Vec<Point3<f64>> = samples.iter().map(|s| s.p).collect();
    let Ok(kd) = KdTree::build(&pts) else {
        return Vec::new();
    };
    let mut visited = vec![false; samples.len()];
    let mut out = Vec::new();
    // One direction of a walk from `start` along `dir`: the samples reached, in order, and
    // whether it came back to `start`.
    let walk = |start: usize, dir: Vector3<f64>, visited: &mut Vec<bool>| {
        let mut path = Vec::new();
        let (mut cur, mut d) = (start, dir);
        loop {
            let near = kd.within(&pts[cur], step);
            // Samples beside the path are taken by it.
            for &j in &near {
                if (pts[j] - pts[cur]).norm() <= 0.75 * cell {
                    visited[j] = true;
                }
            }
            let back_home = path.len() >= 3 && (pts[start] - pts[cur]).norm() <= step && {
                let o = pts[start] - pts[cur];
                o.dot(&d) > 0.5 * o.norm()
            };
            let next = near
                .iter()
                .copied()
                .filter(|&j| !visited[j])
                .filter(|&j| {
                    let o = pts[j] - pts[cur];
                    o.dot(&d) > 0.5 * o.norm()
                })
                .min_by(|&a, &b| {
                    (pts[a] - pts[cur])
                        .norm()
                        .total_cmp(&(pts[b] - pts[cur]).norm())
                        .then(a.cmp(&b))
                });
            match next {
                Some(j)
                    if !back_home
                        || (pts[j] - pts[cur]).norm() < (pts[start] - pts[cur]).norm() =>
                {
                    visited[j] = true;
                    path.push(j);
                    let o = (pts[j] - pts[cur]).normalize();
                    let s = if samples[j].d.dot(&o) < 0.0 {
                        -samples[j].d
                    } else {
                        samples[j].d
                    };
                    d = (o + s).try_normalize(1e-300).unwrap_or(o);
                    cur = j;
                }
                _ => return (path, back_home),
            }
        }
    };
    for start in 0..samples.len() {
        if visited[start] {
            continue;
        }
        visited[start] = true;
        let (fwd, closed) = walk(start, samples[start].d, &mut visited);
        if closed {
            let mut chain = vec![start];
            chain.extend(fwd);
            out.push((chain, true));
            continue;
        }
        let (bwd, _) = walk(start, -samples[start].d, &mut visited);
        let mut chain: Vec<usize> = bwd.into_iter().rev().collect();
        chain.push(start);
        chain.extend(fwd);
        out.push((chain, false));
    }
    out
}

/// `passes` of neighbour averaging (x <- x / 2 + (prev + next) / 4), ends of an open chain kept.
fn smooth(pts: &mut [Point3<f64>], closed: bool, passes: usize) {
    let n = pts.len();
    if n < 3 {
        return;
    }
    for _ in 0..passes {
        let old = pts.to_vec();
        for i in 0..n {
            if !closed && (i == 0 || i == n - 1) {
                continue;
            }
            let (prev, next) = ((i + n - 1) % n, (i + 1) % n);
            pts[i] =
                Point3::from(old[i].coords * 0.5 + (old[prev].coords + old[next].coords) * 0.25);
        }
    }
}
