//! Edge flips inside a region: towards valence 6 (4 on an open boundary) during the
//! remeshing, and to locally Delaunay triangles and without ears at its end. A crease edge is
//! never flipped, and no flip turns a triangle by more than about 25 degrees from the pair's
//! mean normal (from the other triangle's normal, for an ear).
//!
//! An *ear* is a triangle (x, a, b) whose two edges at x lie on the same crease, x being a
//! crease vertex (not a corner): the crease runs a - x - b, and the triangle spans the sliver
//! between the crease and its chord a - b, with an angle near 180 degrees at x on a straight
//! or gently curved crease (zero area, or turned inside out where the crease curves away from
//! the region). Its quads (`polygonize::quad_split`) have three corners on the crease and fold.
//! Flipping the chord a - b to x - d (d the vertex across it) replaces it with two triangles
//! that each have one crease edge.

use super::{key, Kind, On, Rules, State, Topo, NONE};

/// A Delaunay flip needs the opposite angles to exceed pi by this much, radians (no flips back
/// and forth between cocircular vertices).
const DELAUNAY_SLACK: f64 = 1e-3;

/// Flips interior edges inside a region where that brings the four valences nearer their
/// targets (6, or 4 on an open boundary), corners not counted.
pub(super) fn flip_to_valence(s: &mut State, rules: &Rules) -> usize {
    flip_edges(s, rules, Flip::Valence)
}

/// Which edges [`flip_edges`] flips.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Flip {
    /// Those whose flip brings the four valences nearer their targets.
    Valence,
    /// Those whose two opposite angles sum to more than pi (not locally Delaunay): the
    /// obtuse triangles that would give the quad split darts.
    Delaunay,
    /// The chords of ears (module doc).
    Ear,
}

/// Flips interior edges inside a region by the criterion `flip`, one per vertex per pass.
pub(super) fn flip_edges(s: &mut State, rules: &Rules, flip: Flip) -> usize {
    let topo = s.topo();
    let valence: Vec<i64> = (0..s.pos.len() as u32)
        .map(|v| topo.neighbours(s, v).len() as i64)
        .collect();
    let mut open = vec![false; s.pos.len()];
    for (&(a, b), fs) in &topo.edges {
        if fs[1] == NONE {
            open[a as usize] = true;
            open[b as usize] = true;
        }
    }
    let deviation = |v: u32, val: i64| -> i64 {
        if topo.kind[v as usize] == Kind::Corner {
            0
        } else {
            (val - if open[v as usize] { 4 } else { 6 }).abs()
        }
    };
    let mut edges: Vec<(u32, u32)> = topo.edges.keys().copied().collect();
    edges.sort_unstable();
    let mut touched = vec![false; s.pos.len()];
    let mut count = 0;
    for (a, b) in edges {
        let fs = topo.edges[&(a, b)];
        if s.is_crease(&fs) || [a, b].iter().any(|&v| touched[v as usize]) {
            continue;
        }
        // Orient: f0 walks a -> b.
        let t0 = s.tris[fs[0] as usize];
        let walks = (0..3).any(|i| t0[i] == a && t0[(i + 1) % 3] == b);
        let (f0, f1) = if walks {
            (fs[0], fs[1])
        } else {
            (fs[1], fs[0])
        };
        let c = s.opposite(f0, a, b);
        let d = s.opposite(f1, a, b);
        if c == d
            || touched[c as usize]
            || touched[d as usize]
            || topo.edges.contains_key(&key(c, d))
        {
            continue;
        }
        // Whether (c, a, b) and (d, b, a) are ears (asked for ear flips only).
        let ears =
            (flip == Flip::Ear).then(|| (is_ear(s, &topo, c, a, b), is_ear(s, &topo, d, a, b)));
        let wanted = match flip {
            Flip::Valence => {
                let before = deviation(a, valence[a as usize])
                    + deviation(b, valence[b as usize])
                    + deviation(c, valence[c as usize])
                    + deviation(d, valence[d as usize]);
                let after = deviation(a, valence[a as usize] - 1)
                    + deviation(b, valence[b as usize] - 1)
                    + deviation(c, valence[c as usize] + 1)
                    + deviation(d, valence[d as usize] + 1);
                after < before
            }
            Flip::Delaunay => {
                let angle = |at: u32| {
                    let p = s.pos[at as usize];
                    (s.pos[a as usize] - p).angle(&(s.pos[b as usize] - p))
                };
                angle(c) + angle(d) > std::f64::consts::PI + DELAUNAY_SLACK
            }
            // Exactly one of the two an ear: two ears across a chord would join two crease
            // vertices across their region.
            Flip::Ear => ears.is_some_and(|(x, y)| x != y),
        };
        if !wanted {
            continue;
        }
        // f0 = (a, b, c), f1 = (b, a, d) -> (c, a, d) and (d, b, c).
        let (n0, n1) = ([c, a, d], [d, b, c]);
        let unit = |f: u32| s.normal(&s.tris[f as usize]).normalize();
        let old = match ears {
            // An ear's own normal is no guide (a sliver, perhaps inside out).
            Some((true, _)) => unit(f1),
            Some(_) => unit(f0),
            None => (unit(f0) + unit(f1)).normalize(),
        };
        let ok = [n0, n1].iter().all(|t| {
            let n = s.normal(t);
            n.norm() > 0.0 && n.dot(&old) > 0.9 * n.norm()
        });
        if !ok || rules.too_curved(s, c, d, On::Region(s.labels[f0 as usize])) {
            continue;
        }
        s.tris[f0 as usize] = n0;
        s.tris[f1 as usize] = n1;
        for v in [a, b, c, d] {
            touched[v as usize] = true;
        }
        count += 1;
    }
    count
}

/// Whether the triangle (x, a, b) is an ear at x (module doc): x a crease vertex whose edges to
/// a and to b both lie on its crease.
fn is_ear(s: &State, topo: &Topo, x: u32, a: u32, b: u32) -> bool {
    if topo.kind[x as usize] != Kind::Crease {
        return false;
    }
    let on = |w: u32| {
        topo.edges
            .get(&key(x, w))
            .filter(|fs| s.is_crease(fs))
            .map(|fs| match s.edge_on(fs) {
                On::Crease(k) => k,
                On::Region(l) => (l, l),
            })
    };
    matches!((on(a), on(b)), (Some(p), Some(q)) if p == q)
}
