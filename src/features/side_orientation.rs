//! Orientation of one-sided normals within their regions (segmentation step 5).
//!
//! A one-sided normal u_i (fitted to the neighbours of point i's own region) has a reliable
//! direction but no sign. Taking the sign from the input normals of the same neighbours fails
//! where those are wrong together: beside an acute crease (a V-block's rim) an estimated normal
//! blends both faces and the global orientation, propagated across the crease, flips a whole
//! strip of them, so the strip's one-sided normals came out reversed while the face's interior
//! was right.
//!
//! Here the sign travels inside the region instead, where the normal field is smooth (Hoppe et
//! al. 1992's propagation, restricted to one region): from a seed, a Prim-like walk over the
//! neighbour graph between points of the same region takes next the edge (i, j) with the
//! largest |u_i . u_j| and gives u_j the sign that makes u_i . u_j >= 0. Each connected part
//! of a region is then turned as a whole to agree with the input normals summed over it,
//!
//! ```text
//!   sum_i  u_i . n_i  >= 0,
//! ```
//!
//! a vote of every point of the part, not of the few beside the crease.

use nalgebra::Vector3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Points with no region (not oriented here).
const NONE: u32 = u32::MAX;

/// A candidate edge of the walk: reach `to` through a point whose normal makes `cos` with its.
struct Edge {
    cos: f64,
    from: u32,
    to: u32,
}

impl PartialEq for Edge {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Edge {}
impl PartialOrd for Edge {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Edge {
    /// Largest |cos| first; ties by the points, so the walk is deterministic.
    fn cmp(&self, other: &Self) -> Ordering {
        self.cos
            .total_cmp(&other.cos)
            .then(other.to.cmp(&self.to))
            .then(other.from.cmp(&self.from))
    }
}

/// Orients `unit` (one-sided normals, any sign) so that neighbours of one region agree and each
/// connected part of a region agrees with `votes` (the input normals) summed over it.
/// `neighbours(i)` lists point i's nearest neighbours; the graph is made symmetric here.
pub fn orient_within_regions<'a>(
    unit: &mut [Vector3<f64>],
    label: &[u32],
    votes: &[Vector3<f64>],
    neighbours: impl Fn(usize) -> &'a [u32],
) {
    let n = unit.len();
    // Symmetric adjacency between points of one region (CSR).
    let mut degree = vec![0u32; n + 1];
    for i in 0..n {
        for &j in neighbours(i) {
            let j = j as usize;
            if j != i && label[i] != NONE && label[j] == label[i] {
                degree[i] += 1;
                degree[j] += 1;
            }
        }
    }
    let mut start = vec![0usize; n + 1];
    for i in 0..n {
        start[i + 1] = start[i] + degree[i] as usize;
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[n]];
    for i in 0..n {
        for &j in neighbours(i) {
            let ju = j as usize;
            if ju != i && label[i] != NONE && label[ju] == label[i] {
                adj[fill[i]] = j;
                fill[i] += 1;
                adj[fill[ju]] = i as u32;
                fill[ju] += 1;
            }
        }
    }

    // Seeds in order of how clearly their neighbours' input normals give their sign.
    let confidence = |i: usize| -> f64 {
        let s: Vector3<f64> = adj[start[i]..start[i + 1]]
            .iter()
            .map(|&j| votes[j as usize])
            .sum::<Vector3<f64>>()
            + votes[i];
        unit[i].dot(&s).abs() / (1 + start[i + 1] - start[i]) as f64
    };
    let mut seeds: Vec<(f64, u32)> = (0..n)
        .filter(|&i| label[i] != NONE)
        .map(|i| (confidence(i), i as u32))
        .collect();
    seeds.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));

    let mut done = vec![false; n];
    let mut heap = BinaryHeap::new();
    let mut part = Vec::new();
    for &(_, seed) in &seeds {
        if done[seed as usize] {
            continue;
        }
        part.clear();
        done[seed as usize] = true;
        part.push(seed);
        push_edges(seed, unit, &adj, &start, &done, &mut heap);
        while let Some(Edge { from, to, .. }) = heap.pop() {
            let t = to as usize;
            if done[t] {
                continue;
            }
            if unit[t].dot(&unit[from as usize]) < 0.0 {
                unit[t] = -unit[t];
            }
            done[t] = true;
            part.push(to);
            push_edges(to, unit, &adj, &start, &done, &mut heap);
        }
        // Finite terms only: one NaN normal must not silence the whole part's vote.
        let vote: f64 = part
            .iter()
            .map(|&i| unit[i as usize].dot(&votes[i as usize]))
            .filter(|x| x.is_finite())
            .sum();
        if vote < 0.0 {
            for &i in &part {
                unit[i as usize] = -unit[i as usize];
            }
        }
    }
}

/// Pushes the edges from the oriented point `i` to its region neighbours not yet oriented.
fn push_edges(
    i: u32,
    unit: &[Vector3<f64>],
    adj: &[u32],
    start: &[usize],
    done: &[bool],
    heap: &mut BinaryHeap<Edge>,
) {
    let iu = i as usize;
    for &j in &adj[start[iu]..start[iu + 1]] {
        if !done[j as usize] {
            heap.push(Edge {
                cos: unit[iu].dot(&unit[j as usize]).abs(),
                from: i,
                to: j,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of points on one plane (region 0) whose votes are reversed on a strip beside its
    /// end (as beside an acute crease), and two points of another region.
    #[test]
    fn a_strip_of_reversed_votes_does_not_reverse_its_points() {
        let n = 40;
        let mut unit: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                if i % 3 == 0 {
                    -Vector3::z()
                } else {
                    Vector3::z()
                }
            })
            .collect();
        let mut label = vec![0u32; n];
        let mut votes: Vec<Vector3<f64>> = (0..n)
            .map(|i| if i >= 30 { -Vector3::z() } else { Vector3::z() })
            .collect();
        // Two points of another region, whose normal is x, voted -x.
        label[38] = 1;
        label[39] = 1;
        unit[38] = Vector3::x();
        unit[39] = -Vector3::x();
        votes[38] = -Vector3::x();
        votes[39] = -Vector3::x();
        // Neighbours: the two before and the two after on the row.
        let table: Vec<Vec<u32>> = (0..n)
            .map(|i| {
                (i.saturating_sub(2)..(i + 3).min(n))
                    .map(|j| j as u32)
                    .collect()
            })
            .collect();
        // With the neighbours' votes alone, the strip's points would turn to -z.
        orient_within_regions(&mut unit, &label, &votes, |i| &table[i]);
        for (i, u) in unit.iter().enumerate().take(38) {
            assert_eq!(*u, Vector3::z(), "point {i}");
        }
        assert_eq!(unit[38], -Vector3::x());
        assert_eq!(unit[39], -Vector3::x());
    }

    #[test]
    fn points_without_a_region_keep_their_normal() {
        let mut unit = vec![-Vector3::z(), Vector3::z()];
        let label = vec![NONE, NONE];
        let votes = vec![Vector3::z(), -Vector3::z()];
        let table = [vec![0u32, 1], vec![1u32, 0]];
        orient_within_regions(&mut unit, &label, &votes, |i| &table[i]);
        assert_eq!(unit, vec![-Vector3::z(), Vector3::z()]);
    }
}
