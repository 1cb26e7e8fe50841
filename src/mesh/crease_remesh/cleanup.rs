//! Clean-up of the slivers the last relaxation leaves (issue 36: their quads fold or
//! degenerate in the net).
//!
//! The tangential relaxation pulls a smooth vertex towards the centroid of its neighbours; where
//! most of them lie on a crease (a crease vertex with a single interior neighbour on one side) it
//! ends up on the crease itself, between two crease vertices or on top of one, and its triangles
//! spanning the crease edges have an angle near 180 degrees (a *cap*) or near 0 (a *needle*).
//! No length rule flags them, so the remeshing's collapses and flips leave them. Here, while any
//! is left (a sliver: an angle under [`SLIVER_DEG`] or over 180 less that):
//! - a cap (x, a, b) with its angle at x over the opposite edge a - b: that edge, if inside a
//!   region, is flipped to x - d (d across it), when both new triangles face within
//!   [`FLIP_TURN_DEG`] of the area-weighted normal of the four vertices' triangles (the cap's own
//!   normal is no guide); if a - b is a crease edge and x a smooth vertex, x is collapsed onto the
//!   nearer of a and b (a crease vertex x is an ear: [`super::flips`]);
//! - a needle: its shortest edge is collapsed, the less constrained end going;
//! - before them, a crease *hairpin*: a crease vertex whose two crease edges meet at under
//!   [`HAIRPIN_DEG`] (the extracted crease overshooting a corner by a fraction of a voxel and
//!   coming back, a triangle of each region turned over in the bend) is collapsed onto its
//!   nearer crease neighbour; such a vertex is not pinned as a turn of the crease
//!   (`crease_turns` in [`super`]). A new triangle that is a sliver along the straightened
//!   crease is allowed here (the next pass removes it), a folded one is not.
//!
//! The collapses keep the rules of [`super::collapse`] (corners stay, crease vertices move along
//! their crease, the link condition, no triangle turned over, no edge too curved for the
//! tolerance) except the 4/3 L bound on the edges they lengthen.

use super::collapse::{collapse, is_sliver, may_collapse, Lengths};
use super::{key, Kind, On, Rules, State, Topo, NONE};
use nalgebra::Vector3;

/// A triangle with an angle under this (or over 180 less this) is a sliver, degrees.
pub const SLIVER_DEG: f64 = 5.0;

/// A cap's flip may turn its new triangles by at most this from the local normal, degrees.
pub const FLIP_TURN_DEG: f64 = 45.0;

/// A crease vertex whose two crease edges meet at less than this is a hairpin, degrees.
pub const HAIRPIN_DEG: f64 = 60.0;

/// Passes of [`clean_slivers`] at most.
const PASSES: usize = 8;

/// Removes slivers (module doc) until none is left that a rule can remove, at most [`PASSES`]
/// passes. Returns the flips and collapses made.
pub(super) fn clean_slivers(s: &mut State, rules: &Rules) -> usize {
    let mut total = 0;
    for _ in 0..PASSES {
        let n = clean_pass(s, rules);
        total += n;
        if n == 0 {
            break;
        }
    }
    total
}

/// One pass: every sliver whose vertices no earlier repair of the pass touched.
fn clean_pass(s: &mut State, rules: &Rules) -> usize {
    let topo = s.topo();
    let mut touched = vec![false; s.pos.len()];
    let mut count = 0;
    for x in 0..s.pos.len() as u32 {
        if topo.kind[x as usize] != Kind::Crease || touched[x as usize] {
            continue;
        }
        let changed = unpin_hairpin(s, &topo, rules, x);
        if !changed.is_empty() {
            for v in changed {
                touched[v as usize] = true;
            }
            count += 1;
        }
    }
    for f in 0..s.tris.len() as u32 {
        let t = s.tris[f as usize];
        if !s.alive[f as usize] || t.iter().any(|&v| touched[v as usize]) || !is_sliver(s, &t) {
            continue;
        }
        let changed = repair(s, &topo, rules, f);
        if !changed.is_empty() {
            for v in changed {
                touched[v as usize] = true;
            }
            count += 1;
        }
    }
    count
}

