//! Isotropic remeshing that keeps a labelled mesh's creases (issue 36: the net from a
//! crease-preserving surface mesh).
//!
//! Botsch & Kobbelt 2004 ("A remeshing approach to multiresolution modeling"), with the
//! target edge length L: each iteration
//! 1. splits every edge longer than 4/3 L at its midpoint,
//! 2. collapses every edge shorter than 4/5 L whose collapse makes no edge longer than 4/3 L,
//! 3. flips edges that bring the valences nearer 6 (4 on an open boundary),
//! 4. moves every vertex to the centroid of its neighbours within its tangent plane,
//! 5. projects it back onto the input;
//!
//! and at the end splits the edges the last relaxation stretched past 4/3 L. Optionally the
//! length is driven by the chord error too (Botsch & Kobbelt's adaptive variant, measured
//! rather than estimated from curvature): an edge whose midpoint lies farther than a tolerance
//! from the input (the input crease, for a crease edge) is split, and no collapse or flip makes
//! one. A circular crease of radius R then gets edges of about sqrt(8 R tolerance), the
//! sagitta L^2 / (8 R) being the chord error. With a grade as well, the target length itself
//! varies: short along curved creases and growing gradually away from them ([`sizing`]), so
//! that the triangles beside such a crease do not fan out to the coarse surface; and the
//! remesh can end with flips to locally Delaunay triangles inside the regions ([`flips`]).
//! It always ends by flipping away the *ears*, slivers between a crease and its chord
//! ([`flips`]), which the relaxation along a curved crease can leave, and optionally by
//! removing the other slivers the relaxation leaves on the creases ([`cleanup`]).
//!
//! The creases are given, not guessed from angles: every triangle carries the region label of
//! the input's segmentation, and an edge between two regions (or on an open boundary) is a
//! crease edge. A vertex with no crease edge is *smooth*, with two a *crease* vertex, and with
//! one or three or more (or where three regions meet, or where the input's crease turns by more
//! than [`PIN_TURN_DEG`] over a few edges, unless the vertex lies within a quarter of L of a
//! corner, with the clean-up on) a *corner*, pinned. The operations keep this structure:
//! - splitting a crease edge gives a crease vertex (the triangles keep their labels);
//! - a corner is never collapsed; a crease vertex only along one of its crease edges onto a
//!   crease vertex or a corner (so the crease stays a path of edges, shortened along itself);
//!   a smooth vertex onto any neighbour; the link condition (the two ends share exactly the
//!   neighbours opposite the edge) keeps the mesh a 2-manifold, and no triangle may turn by
//!   more than 45 degrees;
//! - crease edges are never flipped (so every triangle stays within one region);
//! - a crease vertex moves along its crease only (towards the midpoint of its two crease
//!   neighbours) and is projected onto the input crease between the same two regions; a
//!   smooth vertex onto its region's input triangles.
//!
//! Why by hand: the remeshers of the Rust crates (baby_shark 0.3, remesh 0.0.5) protect
//! features by dihedral angle only, with no way to give the crease edges or pin the corners,
//! and their flips and relaxation cross creases; MeshLab's isotropic remeshing (feature angle
//! 30 degrees) on make_parts' exact block.stl at a 7 mm target left its faces 13 degrees off
//! (p95) and its creases 1.5 % of the diagonal away.

mod cleanup;
pub use cleanup::clean;
mod collapse;
mod flips;
use collapse::collapse_short;
use flips::{flip_edges, flip_to_valence, Flip};
pub mod reference;
pub mod sizing;

use crate::error::{Error, Result};
use nalgebra::{Point3, Vector3};
use reference::{crease_key, Reference, OPEN};
use std::collections::HashMap;

/// An input crease vertex where its crease turns by more than this is pinned, degrees
/// (measured over [`TURN_SCALE`] crease edges each way: [`crease_turns`]).
pub const PIN_TURN_DEG: f64 = 30.0;

/// The length over which a crease's turn is measured, in mean input crease edges.
pub const TURN_SCALE: f64 = 3.0;

/// No face.
const NONE: u32 = u32::MAX;

/// Edges are not split for their chord error below the target length over this.
pub const MIN_FRACTION: f64 = 16.0;

