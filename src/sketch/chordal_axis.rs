//! Chordal axis transform of a panel (seed 001 section 4.1, after Prasad): a constrained
//! Delaunay triangulation (spade) of the region with its boundary loops as constraints; every
//! interior triangle is a terminal (two boundary edges), sleeve (one) or junction (none)
//! triangle. Skeleton nodes are the midpoints of the internal edges (chords); a sleeve joins
//! its two chords, a junction joins its three chords through its centroid. Short spurs from
//! boundary jitter are pruned, degree-2 chains are thinned to a target spacing, and each node
//! gets the radius of the largest disc around it inside the region (distance to the boundary).

use super::contour::Part;
use crate::error::{Error, Result};
use nalgebra::Point2;
use spade::{ConstrainedDelaunayTriangulation, Triangulation};
use std::collections::HashMap;

/// A planar skeleton graph with radii.
#[derive(Debug, Clone, Default)]
pub struct Skeleton2 {
    pub nodes: Vec<Point2<f64>>,
    pub radius: Vec<f64>,
    pub edges: Vec<[usize; 2]>,
}

impl Skeleton2 {
    fn adjacency(&self) -> Vec<Vec<usize>> {
        let mut adj = vec![Vec::new(); self.nodes.len()];
        for &[a, b] in &self.edges {
            adj[a].push(b);
            adj[b].push(a);
        }
        adj
    }
}

/// Chordal axis of one part, thinned to about `spacing` between nodes.
pub fn chordal_axis(part: &Part, spacing: f64) -> Result<Skeleton2> {
    let mut cdt: ConstrainedDelaunayTriangulation<spade::Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    for lp in part.loops() {
        let mut handles = Vec::with_capacity(lp.len());
        for p in lp {
            let h = cdt
                .insert(spade::Point2::new(p.x, p.y))
                .map_err(|e| Error::Degenerate(format!("cannot triangulate the contour: {e:?}")))?;
            handles.push(h);
        }
        for i in 0..handles.len() {
            let (a, b) = (handles[i], handles[(i + 1) % handles.len()]);
            if a != b && cdt.can_add_constraint(a, b) {
                cdt.add_constraint(a, b);
            }
        }
    }
    let mut sk = Skeleton2::default();
    let mut chord: HashMap<(usize, usize), usize> = HashMap::new();
    let mut node_of = |sk: &mut Skeleton2, a: usize, b: usize, pa: Point2<f64>, pb: Point2<f64>| {
        let key = (a.min(b), a.max(b));
        *chord.entry(key).or_insert_with(|| {
            sk.nodes.push(Point2::from((pa.coords + pb.coords) / 2.0));
            sk.nodes.len() - 1
        })
    };
    for f in cdt.inner_faces() {
        let ps = f.positions();
        let pts = ps.map(|p| Point2::new(p.x, p.y));
        let centroid = Point2::from((pts[0].coords + pts[1].coords + pts[2].coords) / 3.0);
        if !part.contains(&centroid) {
            continue;
        }
        let mut internal = Vec::new();
        for e in f.adjacent_edges() {
            if !e.is_constraint_edge() {
                let (a, b) = (e.from(), e.to());
                let (pa, pb) = (a.position(), b.position());
                internal.push(node_of(
                    &mut sk,
                    a.fix().index(),
                    b.fix().index(),
                    Point2::new(pa.x, pa.y),
                    Point2::new(pb.x, pb.y),
                ));
            }
        }
        match internal.len() {
            2 => sk.edges.push([internal[0], internal[1]]),
            3 => {
                sk.nodes.push(centroid);
                let c = sk.nodes.len() - 1;
                for &k in &internal {
                    sk.edges.push([c, k]);
                }
            }
            0 => sk.nodes.push(centroid),
            _ => {}
        }
    }
    if sk.nodes.is_empty() {
        return Err(Error::Degenerate(
            "the contour's triangulation has no interior triangle".into(),
        ));
    }
    sk.radius = sk
        .nodes
        .iter()
        .map(|p| boundary_distance(part, p))
        .collect();
    let sk = prune(sk);
    Ok(thin(&sk, spacing))
}

/// Distance from `p` to the part's boundary polylines.
pub fn boundary_distance(part: &Part, p: &Point2<f64>) -> f64 {
    let mut best = f64::MAX;
    for lp in part.loops() {
        let n = lp.len();
        for i in 0..n {
            let (a, b) = (lp[i], lp[(i + 1) % n]);
            let ab = b - a;
            let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
            best = best.min((a + ab * t - p).norm());
        }
    }
    best
}

/// Removes spurs: a branch from a leaf to a junction shorter than the junction's radius.
fn prune(mut sk: Skeleton2) -> Skeleton2 {
    for _ in 0..3 {
        let adj = sk.adjacency();
        let mut dead = vec![false; sk.nodes.len()];
        let mut changed = false;
        for leaf in 0..sk.nodes.len() {
            if adj[leaf].len() != 1 {
                continue;
            }
            let mut path = vec![leaf];
            let mut len = 0.0;
            let (mut prev, mut cur) = (leaf, adj[leaf][0]);
            loop {
                len += (sk.nodes[cur] - sk.nodes[prev]).norm();
                if adj[cur].len() != 2 {
                    break;
                }
                path.push(cur);
                let next = if adj[cur][0] == prev {
                    adj[cur][1]
                } else {
                    adj[cur][0]
                };
                prev = cur;
                cur = next;
            }
            if adj[cur].len() >= 3 && len < 1.2 * sk.radius[cur] {
                for &k in &path {
                    dead[k] = true;
                }
                changed = true;
            }
        }
        if !changed {
            break;
        }
        sk = keep(&sk, &dead);
    }
    sk
}

