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
//!   crease is allowed here (the next pass removes it), a folded one is not;
//! - likewise a crease *jog*: a crease vertex whose two crease edges meet at under [`JOG_DEG`]
//!   with the shorter of them under [`JOG_LENGTH`] of its target length (the extracted crease
//!   stepping sideways by a fraction of a voxel, e.g. 0.06 mm on hexnut.stl's vertical edges
//!   at a 0.9 mm target, in a Z of two such bends: its two thin triangles fold in the net).
//!   The vertex is not pinned (its crease turns by under [`super::PIN_TURN_DEG`] on the scale
//!   of a few edges), so the bend is the short edge's, not the part's.
//!
//! The collapses keep the rules of [`super::collapse`] (corners stay, crease vertices move along
//! their crease, the link condition, no triangle turned over, no edge too curved for the
//! tolerance) except the 4/3 L bound on the edges they lengthen.

use super::collapse::{collapse_first, less_constrained_first, nearer_first, Purpose};
use super::flips::{flip_edges, Flip};
use super::reference::Reference;
use super::{compact, crease_edges, crease_turns, validate, LabelledMesh, MIN_FRACTION};
use super::{key, Kind, On, Rules, State, Topo, NONE};
use crate::error::Result;
use nalgebra::Vector3;

/// A triangle with an angle under this (or over 180 less this) is a sliver, degrees.
pub const SLIVER_DEG: f64 = 5.0;

/// A cap's flip may turn its new triangles by at most this from the local normal, degrees.
pub const FLIP_TURN_DEG: f64 = 45.0;

/// A crease vertex whose two crease edges meet at less than this is a hairpin, degrees.
pub const HAIRPIN_DEG: f64 = 60.0;

/// A crease vertex whose two crease edges meet at less than this, the shorter under
/// [`JOG_LENGTH`] of its target, is a jog, degrees.
pub const JOG_DEG: f64 = 120.0;

/// The longest crease edge of a jog, as a fraction of its target length.
pub const JOG_LENGTH: f64 = 0.25;

/// Passes of [`clean_slivers`] at most.
const PASSES: usize = 8;

/// Whether triangle `t` is a sliver: an angle under [`SLIVER_DEG`] (or over
/// 180 degrees less that), so that its normal is no guide to its region's.
pub(super) fn is_sliver(s: &State, t: &[u32; 3]) -> bool {
    let area2 = s.normal(t).norm();
    let [a, b, c] = *t;
    let (la, lb, lc) = (s.len(b, c), s.len(c, a), s.len(a, b));
    // 2 area = l1 l2 sin(angle between them), for the angle at each vertex.
    let sin_min = [lb * lc, lc * la, la * lb]
        .into_iter()
        .map(|p| if p > 0.0 { area2 / p } else { 0.0 })
        .fold(f64::INFINITY, f64::min);
    sin_min < SLIVER_DEG.to_radians().sin()
}

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

/// Removes the slivers of a mesh that was not remeshed here (module doc), e.g. a remeshed one
/// whose vertices were moved afterwards: `target` is its edge length (the collapses' shortest
/// edge, L / [`super::MIN_FRACTION`], hangs on it), `crease_tolerance` the largest chord error
/// a collapse may leave on a crease (against `mesh` itself). Returns the cleaned mesh and the
/// repairs made.
pub fn clean(
    mesh: &LabelledMesh,
    target: f64,
    crease_tolerance: Option<f64>,
) -> Result<(LabelledMesh, usize)> {
    validate(mesh, target)?;
    let mut s = State::new(mesh);
    let topo = s.topo();
    let creases = crease_edges(&s, &topo);
    let edges = creases.iter().map(|c| c.0);
    for v in crease_turns(&s, &topo, edges, true, JOG_LENGTH * target) {
        s.pinned[v as usize] = true;
    }
    let reference = Reference::new(&mesh.positions, &mesh.triangles, &mesh.labels, &creases);
    let rules = Rules {
        target,
        sizing: None,
        min: target / MIN_FRACTION,
        crease_tolerance,
        reference: &reference,
    };
    let total = clean_and_flip(&mut s, &rules);
    Ok((compact(&s), total))
}

/// The remesh's last step and [`clean`]'s: slivers removed and ears flipped, in turn, until
/// a round changes nothing (at most four). Returns the repairs and flips made.
pub(super) fn clean_and_flip(s: &mut State, rules: &Rules) -> usize {
    let mut total = 0;
    for _ in 0..4 {
        let n = clean_slivers(s, rules) + flip_edges(s, rules, Flip::Ear);
        total += n;
        if n == 0 {
            break;
        }
    }
    total
}