/// The length rules: split above 4/3 of an edge's target length, collapse below 4/5, and the
/// chord error allowed.
struct Rules<'a> {
    target: f64,
    /// The target length by position (`RemeshOptions::grade`), else L everywhere.
    sizing: Option<sizing::Sizing>,
    min: f64,
    crease_tolerance: Option<f64>,
    reference: &'a Reference,
}

impl Rules<'_> {
    /// Sets the target length of every vertex (`State::size`; left empty without a sizing
    /// field). Only relaxation and projection move vertices: called after them.
    fn refresh_sizes(&self, s: &mut State) {
        use rayon::prelude::*;
        if let Some(z) = &self.sizing {
            s.size = s.pos.par_iter().map(|p| z.at(p)).collect();
        }
    }

    /// The target length of edge (a, b): the mean of its ends' ([`State::size`]).
    fn edge_target(&self, s: &State, a: u32, b: u32) -> f64 {
        match (s.size.get(a as usize), s.size.get(b as usize)) {
            (Some(x), Some(y)) => 0.5 * (x + y),
            _ => self.target,
        }
    }

    /// How far the midpoint of (a, b) lies from the input: from the crease `crease` when the
    /// edge lies on one, else from the region `label`.
    fn chord_error(&self, s: &State, a: u32, b: u32, on: On) -> f64 {
        let m = nalgebra::center(&s.pos[a as usize], &s.pos[b as usize]);
        let q = match on {
            On::Crease(k) => self.reference.on_crease(k, &m),
            On::Region(l) => self.reference.on_region(l, &m),
        };
        q.map_or(0.0, |q| (q - m).norm())
    }

    /// Whether edge (a, b) lying `on` is too coarse for the tolerance.
    fn too_curved(&self, s: &State, a: u32, b: u32, on: On) -> bool {
        self.too_curved_by(s, a, b, on, 0.0)
    }

    /// [`Self::too_curved`] with the tolerance widened by `allowance`. Only crease edges
    /// are tested against the input; inside a region the sizing field
    /// ([`RemeshOptions::surface_sizing`]) sets the lengths.
    fn too_curved_by(&self, s: &State, a: u32, b: u32, on: On, allowance: f64) -> bool {
        let On::Crease(_) = on else {
            return false;
        };
        self.crease_tolerance.is_some_and(|t| {
            s.len(a, b) > self.min && self.chord_error(s, a, b, on) > t + allowance
        })
    }
}

/// What an edge lies on.
#[derive(Debug, Clone, Copy)]
enum On {
    Crease((u32, u32)),
    Region(u32),
}

/// Options of [`remesh`].
#[derive(Debug, Clone, Copy)]
pub struct RemeshOptions {
    /// Target edge length L.
    pub target: f64,
    /// Iterations of split, collapse, flip, relax and project (default 10).
    pub iterations: usize,
    /// Largest chord error of a crease edge: one whose midpoint lies farther than this from
    /// the input crease between the same two regions is split even when shorter than 4/3 L,
    /// down to L / [`MIN_FRACTION`], and no collapse makes such an edge. A curved crease
    /// (a hole's rim) then gets edges of about sqrt(8 R tolerance). `None` (default): edge
    /// lengths alone.
    pub crease_tolerance: Option<f64>,
    /// Largest chord error inside a region, as a sizing field from the input's curvature
    /// computed once (the [`sizing`] module doc); curved faces get shorter edges. Needs
    /// `grade`. `None` (default): L inside the regions.
    ///
    /// (A test of every region edge's chord against the input triangles, as the crease edges
    /// have, was the first route: on a noisy cloud's mesh, where the labels jog beside a
    /// crease, no split ever met it, and the splits ran down to L / 16 into thousands of
    /// degenerate triangles, 4-40 times slower.)
    pub surface_sizing: Option<f64>,
    /// With a crease tolerance: the target length follows the creases' curvature and grows
    /// by at most this much per unit length away from them ([`sizing`]), so that the
    /// triangles beside a finely split crease do not fan out to the coarse surface. `None`
    /// (default): L everywhere, the chord error alone splitting the crease edges.
    pub grade: Option<f64>,
    /// At the end, flip the edges inside a region that are not locally Delaunay (opposite
    /// angles summing to more than pi), so that fewer triangles are obtuse (default false).
    pub delaunay: bool,
    /// At the very end, remove the slivers (caps and needles) the last relaxation left on the
    /// creases by flips and collapses ([`cleanup`]; default false).
    pub clean_slivers: bool,
}