/// Repairs sliver `f` by a flip or a collapse (module doc); returns the vertices whose
/// one-ring changed (empty: no rule applied).
fn repair(s: &mut State, topo: &Topo, rules: &Rules, f: u32) -> Vec<u32> {
    let t = s.tris[f as usize];
    let p = t.map(|v| s.pos[v as usize]);
    let angle = |i: usize| (p[(i + 1) % 3] - p[i]).angle(&(p[(i + 2) % 3] - p[i]));
    let angles = [angle(0), angle(1), angle(2)];
    let widest = (0..3)
        .max_by(|&i, &j| angles[i].total_cmp(&angles[j]))
        .unwrap_or(0);
    if angles[widest] > std::f64::consts::PI - SLIVER_DEG.to_radians() {
        // A cap at x over a -> b (t walks x, a, b).
        let (x, a, b) = (t[widest], t[(widest + 1) % 3], t[(widest + 2) % 3]);
        let fs = topo.edges[&key(a, b)];
        if !s.is_crease(&fs) {
            return flip_cap(s, topo, rules, f, x, a, b);
        }
        if topo.kind[x as usize] != Kind::Smooth {
            return Vec::new();
        }
        let mut ends = [a, b];
        ends.sort_by(|&u, &w| s.len(x, u).total_cmp(&s.len(x, w)));
        return ends
            .into_iter()
            .find(|&k| may_collapse(s, topo, x, k, rules, Lengths::Free))
            .map_or_else(Vec::new, |k| collapse(s, topo, x, k));
    }
    // A needle: its shortest edge (the one opposite its smallest angle) goes.
    let narrowest = (0..3)
        .min_by(|&i, &j| angles[i].total_cmp(&angles[j]))
        .unwrap_or(0);
    let (a, b) = (t[(narrowest + 1) % 3], t[(narrowest + 2) % 3]);
    let tries = if topo.kind[a as usize] <= topo.kind[b as usize] {
        [(a, b), (b, a)]
    } else {
        [(b, a), (a, b)]
    };
    tries
        .into_iter()
        .find(|&(g, k)| may_collapse(s, topo, g, k, rules, Lengths::Free))
        .map_or_else(Vec::new, |(g, k)| collapse(s, topo, g, k))
}

/// Collapses crease vertex `x` onto the nearer crease neighbour (else the farther) where its
/// crease turns back on itself, its two crease edges meeting at under [`HAIRPIN_DEG`]: the
/// extracted crease overshooting a corner and coming back, a region's triangle folded into
/// the hairpin. Returns the vertices whose one-ring changed.
fn unpin_hairpin(s: &mut State, topo: &Topo, rules: &Rules, x: u32) -> Vec<u32> {
    let ends = topo.crease_neighbours(s, x);
    let [u, w] = ends[..] else {
        return Vec::new();
    };
    let p = s.pos[x as usize];
    if (s.pos[u as usize] - p).angle(&(s.pos[w as usize] - p)) >= HAIRPIN_DEG.to_radians() {
        return Vec::new();
    }
    let mut ends = [u, w];
    ends.sort_by(|&a, &b| s.len(x, a).total_cmp(&s.len(x, b)));
    ends.into_iter()
        .find(|&k| may_collapse(s, topo, x, k, rules, Lengths::Hairpin))
        .map_or_else(Vec::new, |k| collapse(s, topo, x, k))
}

/// Flips the edge a - b of cap `f` = (x, a, b) to x - d (module doc).
fn flip_cap(s: &mut State, topo: &Topo, rules: &Rules, f: u32, x: u32, a: u32, b: u32) -> Vec<u32> {
    let fs = topo.edges[&key(a, b)];
    let g = if fs[0] == f { fs[1] } else { fs[0] };
    if g == NONE {
        return Vec::new();
    }
    let d = s.opposite(g, a, b);
    if d == x || topo.edges.contains_key(&key(x, d)) {
        return Vec::new();
    }
    // f walks x -> a -> b, g walks b -> a -> d: the new (x, a, d) and (d, b, x).
    let new = [[x, a, d], [d, b, x]];
    let local: Vector3<f64> = [x, a, b, d]
        .iter()
        .flat_map(|&v| topo.vfaces[v as usize].iter())
        .map(|&h| s.normal(&s.tris[h as usize]))
        .sum();
    let cos_max = FLIP_TURN_DEG.to_radians().cos();
    let ok = new.iter().all(|t| {
        let n = s.normal(t);
        !is_sliver(s, t) && n.dot(&local) > cos_max * n.norm() * local.norm()
    });
    if !ok || rules.too_curved(s, x, d, On::Region(s.labels[f as usize])) {
        return Vec::new();
    }
    s.tris[f as usize] = new[0];
    s.tris[g as usize] = new[1];
    vec![x, a, b, d]
}

#[cfg(test)]
mod tests {
    use super::super::reference::Reference;
    use super::super::LabelledMesh;
    use super::*;
    use nalgebra::Point3;

