//! Planar Delaunay hole filling with circular-arc subdivision (seed 002 section 3).
//!
//! 1. **Projection** (section 3.2, eq. 1): the ring goes onto the plane of its mean normal, or
//!    the user's direction ([`super::plane`]); rings that fold are cut ([`super::split`]).
//! 2. **Triangulation** (section 3.3, eq. 2): constrained Delaunay triangulation of the
//!    projected ring (spade), kept inside the ring, mapped back to the ring's 3D vertices.
//! 3. **Subdivision** (section 3.4, eq. 3-4): inner edges longer than `ratio` times the ring's
//!    shortest edge are split at circular-arc midpoints ([`super::arc`]), faces cut 1-to-4
//!    ([`super::subdivide_fill`]), repeated until no edge is that long.
//! 4. **Smoothing** (section 3.5): circular-arc smoothing weighted by neighbour distance.
//!
//! After each subdivision, 3D Delaunay flips ([`super::flip`]) remove the slivers that a
//! triangulation with only ring vertices starts from (not in the paper). With
//! `circular_arc = false` the midpoints stay on the edges and nothing is smoothed: a flat fill,
//! the baseline most mesh editors give.

use super::arc::{arc_midpoint, arc_smooth};
use super::flip::delaunay_flips;
use super::patch::Patch;
use super::plane::Frame;
use super::split::{fill_ring, Projection};
use super::subdivide_fill::refine;
use crate::error::{Error, Result};
use nalgebra::{Point2, Point3, Vector3};
use spade::{ConstrainedDelaunayTriangulation, Point2 as SPoint, Triangulation};

/// Options of the planar fill.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PlanarOptions {
    /// Subdivide until every new edge is at most `ratio` times the ring's shortest edge (the
    /// shortest edge is taken at least half the mean ring edge, so that one tiny edge does not
    /// blow the fill up).
    pub ratio: f64,
    /// Circular-arc smoothing sweeps after the last subdivision (one more after each level).
    pub smoothing_iterations: usize,
    /// At most this many subdivision levels.
    pub max_levels: usize,
    /// Place midpoints on circular arcs and smooth (seed 002); `false` gives a flat fill.
    pub circular_arc: bool,
}

impl Default for PlanarOptions {
    fn default() -> Self {
        PlanarOptions {
            ratio: 2.0,
            smoothing_iterations: 5,
            max_levels: 10,
            circular_arc: true,
        }
    }
}