impl RemeshOptions {
    pub fn new(target: f64) -> Self {
        RemeshOptions {
            target,
            iterations: 10,
            crease_tolerance: None,
            surface_sizing: None,
            grade: None,
            delaunay: false,
            clean_slivers: false,
        }
    }
}

/// A triangle mesh with a region per triangle.
#[derive(Debug, Clone)]
pub struct LabelledMesh {
    pub positions: Vec<Point3<f64>>,
    pub triangles: Vec<[u32; 3]>,
    pub labels: Vec<u32>,
}

/// What a vertex may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Smooth,
    Crease,
    Corner,
}

/// The working mesh: triangles are killed, not removed, until the end.
struct State {
    pos: Vec<Point3<f64>>,
    tris: Vec<[u32; 3]>,
    labels: Vec<u32>,
    alive: Vec<bool>,
    pinned: Vec<bool>,
    /// Target length per vertex with a sizing field ([`Rules::refresh_sizes`]), else empty.
    size: Vec<f64>,
}

/// Adjacency of the live triangles, rebuilt before every pass.
struct Topo {
    /// Undirected edge -> its (one or two) triangles.
    edges: HashMap<(u32, u32), [u32; 2]>,
    /// Vertex -> its triangles.
    vfaces: Vec<Vec<u32>>,
    kind: Vec<Kind>,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl State {
    /// All of `mesh` alive, nothing pinned, no sizes yet.
    fn new(mesh: &LabelledMesh) -> State {
        State {
            pos: mesh.positions.clone(),
            tris: mesh.triangles.clone(),
            labels: mesh.labels.clone(),
            alive: vec![true; mesh.triangles.len()],
            pinned: vec![false; mesh.positions.len()],
            size: Vec::new(),
        }
    }

    fn topo(&self) -> Topo {
        let mut edges: HashMap<(u32, u32), [u32; 2]> = HashMap::new();
        let mut vfaces = vec![Vec::new(); self.pos.len()];
        for (f, t) in self.tris.iter().enumerate() {
            if !self.alive[f] {
                continue;
            }
            for i in 0..3 {
                vfaces[t[i] as usize].push(f as u32);
                let e = edges
                    .entry(key(t[i], t[(i + 1) % 3]))
                    .or_insert([NONE, NONE]);
                if e[0] == NONE {
                    e[0] = f as u32;
                } else {
                    e[1] = f as u32;
                }
            }
        }
        let mut creases = vec![0u32; self.pos.len()];
        let mut regions: Vec<Vec<u32>> = vec![Vec::new(); self.pos.len()];
        for (&(a, b), fs) in &edges {
            if self.is_crease(fs) {
                creases[a as usize] += 1;
                creases[b as usize] += 1;
            }
        }
        for (v, fs) in vfaces.iter().enumerate() {
            for &f in fs {
                let l = self.labels[f as usize];
                if !regions[v].contains(&l) {
                    regions[v].push(l);
                }
            }
        }
        let kind = (0..self.pos.len())
            .map(|v| {
                if self.pinned[v] || regions[v].len() >= 3 {
                    Kind::Corner
                } else {
                    match creases[v] {
                        0 => Kind::Smooth,
                        2 => Kind::Crease,
                        _ => Kind::Corner,
                    }
                }
            })
            .collect();
        Topo {
            edges,
            vfaces,
            kind,
        }
    }

    fn is_crease(&self, fs: &[u32; 2]) -> bool {
        fs[1] == NONE || self.labels[fs[0] as usize] != self.labels[fs[1] as usize]
    }

    /// What the edge with triangles `fs` lies on.
    fn edge_on(&self, fs: &[u32; 2]) -> On {
        let l0 = self.labels[fs[0] as usize];
        if fs[1] == NONE {
            On::Crease(crease_key(l0, OPEN))
        } else if self.is_crease(fs) {
            On::Crease(crease_key(l0, self.labels[fs[1] as usize]))
        } else {
            On::Region(l0)
        }
    }

    fn normal(&self, t: &[u32; 3]) -> Vector3<f64> {
        let [a, b, c] = t.map(|v| self.pos[v as usize]);
        (b - a).cross(&(c - a))
    }

    fn len(&self, a: u32, b: u32) -> f64 {
        (self.pos[a as usize] - self.pos[b as usize]).norm()
    }

    /// The vertex opposite edge (a, b) in triangle f.
    fn opposite(&self, f: u32, a: u32, b: u32) -> u32 {
        let t = self.tris[f as usize];
        t.into_iter().find(|&v| v != a && v != b).unwrap_or(a)
    }
}

impl Topo {
    fn neighbours(&self, s: &State, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> = self.vfaces[v as usize]
            .iter()
            .flat_map(|&f| s.tris[f as usize])
            .filter(|&w| w != v)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// The crease edges' other ends at `v`.
    fn crease_neighbours(&self, s: &State, v: u32) -> Vec<u32> {
        self.neighbours(s, v)
            .into_iter()
            .filter(|&w| self.edges.get(&key(v, w)).is_some_and(|fs| s.is_crease(fs)))
            .collect()
    }

    /// The regions on the two sides of `v`'s crease ([`crease_key`]).
    fn crease_of(&self, s: &State, v: u32) -> (u32, u32) {
        let mut ls: Vec<u32> = self.vfaces[v as usize]
            .iter()
            .map(|&f| s.labels[f as usize])
            .collect();
        ls.sort_unstable();
        ls.dedup();
        crease_key(ls[0], *ls.get(1).unwrap_or(&OPEN))
    }
}

/// Checks that `mesh` can be remeshed at edge length `target`: a label per triangle, a
/// positive target, vertex indices in range, an edge-manifold mesh.
fn validate(mesh: &LabelledMesh, target: f64) -> Result<()> {
    if mesh.labels.len() != mesh.triangles.len() {
        return Err(Error::Degenerate(format!(
            "remesh: {} labels for {} triangles",
            mesh.labels.len(),
            mesh.triangles.len()
        )));
    }
    if !(target.is_finite() && target > 0.0) {
        return Err(Error::InvalidOption(format!(
            "remesh: target edge length {} (positive expected)",
            target
        )));
    }
    if let Some(t) = mesh
        .triangles
        .iter()
        .find(|t| t.iter().any(|&v| v as usize >= mesh.positions.len()))
    {
        return Err(Error::Degenerate(format!(
            "remesh: a triangle names vertex {} of {}",
            t.iter().max().copied().unwrap_or(0),
            mesh.positions.len()
        )));
    }
    check_manifold(mesh)
}

/// Remeshes `mesh` to edges of about `opts.target`, keeping its creases and corners (see the
/// module doc). The input should be finer than the target (it is the projection target).
pub fn remesh(mesh: &LabelledMesh, opts: &RemeshOptions) -> Result<LabelledMesh> {
    validate(mesh, opts.target)?;
    let mut s = State::new(mesh);
    // The input's creases (projection targets) and its pinned turns.
    let topo = s.topo();
    let creases = crease_edges(&s, &topo);
    // With the clean-up, a vertex by a corner is left to its jog rule.
    let corner_gap = if opts.clean_slivers {
        cleanup::JOG_LENGTH * opts.target
    } else {
        0.0
    };
    let pins = crease_turns(
        &s,
        &topo,
        creases.iter().map(|c| c.0),
        opts.clean_slivers,
        corner_gap,
    );
    for v in pins {
        s.pinned[v as usize] = true;
    }
    let reference = Reference::new(&mesh.positions, &mesh.triangles, &mesh.labels, &creases);

    let sizing = match (opts.grade, opts.crease_tolerance) {
        (Some(g), Some(t)) => {
            let input_creases: Vec<[u32; 2]> = creases.iter().map(|c| c.0).collect();
            let stops: Vec<bool> = (0..s.pos.len())
                .map(|v| s.pinned[v] || topo.kind[v] != Kind::Crease)
                .collect();
            Some(sizing::Sizing::new(
                &mesh.positions,
                &input_creases,
                &stops,
                opts.target,
                t,
                g,
                1.0 / MIN_FRACTION,
            ))
        }
        _ => None,
    };
    let sizing = match (sizing, opts.surface_sizing) {
        (Some(z), Some(t)) => Some(z.with_samples(sizing::surface_samples(
            &mesh.positions,
            &mesh.triangles,
            &mesh.labels,
            &topo.edges,
            opts.target,
            t,
            1.0 / MIN_FRACTION,
        ))),
        (z, _) => z,
    };
    let rules = Rules {
        target: opts.target,
        sizing,
        min: opts.target / MIN_FRACTION,
        crease_tolerance: opts.crease_tolerance,
        reference: &reference,
    };
    rules.refresh_sizes(&mut s);
    for _ in 0..opts.iterations {
        for _ in 0..16 {
            if split_long(&mut s, &rules) == 0 {
                break;
            }
        }
        for _ in 0..64 {
            if collapse_short(&mut s, &rules) == 0 {
                break;
            }
        }
        for _ in 0..4 {
            if flip_to_valence(&mut s, &rules) == 0 {
                break;
            }
        }
        // Relaxation moves vertices only: one adjacency serves both.
        let topo = s.topo();
        let before = s.pos.clone();
        relax(&mut s, &topo);
        project(&mut s, &topo, &reference);
        undo_folds(&mut s, &before);
        rules.refresh_sizes(&mut s);
    }
    // The relaxation stretches a few edges past 4/3 L again: split those, onto the input.
    for _ in 0..16 {
        if split_long(&mut s, &rules) == 0 {
            break;
        }
        let topo = s.topo();
        let before = s.pos.clone();
        project(&mut s, &topo, &reference);
        undo_folds(&mut s, &before);
        rules.refresh_sizes(&mut s);
    }
    if opts.delaunay {
        for _ in 0..16 {
            if flip_edges(&mut s, &rules, Flip::Delaunay) == 0 {
                break;
            }
        }
    }
    for _ in 0..16 {
        if flip_edges(&mut s, &rules, Flip::Ear) == 0 {
            break;
        }
    }
    if opts.clean_slivers {
        cleanup::clean_and_flip(&mut s, &rules);
    }
    Ok(compact(&s))
}

/// The crease edges of `s` with the two regions each separates ([`crease_key`]; [`OPEN`] for
/// the missing side of a boundary edge).
fn crease_edges(s: &State, topo: &Topo) -> Vec<([u32; 2], (u32, u32))> {
    topo.edges
        .iter()
        .filter(|(_, fs)| s.is_crease(fs))
        .map(|(&(a, b), fs)| {
            let other = if fs[1] == NONE {
                OPEN
            } else {
                s.labels[fs[1] as usize]
            };
            ([a, b], crease_key(s.labels[fs[0] as usize], other))
        })
        .collect()
}

/// The input's crease vertices where their crease turns by more than [`PIN_TURN_DEG`], on the
/// scale of [`TURN_SCALE`] mean crease edges: the angle between the chords from the crease
/// points that far back along the crease to the vertex and from it to the point that far on
/// (or to the crease's end, a corner, if nearer). A corner of a crease turns at every scale;
/// the zigzag of an extracted crease (a vertex a tenth of a voxel off a straight edge turns its
/// two short edges by tens of degrees) only at the scale of its edges, and pinned it would stay
/// for good, with its slivers. With `hairpins_free`, a turn by more than 180 degrees less
/// [`cleanup::HAIRPIN_DEG`] (the crease coming back on itself: an extraction overshooting a
/// corner) is not pinned either: the clean-up undoes it; nor is a vertex nearer than
/// `corner_gap` to the corner its crease ends at (its turn there is the corner's, measured
/// over a chord too short to tell: pinned, the short edge to the corner could never go, and
/// the clean-up undoes its jog).
fn crease_turns(
    s: &State,
    topo: &Topo,
    crease_edges: impl Iterator<Item = [u32; 2]>,
    hairpins_free: bool,
    corner_gap: f64,
) -> Vec<u32> {
    let (mut sum, mut n) = (0.0, 0usize);
    for [a, b] in crease_edges {
        sum += s.len(a, b);
        n += 1;
    }
    if n == 0 {
        return Vec::new();
    }
    let scale = TURN_SCALE * sum / n as f64;
    // The vertex `scale` from v walking away from it through `first` (or the last one: a
    // corner, an open end, or v itself round a closed crease).
    let walk = |v: u32, first: u32| -> u32 {
        let p = s.pos[v as usize];
        let (mut prev, mut cur) = (v, first);
        for _ in 0..64 {
            if (s.pos[cur as usize] - p).norm() >= scale
                || topo.kind[cur as usize] != Kind::Crease
                || cur == v
            {
                break;
            }
            let c = topo.crease_neighbours(s, cur);
            let Some(&next) = c.iter().find(|&&w| w != prev) else {
                break;
            };
            (prev, cur) = (cur, next);
        }
        cur
    };
    let cos_turn = PIN_TURN_DEG.to_radians().cos();
    let cos_hairpin = if hairpins_free {
        (180.0 - cleanup::HAIRPIN_DEG).to_radians().cos()
    } else {
        -1.0
    };
    (0..s.pos.len() as u32)
        .filter(|&v| {
            if topo.kind[v as usize] != Kind::Crease {
                return false;
            }
            let c = topo.crease_neighbours(s, v);
            let p = s.pos[v as usize];
            let ends = [walk(v, c[0]), walk(v, c[1])];
            let by_corner = ends.iter().any(|&e| {
                topo.kind[e as usize] == Kind::Corner && (s.pos[e as usize] - p).norm() < corner_gap
            });
            let (d0, d1) = (p - s.pos[ends[0] as usize], s.pos[ends[1] as usize] - p);
            let cos = d0.dot(&d1) / (d0.norm() * d1.norm());
            cos < cos_turn && cos >= cos_hairpin && !by_corner
        })
        .collect()
}

/// The remeshing needs an edge-manifold, consistently oriented mesh of proper triangles:
/// every directed edge used once, so every edge by at most two triangles walking it in
/// opposite directions.
fn check_manifold(mesh: &LabelledMesh) -> Result<()> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            return Err(Error::Degenerate(format!(
                "remesh: triangle {f} repeats a vertex ({} {} {})",
                t[0], t[1], t[2]
            )));
        }
        for i in 0..3 {
            if let Some(g) = directed.insert((t[i], t[(i + 1) % 3]), f) {
                return Err(Error::Degenerate(format!(
                    "remesh: triangles {g} and {f} both walk edge {} -> {} (an edge of more \
                     than two triangles, or inconsistent orientation)",
                    t[i],
                    t[(i + 1) % 3]
                )));
            }
        }
    }
    Ok(())
}