    /// A floor (region 0, z = 0, y in [0, 1]) and a wall (region 1, y = 0) meeting along the
    /// crease c0 - c1 - c2 on the x axis, with the floor's vertex `s` (index 3) at `s`.
    fn floor_and_wall(s: Point3<f64>) -> (State, LabelledMesh) {
        let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
        // c0 c1 c2 s i0 i1 i2 w0 w1 w2
        let pos = vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(2.0, 0.0, 0.0),
            s,
            p(0.0, 1.0, 0.0),
            p(1.0, 1.0, 0.0),
            p(2.0, 1.0, 0.0),
            p(0.0, 0.0, 1.0),
            p(1.0, 0.0, 1.0),
            p(2.0, 0.0, 1.0),
        ];
        let (c0, c1, c2, sv, i0, i1, i2, w0, w1, w2) = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9);
        let tris = vec![
            [c0, c1, i1],
            [c0, i1, i0],
            [c1, c2, sv],
            [c1, sv, i1],
            [sv, c2, i2],
            [sv, i2, i1],
            [c1, c0, w0],
            [c1, w0, w1],
            [c2, c1, w1],
            [c2, w1, w2],
        ];
        let labels = vec![0, 0, 0, 0, 0, 0, 1, 1, 1, 1];
        let state = State {
            pos: pos.clone(),
            tris: tris.clone(),
            labels: labels.clone(),
            alive: vec![true; tris.len()],
            pinned: vec![false; pos.len()],
            size: Vec::new(),
        };
        let mesh = LabelledMesh {
            positions: pos,
            triangles: tris,
            labels,
        };
        (state, mesh)
    }

    /// Cleans the floor-and-wall mesh and checks that no sliver is left, the floor still
    /// faces +z and the wall +y, and the crease is still the path c0 - c1 - c2.
    fn cleaned(s: Point3<f64>) -> State {
        let (mut state, m) = floor_and_wall(s);
        let reference = Reference::new(&m.positions, &m.triangles, &m.labels, &[]);
        let rules = Rules {
            target: 1.0,
            sizing: None,
            min: 1.0 / 16.0,
            crease_tolerance: None,
            surface_tolerance: None,
            reference: &reference,
        };
        assert!(clean_slivers(&mut state, &rules) > 0);
        for (f, t) in state.tris.iter().enumerate() {
            if !state.alive[f] {
                continue;
            }
            assert!(!is_sliver(&state, t), "sliver {t:?} left");
            let n = state.normal(t).normalize();
            let want = if state.labels[f] == 0 {
                Vector3::z()
            } else {
                Vector3::y()
            };
            assert!(n.dot(&want) > 0.99, "triangle {t:?} faces {n:?}");
        }
        let topo = state.topo();
        for (a, b) in [(0, 1), (1, 2)] {
            let fs = topo.edges.get(&key(a, b)).expect("crease edge kept");
            assert!(state.is_crease(fs));
        }
        state
    }

    #[test]
    fn a_smooth_vertex_on_a_crease_edge_is_collapsed() {
        // s on the crease edge c1 - c2: the cap (c1, c2, s) at 179.9 degrees.
        let state = cleaned(Point3::new(1.5, 0.001, 0.0));
        let alive = state.alive.iter().filter(|&&a| a).count();
        assert_eq!(alive, 8, "the cap and one triangle of s go");
        assert!(state
            .tris
            .iter()
            .zip(&state.alive)
            .all(|(t, &a)| !a || !t.contains(&3)));
    }

    #[test]
    fn a_smooth_vertex_beside_a_crease_vertex_is_collapsed() {
        // s 0.02 from c1: the needle (c1, c2, s) and the cap (c1, s, i1).
        let state = cleaned(Point3::new(1.0, 0.02, 0.0));
        assert!(state
            .tris
            .iter()
            .zip(&state.alive)
            .all(|(t, &a)| !a || !t.contains(&3)));
    }

    #[test]
    fn a_crease_hairpin_is_undone() {
        // The crease c0 - c1 - h - c2 runs past its end c2 to h and comes back: the floor's
        // triangle (h, c2, i2) and the wall's (c2, h, w2) are turned over.
        let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
        // c0 c1 h c2 i0 i1 i2 w0 w1 w2
        let pos = vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(2.2, 0.0, 0.0),
            p(2.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(1.0, 1.0, 0.0),
            p(2.0, 1.0, 0.0),
            p(0.0, 0.0, 1.0),
            p(1.0, 0.0, 1.0),
            p(2.0, 0.0, 1.0),
        ];
        let (c0, c1, h, c2, i0, i1, i2, w0, w1, w2) = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9);
        let tris = vec![
            [c0, c1, i1],
            [c0, i1, i0],
            [h, i1, c1],
            [h, i2, i1],
            [h, c2, i2],
            [c1, c0, w0],
            [c1, w0, w1],
            [h, c1, w1],
            [h, w1, w2],
            [c2, h, w2],
        ];
        let labels = vec![0, 0, 0, 0, 0, 1, 1, 1, 1, 1];
        let mut state = State {
            pos: pos.clone(),
            tris: tris.clone(),
            labels: labels.clone(),
            alive: vec![true; tris.len()],
            pinned: vec![false; pos.len()],
            size: Vec::new(),
        };
        assert_eq!(state.topo().kind[h as usize], Kind::Crease);
        let reference = Reference::new(&pos, &tris, &labels, &[]);
        let rules = Rules {
            target: 1.0,
            sizing: None,
            min: 1.0 / 16.0,
            crease_tolerance: None,
            surface_tolerance: None,
            reference: &reference,
        };
        assert!(clean_slivers(&mut state, &rules) > 0);
        for (f, t) in state.tris.iter().enumerate() {
            if !state.alive[f] {
                continue;
            }
            assert!(!t.contains(&h), "the hairpin's vertex is left in {t:?}");
            let n = state.normal(t).normalize();
            let want = if state.labels[f] == 0 {
                Vector3::z()
            } else {
                Vector3::y()
            };
            assert!(n.dot(&want) > 0.99, "triangle {t:?} faces {n:?}");
        }
        let topo = state.topo();
        let fs = topo.edges.get(&key(c1, c2)).expect("the crease ends at c2");
        assert!(state.is_crease(fs));
    }
}