/// Fills the patch's ring (see the module doc). Returns how the ring was projected.
pub fn fill_planar(
    patch: &mut Patch,
    direction: Option<Vector3<f64>>,
    opts: &PlanarOptions,
) -> Result<Projection> {
    let n = patch.ring_len() as u32;
    if n < 3 {
        return Err(Error::Degenerate(format!("a ring of {n} vertices")));
    }
    if !(opts.ratio > 0.0 && opts.ratio.is_finite()) {
        return Err(Error::InvalidOption(format!(
            "subdivision ratio {} must be positive",
            opts.ratio
        )));
    }
    let ring: Vec<u32> = (0..n).collect();
    let ring_edges: Vec<f64> = (0..n).map(|i| patch.edge_length(i, (i + 1) % n)).collect();
    let mean = ring_edges.iter().sum::<f64>() / n as f64;
    let shortest = ring_edges
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
        .max(0.5 * mean);
    let threshold = opts.ratio * shortest;
    if !(threshold > 0.0 && threshold.is_finite()) {
        return Err(Error::Degenerate("the hole's ring has zero length".into()));
    }
    let arc = opts.circular_arc;
    let midpoint = move |p: &Patch, a: u32, b: u32| -> (Point3<f64>, Vector3<f64>) {
        let (pa, pb) = (p.positions[a as usize], p.positions[b as usize]);
        let (na, nb) = (p.normals[a as usize], p.normals[b as usize]);
        if arc {
            arc_midpoint(&pa, &na, &pb, &nb)
        } else {
            let nm = na + nb;
            let l = nm.norm();
            (
                nalgebra::center(&pa, &pb),
                if l > 1e-12 { nm / l } else { na },
            )
        }
    };
    let mut mesh_part = |p: &mut Patch, r: &[u32], _frame: &Frame, poly: &[Point2<f64>]| {
        let tris = constrained_delaunay(poly)?;
        for t in tris {
            p.faces.push([r[t[0]], r[t[1]], r[t[2]]]);
        }
        Ok(())
    };
    let mut chord = |p: &mut Patch, a: u32, b: u32, pieces: usize| -> Result<Vec<u32>> {
        // Bisect the chord on circular arcs down to at least `pieces` segments.
        let mut nodes: Vec<(Point3<f64>, Vector3<f64>)> = vec![
            (p.positions[a as usize], p.normals[a as usize]),
            (p.positions[b as usize], p.normals[b as usize]),
        ];
        while nodes.len() - 1 < pieces {
            let mut next = Vec::with_capacity(2 * nodes.len());
            for w in nodes.windows(2) {
                next.push(w[0]);
                next.push(if arc {
                    arc_midpoint(&w[0].0, &w[0].1, &w[1].0, &w[1].1)
                } else {
                    (nalgebra::center(&w[0].0, &w[1].0), w[0].1)
                });
            }
            next.push(nodes[nodes.len() - 1]);
            nodes = next;
        }
        Ok(nodes[1..nodes.len() - 1]
            .iter()
            .map(|&(x, nv)| p.add_vertex(x, nv))
            .collect())
    };
    let projection = fill_ring(
        patch,
        &ring,
        direction,
        threshold,
        4,
        &mut mesh_part,
        &mut chord,
    )?;
    // Inner edges between ring vertices that the mesh already has (across a narrow neck of the
    // hole) would become non-manifold: split them first.
    refine(patch, &|p, a, b| p.is_mesh_edge(a, b), &midpoint);
    delaunay_flips(patch, 20);
    // An edge at a ring vertex may be as long as that vertex's longest ring edge: a triangle on
    // a ring edge longer than the threshold can never have all its edges below it, and would be
    // cut into ever thinner slivers.
    let mut ring_len = vec![0.0f64; n as usize];
    for i in 0..n {
        let j = (i + 1) % n;
        let l = patch.edge_length(i, j);
        ring_len[i as usize] = ring_len[i as usize].max(l);
        ring_len[j as usize] = ring_len[j as usize].max(l);
    }
    let limit = |a: u32, b: u32| {
        let at = |v: u32| ring_len.get(v as usize).copied().unwrap_or(0.0);
        threshold.max(at(a)).max(at(b))
    };
    for _ in 0..opts.max_levels {
        let split = refine(
            patch,
            &|p, a, b| p.edge_length(a, b) > limit(a, b),
            &midpoint,
        );
        if split == 0 {
            break;
        }
        delaunay_flips(patch, 20);
        if arc {
            smooth_without_folding(patch, 1);
        }
    }
    if arc {
        smooth_without_folding(patch, opts.smoothing_iterations);
    }
    Ok(projection)
}

/// Circular-arc smoothing sweeps that may not make the fill cut through itself more than before
/// (on creases and noisy borders the normals disagree, and smoothing can fold the fill). All
/// sweeps are tried at once; when that folds, they are redone one at a time, each kept only if
/// it does not.
fn smooth_without_folding(patch: &mut Patch, iterations: usize) {
    if iterations == 0 {
        return;
    }
    let crossings = |p: &Patch| {
        let m = crate::mesh::Mesh {
            positions: p.positions.clone(),
            normals: None,
            faces: p.faces.clone(),
        };
        super::intersect::fill_intersections(&m, 0).len()
    };
    let before = crossings(patch);
    let saved = patch.positions.clone();
    arc_smooth(patch, iterations);
    if crossings(patch) <= before {
        return;
    }
    patch.positions = saved;
    if iterations == 1 {
        return;
    }
    for _ in 0..iterations {
        let step = patch.positions.clone();
        arc_smooth(patch, 1);
        if crossings(patch) > before {
            patch.positions = step;
            break;
        }
    }
}

