//! Edge collapses: a vertex merged into a neighbour under the rules of the module doc of
//! [`super`] (corners stay, a crease vertex moves along its crease only, the link condition,
//! no triangle turned by more than 45 degrees, no edge made too long or too curved).

use super::cleanup::is_sliver;
use super::{key, Kind, Rules, State, Topo, NONE};

/// Collapses edges shorter than 4/5 L, shortest first, where the rules of the module doc allow.
pub(super) fn collapse_short(s: &mut State, rules: &Rules) -> usize {
    let topo = s.topo();
    let mut short: Vec<((u32, u32), f64)> = topo
        .edges
        .keys()
        .map(|&(a, b)| ((a, b), s.len(a, b)))
        .filter(|&((a, b), l)| l < 0.8 * rules.edge_target(s, a, b))
        .collect();
    short.sort_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)));
    let mut touched = vec![false; s.pos.len()];
    let mut count = 0;
    for ((a, b), _) in short {
        if touched[a as usize] || touched[b as usize] {
            continue;
        }
        let changed = collapse_first(
            s,
            &topo,
            less_constrained_first(&topo, a, b),
            rules,
            Purpose::Remesh,
        );
        if changed.is_empty() {
            continue;
        }
        for v in changed {
            touched[v as usize] = true;
        }
        count += 1;
    }
    count
}

/// The two ways of collapsing edge (a, b), the less constrained end ([`Kind`]) going first.
pub(super) fn less_constrained_first(topo: &Topo, a: u32, b: u32) -> [(u32, u32); 2] {
    if topo.kind[a as usize] <= topo.kind[b as usize] {
        [(a, b), (b, a)]
    } else {
        [(b, a), (a, b)]
    }
}

/// The collapses of `x` onto `a` and onto `b`, the nearer first.
pub(super) fn nearer_first(s: &State, x: u32, a: u32, b: u32) -> [(u32, u32); 2] {
    if s.len(x, b) < s.len(x, a) {
        [(x, b), (x, a)]
    } else {
        [(x, a), (x, b)]
    }
}

/// Makes the first of the (gone, kept) collapses `tries` that [`may_collapse`] allows; returns
/// the vertices whose one-ring changed (empty: none allowed).
pub(super) fn collapse_first(
    s: &mut State,
    topo: &Topo,
    tries: [(u32, u32); 2],
    rules: &Rules,
    purpose: Purpose,
) -> Vec<u32> {
    tries
        .into_iter()
        .find(|&(g, k)| may_collapse(s, topo, g, k, rules, purpose))
        .map_or_else(Vec::new, |(g, k)| collapse(s, topo, g, k))
}

/// Merges `gone` into `kept`: the triangles on their edge die, the others of `gone` take
/// `kept`. Returns the vertices whose one-ring changed (both ends and their neighbours).
fn collapse(s: &mut State, topo: &Topo, gone: u32, kept: u32) -> Vec<u32> {
    let changed: Vec<u32> = topo
        .neighbours(s, gone)
        .into_iter()
        .chain(topo.neighbours(s, kept))
        .chain([gone, kept])
        .collect();
    for &f in &topo.vfaces[gone as usize] {
        let t = &mut s.tris[f as usize];
        if t.contains(&kept) {
            s.alive[f as usize] = false;
        } else {
            for v in t.iter_mut() {
                if *v == gone {
                    *v = kept;
                }
            }
        }
    }
    changed
}

/// What a collapse is for, which sets the rules it keeps.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Purpose {
    /// The remeshing's: no edge made longer than 4/3 of its target.
    Remesh,
    /// The clean-up of slivers ([`super::cleanup`]): edges of any length, and a sliver's
    /// turn judged against its vertex's one-ring.
    Sliver,
    /// The clean-up of a crease's hairpin ([`super::cleanup`]): as for a sliver, and the
    /// crease vertex `gone` may fold its other crease edge onto the triangle it spans with
    /// them (the hairpin's ear, which the collapse removes), and may leave a sliver along the
    /// straightened crease.
    Hairpin,
    /// The clean-up of a crease's jog ([`super::cleanup`]): as for a sliver, and the new
    /// edges may stray from the input by the collapsed edge's length more than the
    /// tolerances allow (the input crease has the jog too: it is the step being removed).
    Jog,
}

/// Whether `gone` may collapse onto `kept` (module doc) for `purpose`.
pub(super) fn may_collapse(
    s: &State,
    topo: &Topo,
    gone: u32,
    kept: u32,
    rules: &Rules,
    purpose: Purpose,
) -> bool {
    let fs = topo.edges[&key(gone, kept)];
    let crease_edge = s.is_crease(&fs);
    match topo.kind[gone as usize] {
        Kind::Corner => return false,
        Kind::Crease => {
            if !crease_edge || topo.kind[kept as usize] == Kind::Smooth {
                return false;
            }
        }
        Kind::Smooth => {}
    }
    // Link condition: the common neighbours are the vertices opposite the edge.
    let opposite: Vec<u32> = fs
        .iter()
        .filter(|&&f| f != NONE)
        .map(|&f| s.opposite(f, gone, kept))
        .collect();
    let ng = topo.neighbours(s, gone);
    let nk = topo.neighbours(s, kept);
    let common = ng.iter().filter(|v| nk.binary_search(v).is_ok()).count();
    if common != opposite.len() {
        return false;
    }
    // A crease vertex's other crease edge must not fold onto an edge of a triangle it spans.
    if purpose != Purpose::Hairpin
        && topo.kind[gone as usize] == Kind::Crease
        && topo
            .crease_neighbours(s, gone)
            .iter()
            .any(|w| *w != kept && opposite.contains(w))
    {
        return false;
    }
    let pk = s.pos[kept as usize];
    let cos_max_turn = std::f64::consts::FRAC_1_SQRT_2;
    for &f in &topo.vfaces[gone as usize] {
        let t = s.tris[f as usize];
        if t.contains(&kept) {
            continue;
        }
        // In the clean-up, a sliver's own normal is no guide: it is judged against the
        // area-weighted normal of `gone`'s one-ring instead.
        let old = if purpose != Purpose::Remesh && is_sliver(s, &t) {
            topo.vfaces[gone as usize]
                .iter()
                .map(|&h| s.normal(&s.tris[h as usize]))
                .sum()
        } else {
            s.normal(&t)
        };
        let moved = t.map(|v| if v == gone { kept } else { v });
        let new = s.normal(&moved);
        // Undoing a hairpin may leave a sliver along the straightened crease for the next
        // pass of the clean-up, not a fold.
        let sliver_left = purpose == Purpose::Hairpin && is_sliver(s, &moved);
        if !sliver_left && new.dot(&old) <= cos_max_turn * new.norm() * old.norm() {
            return false;
        }
        if purpose == Purpose::Remesh
            && t.iter().any(|&v| {
                v != gone
                    && (s.pos[v as usize] - pk).norm() > 4.0 / 3.0 * rules.edge_target(s, kept, v)
            })
        {
            return false;
        }
    }
    // No new edge too curved for the tolerance: (kept, x) for every neighbour x of gone,
    // on the crease where it replaces a crease edge of gone, else inside its triangles' region.
    if rules.crease_tolerance.is_some() {
        let allowance = if purpose == Purpose::Jog {
            s.len(gone, kept)
        } else {
            0.0
        };
        for &x in &ng {
            if x == kept || opposite.contains(&x) {
                continue;
            }
            let on = s.edge_on(&topo.edges[&key(gone, x)]);
            if rules.too_curved_by(s, kept, x, on, allowance) {
                return false;
            }
        }
    }
    true
}