fn keep(sk: &Skeleton2, dead: &[bool]) -> Skeleton2 {
    let mut map = vec![usize::MAX; sk.nodes.len()];
    let mut out = Skeleton2::default();
    for i in 0..sk.nodes.len() {
        if !dead[i] {
            map[i] = out.nodes.len();
            out.nodes.push(sk.nodes[i]);
            out.radius.push(sk.radius[i]);
        }
    }
    for &[a, b] in &sk.edges {
        if !dead[a] && !dead[b] {
            out.edges.push([map[a], map[b]]);
        }
    }
    out
}

/// Thins degree-2 chains so that consecutive kept nodes are about `spacing` apart (junctions,
/// leaves and one node per pure cycle are always kept).
fn thin(sk: &Skeleton2, spacing: f64) -> Skeleton2 {
    let adj = sk.adjacency();
    let n = sk.nodes.len();
    let mut keep_node: Vec<bool> = adj.iter().map(|a| a.len() != 2).collect();
    let mut visited_edge: HashMap<(usize, usize), ()> = HashMap::new();
    let mut seen = vec![false; n];
    let mut out_edges: Vec<[usize; 2]> = Vec::new();
    let mut walk = |start: usize,
                    first: usize,
                    keep_node: &mut Vec<bool>,
                    out: &mut Vec<[usize; 2]>,
                    seen: &mut Vec<bool>| {
        let key = (start.min(first), start.max(first));
        if visited_edge.insert(key, ()).is_some() {
            return;
        }
        let (mut prev, mut cur) = (start, first);
        let mut last = start;
        let mut acc = (sk.nodes[cur] - sk.nodes[prev]).norm();
        loop {
            if keep_node[cur] || cur == start {
                if last != cur {
                    out.push([last, cur]);
                }
                return;
            }
            if acc >= spacing {
                keep_node[cur] = true;
                out.push([last, cur]);
                last = cur;
                acc = 0.0;
            }
            seen[cur] = true;
            let next = if adj[cur][0] == prev {
                adj[cur][1]
            } else {
                adj[cur][0]
            };
            visited_edge.insert((cur.min(next), cur.max(next)), ());
            prev = cur;
            cur = next;
            acc += (sk.nodes[cur] - sk.nodes[prev]).norm();
        }
    };
    for s in 0..n {
        if keep_node[s] {
            for &f in &adj[s] {
                walk(s, f, &mut keep_node, &mut out_edges, &mut seen);
            }
        }
    }
    // Pure cycles (no node of degree != 2): start at their lowest node.
    for s in 0..n {
        if !keep_node[s] && !seen[s] && adj[s].len() == 2 {
            keep_node[s] = true;
            walk(s, adj[s][0], &mut keep_node, &mut out_edges, &mut seen);
        }
    }
    let mut map = vec![usize::MAX; n];
    let mut out = Skeleton2::default();
    for i in 0..n {
        if keep_node[i] {
            map[i] = out.nodes.len();
            out.nodes.push(sk.nodes[i]);
            out.radius.push(sk.radius[i]);
        }
    }
    for [a, b] in out_edges {
        if map[a] != usize::MAX && map[b] != usize::MAX && a != b {
            out.edges.push([map[a], map[b]]);
        }
    }
    out.edges.sort_unstable();
    out.edges.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::super::contour::analyse;
    use super::*;

    fn ellipse(a: f64, b: f64, n: usize) -> Vec<Point2<f64>> {
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                Point2::new(a * t.cos(), b * t.sin())
            })
            .collect()
    }

    #[test]
    fn ellipse_axis_is_a_chain_along_the_major_axis() {
        let an = analyse(&[ellipse(4.0, 1.0, 200)], &[], 0.1, false).unwrap();
        let sk = chordal_axis(&an.parts[0], 0.3).unwrap();
        assert!(sk.nodes.len() > 8, "{}", sk.nodes.len());
        // A tree (no cycle) close to y = 0 with radii up to the minor axis.
        assert_eq!(sk.edges.len() + 1, sk.nodes.len());
        let ymax = sk.nodes.iter().fold(0.0f64, |m, p| m.max(p.y.abs()));
        assert!(ymax < 0.35, "{ymax}");
        let rmax = sk.radius.iter().cloned().fold(0.0, f64::max);
        assert!((rmax - 1.0).abs() < 0.1, "{rmax}");
    }

    #[test]
    fn ring_axis_is_a_cycle() {
        let mut inner = ellipse(1.0, 1.0, 80);
        inner.iter_mut().for_each(|p| *p = Point2::new(p.x, p.y));
        let an = analyse(&[ellipse(2.0, 2.0, 160), inner], &[], 0.08, false).unwrap();
        let sk = chordal_axis(&an.parts[0], 0.3).unwrap();
        assert_eq!(sk.edges.len(), sk.nodes.len(), "one cycle");
        for (p, r) in sk.nodes.iter().zip(&sk.radius) {
            assert!((p.coords.norm() - 1.5).abs() < 0.15);
            assert!((r - 0.5).abs() < 0.1);
        }
    }
}