/// Constrained Delaunay triangulation of a simple counter-clockwise polygon, keeping the
/// triangles inside it (spade). Triangles index the polygon's vertices.
pub fn constrained_delaunay(poly: &[Point2<f64>]) -> Result<Vec<[usize; 3]>> {
    let n = poly.len();
    let mut cdt: ConstrainedDelaunayTriangulation<SPoint<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let mut handles = Vec::with_capacity(n);
    for p in poly {
        let h = cdt
            .insert(SPoint::new(p.x, p.y))
            .map_err(|e| Error::Degenerate(format!("Delaunay triangulation: {e:?}")))?;
        handles.push(h);
    }
    if cdt.num_vertices() != n {
        return Err(Error::Degenerate(
            "Delaunay triangulation: two ring vertices project onto one point".into(),
        ));
    }
    let mut index_of = vec![usize::MAX; n];
    for (i, h) in handles.iter().enumerate() {
        index_of[h.index()] = i;
    }
    for i in 0..n {
        let (a, b) = (handles[i], handles[(i + 1) % n]);
        if !cdt.can_add_constraint(a, b) {
            return Err(Error::Degenerate(
                "Delaunay triangulation: the projected ring crosses itself".into(),
            ));
        }
        cdt.add_constraint(a, b);
    }
    // The triangles inside: flood from the face left of each ring edge (the ring runs
    // counter-clockwise) without crossing a constraint.
    let missing = || Error::Degenerate("Delaunay triangulation lost a ring edge".into());
    let mut seen = vec![false; cdt.num_inner_faces() + 1];
    let mut stack = Vec::new();
    for i in 0..n {
        let e = cdt
            .get_edge_from_neighbors(handles[i], handles[(i + 1) % n])
            .ok_or_else(missing)?;
        let f = e.face().as_inner().ok_or_else(missing)?;
        stack.push(f.fix());
    }
    let mut tris = Vec::new();
    while let Some(fh) = stack.pop() {
        let k = fh.index();
        if k >= seen.len() || seen[k] {
            continue;
        }
        seen[k] = true;
        let face = cdt.face(fh);
        let vs = face.vertices();
        let t = [
            index_of[vs[0].fix().index()],
            index_of[vs[1].fix().index()],
            index_of[vs[2].fix().index()],
        ];
        if t.contains(&usize::MAX) {
            return Err(Error::Degenerate(
                "Delaunay triangulation added a vertex".into(),
            ));
        }
        tris.push(t);
        for e in face.adjacent_edges() {
            if e.is_constraint_edge() {
                continue;
            }
            let g = e.rev().face().as_inner().ok_or_else(|| {
                Error::Degenerate("Delaunay triangulation: the ring is not closed".into())
            })?;
            stack.push(g.fix());
        }
    }
    tris.sort_unstable();
    if tris.len() != n - 2 {
        return Err(Error::Degenerate(format!(
            "Delaunay triangulation of a {n}-vertex ring gave {} triangles inside, expected {}",
            tris.len(),
            n - 2
        )));
    }
    Ok(tris)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdt_of_an_l_shape() {
        let poly = vec![
            Point2::new(0.0, 0.0),
            Point2::new(3.0, 0.0),
            Point2::new(3.0, 1.0),
            Point2::new(1.0, 1.0),
            Point2::new(1.0, 3.0),
            Point2::new(0.0, 3.0),
        ];
        let t = constrained_delaunay(&poly).unwrap();
        assert_eq!(t.len(), 4);
        let area: f64 = t
            .iter()
            .map(|t| 0.5 * super::super::plane::orient(&poly[t[0]], &poly[t[1]], &poly[t[2]]))
            .sum();
        assert!((area - 5.0).abs() < 1e-12);
        // Duplicate projected points are an error, not a panic.
        let dup = vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 0.0),
            Point2::new(0.0, 1.0),
        ];
        assert!(constrained_delaunay(&dup).is_err());
    }

    #[test]
    fn sphere_cap_is_filled_on_the_sphere() {
        let n = 30;
        let th: f64 = 0.4;
        let mut pos = Vec::new();
        for k in 0..n {
            let ph = std::f64::consts::TAU * k as f64 / n as f64;
            pos.push(Point3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
        let normals = pos.iter().map(|p| p.coords).collect();
        let mut patch = Patch::from_ring(pos, normals, (0..n as u32).collect(), Default::default());
        let proj = fill_planar(&mut patch, None, &PlanarOptions::default()).unwrap();
        assert_eq!(proj.parts(), 1);
        assert!(
            patch.check_topology().is_ok(),
            "{:?}",
            patch.check_topology()
        );
        let worst = patch
            .positions
            .iter()
            .map(|p| (p.coords.norm() - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-3, "worst radial error {worst}");
        assert!(patch.positions.len() > n + 10);
    }
}