/// Splits edges longer than 4/3 L, or too curved for the tolerance, at their midpoints,
/// longest first, one per triangle per pass.
fn split_long(s: &mut State, rules: &Rules) -> usize {
    use rayon::prelude::*;
    let topo = s.topo();
    // In parallel: every crease edge's chord error is a query of the input.
    let edges: Vec<(&(u32, u32), &[u32; 2])> = topo.edges.iter().collect();
    let state: &State = s;
    let mut long: Vec<((u32, u32), f64)> = edges
        .into_par_iter()
        .map(|(&(a, b), fs)| ((a, b), state.len(a, b), fs))
        .filter(|&((a, b), l, fs)| {
            l > 4.0 / 3.0 * rules.edge_target(state, a, b)
                || rules.too_curved(state, a, b, state.edge_on(fs))
        })
        .map(|(e, l, _)| (e, l))
        .collect();
    long.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
    let mut touched = vec![false; s.tris.len()];
    let mut count = 0;
    for ((a, b), _) in long {
        let fs = topo.edges[&(a, b)];
        let fs: Vec<u32> = fs.into_iter().filter(|&f| f != NONE).collect();
        if fs.iter().any(|&f| touched[f as usize]) {
            continue;
        }
        let m = s.pos.len() as u32;
        let mid = nalgebra::center(&s.pos[a as usize], &s.pos[b as usize]);
        s.pos.push(mid);
        s.pinned.push(false);
        if let Some(z) = &rules.sizing {
            s.size.push(z.at(&mid));
        }
        for f in fs {
            let t = s.tris[f as usize];
            let i = (0..3)
                .find(|&i| key(t[i], t[(i + 1) % 3]) == (a, b))
                .unwrap_or(0);
            let (u, w, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            s.tris[f as usize] = [u, m, c];
            s.tris.push([m, w, c]);
            s.labels.push(s.labels[f as usize]);
            s.alive.push(true);
            touched[f as usize] = true;
        }
        count += 1;
    }
    count
}

/// Tangential relaxation: a smooth vertex towards the area-weighted centroid of its triangles'
/// centres within its tangent plane, a crease vertex towards the midpoint of its two crease
/// neighbours along its crease; corners stay.
fn relax(s: &mut State, topo: &Topo) {
    let moved: Vec<Point3<f64>> = (0..s.pos.len() as u32)
        .map(|v| {
            let p = s.pos[v as usize];
            match topo.kind[v as usize] {
                Kind::Corner => p,
                Kind::Crease => {
                    let c = topo.crease_neighbours(s, v);
                    let (c0, c1) = (s.pos[c[0] as usize], s.pos[c[1] as usize]);
                    let t = (c1 - c0).normalize();
                    let q = nalgebra::center(&c0, &c1);
                    if t.iter().all(|x| x.is_finite()) {
                        p + t * t.dot(&(q - p))
                    } else {
                        p
                    }
                }
                Kind::Smooth => {
                    let (mut sum, mut area, mut n) = (Vector3::zeros(), 0.0, Vector3::zeros());
                    for &f in &topo.vfaces[v as usize] {
                        let t = s.tris[f as usize];
                        let nf = s.normal(&t);
                        let a = nf.norm();
                        let centre: Vector3<f64> = t
                            .iter()
                            .map(|&w| s.pos[w as usize].coords)
                            .sum::<Vector3<f64>>()
                            / 3.0;
                        sum += centre * a;
                        area += a;
                        n += nf;
                    }
                    if area <= 0.0 || n.norm() == 0.0 {
                        return p;
                    }
                    let n = n.normalize();
                    let d = sum / area - p.coords;
                    p + (d - n * n.dot(&d))
                }
            }
        })
        .collect();
    s.pos = moved;
}

/// Every vertex back onto the input: a smooth one onto its region's triangles, a crease one onto
/// the input crease between its two regions.
fn project(s: &mut State, topo: &Topo, reference: &Reference) {
    for v in 0..s.pos.len() as u32 {
        let fs = &topo.vfaces[v as usize];
        if fs.is_empty() {
            continue;
        }
        let p = s.pos[v as usize];
        let q = match topo.kind[v as usize] {
            Kind::Corner => None,
            Kind::Crease => reference.on_crease(topo.crease_of(s, v), &p),
            Kind::Smooth => reference.on_region(s.labels[fs[0] as usize], &p),
        };
        if let Some(q) = q {
            s.pos[v as usize] = q;
        }
    }
}

/// Largest turn of a triangle's normal in one relaxation and projection, degrees: beyond it
/// (a triangle turned inside out or on edge, which the tangential moves of Botsch & Kobbelt's
/// relaxation do not exclude near a corner or a tight crease) its vertices go back.
pub const MAX_MOVE_TURN_DEG: f64 = 60.0;

/// Puts back at their positions in `before` the vertices of every live triangle that the moves
/// since then turned by more than [`MAX_MOVE_TURN_DEG`] (or shrank to nothing), until none is;
/// the triangles of `before` are taken as sound (a triangle turned already stays as it is).
/// Returns the vertices put back.
fn undo_folds(s: &mut State, before: &[Point3<f64>]) -> usize {
    let cos_max = MAX_MOVE_TURN_DEG.to_radians().cos();
    let mut back = vec![false; s.pos.len()];
    let mut count = 0;
    for _ in 0..32 {
        let mut changed = false;
        for f in 0..s.tris.len() {
            let t = s.tris[f];
            if !s.alive[f] || t.iter().all(|&v| back[v as usize]) {
                continue;
            }
            let [a, b, c] = t.map(|v| before[v as usize]);
            let old = (b - a).cross(&(c - a));
            let new = s.normal(&t);
            if old.norm() == 0.0 || new.dot(&old) > cos_max * new.norm() * old.norm() {
                continue;
            }
            for v in t {
                if !back[v as usize] {
                    back[v as usize] = true;
                    s.pos[v as usize] = before[v as usize];
                    count += 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    count
}

/// The live triangles with their used vertices renumbered.
fn compact(s: &State) -> LabelledMesh {
    let mut index = vec![NONE; s.pos.len()];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut labels = Vec::new();
    for (f, t) in s.tris.iter().enumerate() {
        if !s.alive[f] {
            continue;
        }
        triangles.push(t.map(|v| {
            if index[v as usize] == NONE {
                index[v as usize] = positions.len() as u32;
                positions.push(s.pos[v as usize]);
            }
            index[v as usize]
        }));
        labels.push(s.labels[f]);
    }
    LabelledMesh {
        positions,
        triangles,
        labels,
    }
}

#[cfg(test)]
mod tests;