/// One pass: every hairpin, then every sliver, whose vertices no earlier repair of the pass
/// touched.
fn clean_pass(s: &mut State, rules: &Rules) -> usize {
    let topo = s.topo();
    let mut touched = vec![false; s.pos.len()];
    let mut count = 0;
    // Marks the vertices a repair changed; whether it made one.
    let mut made = |changed: Vec<u32>, touched: &mut Vec<bool>| {
        for &v in &changed {
            touched[v as usize] = true;
        }
        count += usize::from(!changed.is_empty());
    };
    for x in 0..s.pos.len() as u32 {
        if topo.kind[x as usize] == Kind::Crease && !touched[x as usize] {
            made(undo_hairpin_or_jog(s, &topo, rules, x), &mut touched);
        }
    }
    for f in 0..s.tris.len() as u32 {
        let t = s.tris[f as usize];
        if s.alive[f as usize] && !t.iter().any(|&v| touched[v as usize]) && is_sliver(s, &t) {
            made(repair(s, &topo, rules, f), &mut touched);
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
        return collapse_first(s, topo, nearer_first(s, x, a, b), rules, Purpose::Sliver);
    }
    // A needle: its shortest edge (the one opposite its smallest angle) goes.
    let narrowest = (0..3)
        .min_by(|&i, &j| angles[i].total_cmp(&angles[j]))
        .unwrap_or(0);
    let (a, b) = (t[(narrowest + 1) % 3], t[(narrowest + 2) % 3]);
    let tries = less_constrained_first(topo, a, b);
    collapse_first(s, topo, tries, rules, Purpose::Sliver)
}

/// Collapses crease vertex `x` onto the nearer crease neighbour (else the farther) where its
/// crease turns back on itself, its two crease edges meeting at under [`HAIRPIN_DEG`]: the
/// extracted crease overshooting a corner and coming back, a region's triangle folded into
/// the hairpin; or where it jogs (under [`JOG_DEG`] with an edge under [`JOG_LENGTH`] of its
/// target). Returns the vertices whose one-ring changed.
fn undo_hairpin_or_jog(s: &mut State, topo: &Topo, rules: &Rules, x: u32) -> Vec<u32> {
    let ends = topo.crease_neighbours(s, x);
    let [u, w] = ends[..] else {
        return Vec::new();
    };
    let p = s.pos[x as usize];
    let angle = (s.pos[u as usize] - p).angle(&(s.pos[w as usize] - p));
    let short = [u, w]
        .iter()
        .any(|&v| s.len(x, v) < JOG_LENGTH * rules.edge_target(s, x, v));
    let purpose = if angle < HAIRPIN_DEG.to_radians() {
        Purpose::Hairpin
    } else if angle < JOG_DEG.to_radians() && short {
        Purpose::Jog
    } else {
        return Vec::new();
    };
    collapse_first(s, topo, nearer_first(s, x, u, w), rules, purpose)
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

    // Vertex names of the floor-and-wall meshes: the crease c0 - c1 - c2 on the x axis, the
    // floor's far side i0 i1 i2 (y = 1), the wall's top w0 w1 w2 (z = 1), and a vertex v3.
    const C0: u32 = 0;
    const C1: u32 = 1;
    const C2: u32 = 2;
    const V3: u32 = 3;
    const I0: u32 = 4;
    const I1: u32 = 5;
    const I2: u32 = 6;
    const W0: u32 = 7;
    const W1: u32 = 8;
    const W2: u32 = 9;

    /// A floor (region 0, z = 0, y in [0, 1], facing +z) and a wall (region 1, y = 0, facing
    /// +y) meeting along the x axis, vertex 3 at `v3`, with the given triangles (floor first).
    fn floor_and_wall(v3: Point3<f64>, floor: &[[u32; 3]], wall: &[[u32; 3]]) -> LabelledMesh {
        let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
        let mut positions = vec![p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(2.0, 0.0, 0.0), v3];
        positions.extend([0.0, 1.0, 2.0].map(|x| p(x, 1.0, 0.0)));
        positions.extend([0.0, 1.0, 2.0].map(|x| p(x, 0.0, 1.0)));
        LabelledMesh {
            positions,
            triangles: floor.iter().chain(wall).copied().collect(),
            labels: floor
                .iter()
                .map(|_| 0)
                .chain(wall.iter().map(|_| 1))
                .collect(),
        }
    }

    /// Cleans `m` and checks that something was done, no sliver is left, the floor still faces
    /// +z and the wall +y, and `crease` is still a crease edge; returns the live triangles.
    fn clean(m: &LabelledMesh, crease: (u32, u32)) -> Vec<[u32; 3]> {
        let (state, live) = cleaned(m, None);
        assert!(is_crease_edge(&state, crease), "crease {crease:?} lost");
        live
    }

    /// Whether `e` is a crease edge of `state`.
    fn is_crease_edge(state: &State, e: (u32, u32)) -> bool {
        let topo = state.topo();
        let fs = topo.edges.get(&key(e.0, e.1));
        fs.is_some_and(|fs| state.is_crease(fs))
    }

    /// Cleans `m` with the crease tolerance given; returns the state and the repairs made.
    fn clean_count(m: &LabelledMesh, crease_tolerance: Option<f64>) -> (State, usize) {
        let mut state = State::new(m);
        let creases = super::super::crease_edges(&state, &state.topo());
        let reference = Reference::new(&m.positions, &m.triangles, &m.labels, &creases);
        let rules = Rules {
            target: 1.0,
            sizing: None,
            min: 1.0 / 16.0,
            crease_tolerance,
            reference: &reference,
        };
        let count = clean_slivers(&mut state, &rules);
        (state, count)
    }

    /// Cleans `m` (with the crease tolerance given) and checks that something was done, no
    /// sliver is left, the floor still faces +z and the wall +y; returns the state and its
    /// live triangles.
    fn cleaned(m: &LabelledMesh, crease_tolerance: Option<f64>) -> (State, Vec<[u32; 3]>) {
        let (state, count) = clean_count(m, crease_tolerance);
        assert!(count > 0);
        let mut live = Vec::new();
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
            live.push(*t);
        }
        (state, live)
    }

    /// The floor with the smooth vertex v3 near the crease edge c1 - c2, over which it has the
    /// triangle (c1, c2, v3).
    const FLOOR: [[u32; 3]; 6] = [
        [C0, C1, I1],
        [C0, I1, I0],
        [C1, C2, V3],
        [C1, V3, I1],
        [V3, C2, I2],
        [V3, I2, I1],
    ];
    const WALL: [[u32; 3]; 4] = [[C1, C0, W0], [C1, W0, W1], [C2, C1, W1], [C2, W1, W2]];

    /// The floor and the wall with v3 a crease vertex: the crease c0 - c1 - v3 - c2.
    const CREASE_FLOOR: [[u32; 3]; 5] = [
        [C0, C1, I1],
        [C0, I1, I0],
        [V3, I1, C1],
        [V3, I2, I1],
        [V3, C2, I2],
    ];
    const CREASE_WALL: [[u32; 3]; 5] = [
        [C1, C0, W0],
        [C1, W0, W1],
        [V3, C1, W1],
        [V3, W1, W2],
        [C2, V3, W2],
    ];

    #[test]
    fn a_smooth_vertex_on_a_crease_edge_is_collapsed() {
        // v3 on the crease edge c1 - c2: the cap (c1, c2, v3) at 179.9 degrees.
        let m = floor_and_wall(Point3::new(1.5, 0.001, 0.0), &FLOOR, &WALL);
        let live = clean(&m, (C1, C2));
        assert_eq!(live.len(), 8, "the cap and one triangle of v3 go");
        assert!(live.iter().all(|t| !t.contains(&V3)));
    }

    #[test]
    fn a_smooth_vertex_beside_a_crease_vertex_is_collapsed() {
        // v3 0.02 from c1: the needle (c1, c2, v3) and the cap (c1, v3, i1).
        let m = floor_and_wall(Point3::new(1.0, 0.02, 0.0), &FLOOR, &WALL);
        let live = clean(&m, (C1, C2));
        assert!(live.iter().all(|t| !t.contains(&V3)));
    }

    #[test]
    fn a_crease_hairpin_is_undone() {
        // The crease c0 - c1 - v3 - c2 runs past its end c2 to v3 (x = 2.2) and comes back:
        // the floor's triangle (v3, c2, i2) and the wall's (c2, v3, w2) are turned over.
        let m = floor_and_wall(Point3::new(2.2, 0.0, 0.0), &CREASE_FLOOR, &CREASE_WALL);
        let live = clean(&m, (C1, C2));
        assert!(live.iter().all(|t| !t.contains(&V3)), "the hairpin is left");
    }

    #[test]
    fn a_crease_jog_is_straightened() {
        // The crease c0 - c1 - v3 - c2 steps 0.06 up the wall at x = 1 (a Z of two 90-degree
        // bends on an edge of a twentieth of the target): the floor's triangle (v3, i1, c1)
        // stands upright, and the wall's (v3, c1, w1) is a needle. The input crease has the
        // step too, farther from the straightened crease than the tolerance 0.01: only the
        // jog's allowance lets the collapse through.
        let m = floor_and_wall(Point3::new(1.0, 0.0, 0.06), &CREASE_FLOOR, &CREASE_WALL);
        let (state, live) = cleaned(&m, Some(0.01));
        let kept: Vec<u32> = [C1, V3]
            .into_iter()
            .filter(|v| live.iter().any(|t| t.contains(v)))
            .collect();
        assert_eq!(kept.len(), 1, "the jog's short edge is left");
        assert!(is_crease_edge(&state, (C0, kept[0])));
        assert!(is_crease_edge(&state, (kept[0], C2)));
        // A step longer than a quarter of the target is the part's, not a jog: left alone
        // (no triangle is a sliver, so no other rule applies either).
        let m = floor_and_wall(Point3::new(1.1, 0.0, 0.3), &CREASE_FLOOR, &CREASE_WALL);
        assert_eq!(clean_count(&m, Some(0.01)).1, 0);
    }
}
