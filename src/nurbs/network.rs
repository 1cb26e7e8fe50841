//! The patch network: bicubic patches sewn along shared edge curves, the data model the STEP
//! and IGES writers take.
//!
//! Topology is explicit: net vertices (patch corners), edges (a curve between two vertices,
//! stored once however many patches use it) and faces (a surface plus its four edges in
//! boundary-loop order, [`Side::LOOP`]). A face's boundary curve on each side must equal its
//! edge's curve (reversed where the loop runs against the edge), which
//! [`PatchNetwork::validate`] checks; [`PatchNetwork::from_patches`] builds the topology from
//! surfaces and corner vertex ids.

use super::curve::BSplineCurve;
use super::surface::{BSplineSurface, Side};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// An edge of the net: `curve` runs from vertex `v[0]` to vertex `v[1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct NetEdge {
    pub v: [u32; 2],
    pub curve: BSplineCurve,
}

/// A patch: its surface and its four edges in loop order (V0 with u increasing, U1, V1
/// reversed, U0 reversed; see [`Side::LOOP`]). `edges[k] = (edge index, reversed)`, where
/// `reversed` says the loop runs the edge from `v[1]` to `v[0]`.
#[derive(Debug, Clone, PartialEq)]
pub struct NetFace {
    pub surface: BSplineSurface,
    pub edges: [(u32, bool); 4],
    /// True when the surface normal `S_u × S_v` points out of the solid (for an open shell:
    /// to its front side). The STEP writer sets ADVANCED_FACE.same_sense from it.
    pub same_sense: bool,
}

/// A network of B-spline patches sharing edge curves.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PatchNetwork {
    /// Net corners.
    pub vertices: Vec<Point3<f64>>,
    pub edges: Vec<NetEdge>,
    pub faces: Vec<NetFace>,
    /// Every edge has exactly two faces (a closed shell).
    pub closed: bool,
}

/// One patch for [`PatchNetwork::from_patches`]: a surface and the vertex ids of its corners
/// (u,v) = (0,0), (1,0), (1,1), (0,1), i.e. counter-clockwise around `S_u × S_v`.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchInput {
    pub surface: BSplineSurface,
    pub corners: [u32; 4],
    pub same_sense: bool,
}

impl PatchNetwork {
    /// Builds the network from patches with corner vertex ids. An edge is identified by its
    /// (unordered) vertex pair plus its curve: patches whose boundary curves between the same
    /// two vertices agree (within 1e-9 of the network size) share one edge; a different curve
    /// between the same vertices becomes a separate edge (then neither is sewn, and `closed`
    /// is false). Edge curves are stored in the direction of their first use. The result is
    /// validated.
    pub fn from_patches(vertices: Vec<Point3<f64>>, patches: Vec<PatchInput>) -> Result<Self> {
        let size = network_size(&vertices, patches.iter().map(|p| &p.surface));
        let tol = 1e-9 * size;
        let mut edges: Vec<NetEdge> = Vec::new();
        let mut by_pair: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut faces = Vec::with_capacity(patches.len());
        for (fi, patch) in patches.into_iter().enumerate() {
            let c = patch.corners;
            if let Some(&bad) = c.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(Error::Degenerate(format!(
                    "patch {fi}: corner vertex {bad} out of range ({} vertices)",
                    vertices.len()
                )));
            }
            let mut loop_edges = [(0u32, false); 4];
            for (k, side) in Side::LOOP.into_iter().enumerate() {
                // Loop direction: corner k -> corner k+1.
                let (a, b) = (c[k], c[(k + 1) % 4]);
                if a == b {
                    return Err(Error::Degenerate(format!(
                        "patch {fi}: side {side:?} starts and ends at vertex {a} (collapsed side)"
                    )));
                }
                let mut curve = patch.surface.boundary_curve(side);
                if side.loop_reversed() {
                    curve = curve.reversed();
                }
                // `curve` now runs a -> b.
                let key = (a.min(b), a.max(b));
                let candidates = by_pair.entry(key).or_default();
                let mut found = None;
                for &ei in candidates.iter() {
                    let e = &edges[ei as usize];
                    let rev = e.v[0] != a;
                    let stored = if rev {
                        e.curve.reversed()
                    } else {
                        e.curve.clone()
                    };
                    if stored
                        .max_ctrl_distance(&curve, 1e-9)
                        .is_some_and(|d| d <= tol)
                    {
                        found = Some((ei, rev));
                        break;
                    }
                }
                loop_edges[k] = match found {
                    Some(f) => f,
                    None => {
                        let ei = edges.len() as u32;
                        edges.push(NetEdge { v: [a, b], curve });
                        candidates.push(ei);
                        (ei, false)
                    }
                };
            }
            faces.push(NetFace {
                surface: patch.surface,
                edges: loop_edges,
                same_sense: patch.same_sense,
            });
        }
        let mut net = PatchNetwork {
            vertices,
            edges,
            faces,
            closed: false,
        };
        net.closed = net.edge_use_counts().iter().all(|&n| n == 2) && !net.faces.is_empty();
        net.validate()?;
        Ok(net)
    }

    /// Parameters (u, v) on face `face` of the point at `t` in [0, 1] along its loop side `k`
    /// (`faces[face].edges[k]`), `t` running in the edge's own direction (`reversed` as
    /// stored in the face's edge list): the side's iso-line, linear in `t`, which is also how
    /// the edge curve's parameter maps onto the face (both have the same knots).
    pub fn side_uv(&self, face: usize, k: usize, reversed: bool, t: f64) -> (f64, f64) {
        let s = &self.faces[face].surface;
        let (u0, u1) = s.domain_u();
        let (v0, v1) = s.domain_v();
        // Position along the loop direction of this side.
        let loop_t = if reversed { 1.0 - t } else { t };
        let lerp = |a: f64, b: f64, x: f64| a + (b - a) * x;
        match Side::LOOP[k] {
            Side::V0 => (lerp(u0, u1, loop_t), v0),
            Side::U1 => (u1, lerp(v0, v1, loop_t)),
            Side::V1 => (lerp(u1, u0, loop_t), v1),
            Side::U0 => (u0, lerp(v1, v0, loop_t)),
        }
    }

    /// The quad net the patches were built on: per face, its four corner vertices in loop
    /// order ((u, v) = (0, 0), (1, 0), (1, 1), (0, 1): counter-clockwise around S_u x S_v), the
    /// start of each loop edge. Faces follow `faces` (the STEP's face order).
    pub fn quads(&self) -> Vec<[u32; 4]> {
        self.faces
            .iter()
            .map(|f| {
                f.edges.map(|(e, reversed)| {
                    let v = self.edges[e as usize].v;
                    if reversed {
                        v[1]
                    } else {
                        v[0]
                    }
                })
            })
            .collect()
    }

    /// How many faces use each edge.
    pub fn edge_use_counts(&self) -> Vec<usize> {
        let mut uses = vec![0usize; self.edges.len()];
        for f in &self.faces {
            for &(e, _) in &f.edges {
                if let Some(u) = uses.get_mut(e as usize) {
                    *u += 1;
                }
            }
        }
        uses
    }

    /// Diagonal of the bounding box of all vertices and control points.
    pub fn size(&self) -> f64 {
        network_size(&self.vertices, self.faces.iter().map(|f| &f.surface))
    }

    /// Checks the network's consistency:
    /// - every vertex and control point is finite, surfaces and curves are well formed;
    /// - edge endpoints are valid vertex ids and the curve starts and ends at them;
    /// - each face's boundary curve on every side equals its edge's curve (reversed as the loop
    ///   says) within 1e-9 x network size, and consecutive loop edges meet;
    /// - every edge is used by one or two faces, and `closed` is true exactly when every edge
    ///   is used twice;
    /// - an edge used by two faces is traversed in opposite directions by their outward
    ///   oriented loops (consistent orientation, needed for a valid solid).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Degenerate(format!("patch network: {m}")));
        if self.faces.is_empty() {
            return bad("no faces".into());
        }
        if self
            .vertices
            .iter()
            .any(|p| !p.coords.iter().all(|c| c.is_finite()))
        {
            return bad("non-finite vertex".into());
        }
        let tol = 1e-9 * self.size();
        for (ei, e) in self.edges.iter().enumerate() {
            let c = BSplineCurve::new(e.curve.degree, e.curve.knots.clone(), e.curve.ctrl.clone())
                .map_err(|err| Error::Degenerate(format!("patch network: edge {ei}: {err}")))?;
            for (end, &vi) in e.v.iter().enumerate() {
                let Some(vp) = self.vertices.get(vi as usize) else {
                    return bad(format!("edge {ei}: vertex {vi} out of range"));
                };
                let (a, b) = c.domain();
                let cp = c.evaluate(if end == 0 { a } else { b });
                if (cp - vp).norm() > tol {
                    return bad(format!(
                        "edge {ei}: curve end {end} is {:.3e} away from vertex {vi}",
                        (cp - vp).norm()
                    ));
                }
            }
        }
        // Per edge: directions in which outward-oriented loops traverse it.
        let mut dirs: Vec<Vec<bool>> = vec![Vec::new(); self.edges.len()];
        for (fi, f) in self.faces.iter().enumerate() {
            let s = &f.surface;
            BSplineSurface::new(
                s.degree_u,
                s.degree_v,
                s.knots_u.clone(),
                s.knots_v.clone(),
                s.ctrl.clone(),
            )
            .map_err(|err| Error::Degenerate(format!("patch network: face {fi}: {err}")))?;
            let mut ends = [[0u32; 2]; 4];
            for (k, side) in Side::LOOP.into_iter().enumerate() {
                let (ei, rev) = f.edges[k];
                let Some(e) = self.edges.get(ei as usize) else {
                    return bad(format!("face {fi}: edge {ei} out of range"));
                };
                let mut curve = s.boundary_curve(side);
                if side.loop_reversed() {
                    curve = curve.reversed();
                }
                let edge_curve = if rev {
                    e.curve.reversed()
                } else {
                    e.curve.clone()
                };
                let knot_tol = 1e-9 * (edge_curve.domain().1 - edge_curve.domain().0);
                match edge_curve.max_ctrl_distance(&curve, knot_tol) {
                    Some(d) if d <= tol => {}
                    Some(d) => {
                        return bad(format!(
                            "face {fi} side {side:?}: boundary differs from edge {ei} by {d:.3e}"
                        ))
                    }
                    None => {
                        return bad(format!(
                            "face {fi} side {side:?}: boundary and edge {ei} have different \
                             degree, knots or control point counts"
                        ))
                    }
                }
                ends[k] = if rev { [e.v[1], e.v[0]] } else { e.v };
                dirs[ei as usize].push(rev ^ !f.same_sense);
            }
            for k in 0..4 {
                if ends[k][1] != ends[(k + 1) % 4][0] {
                    return bad(format!("face {fi}: loop is not connected at side {k}"));
                }
            }
        }
        for (ei, d) in dirs.iter().enumerate() {
            match d.len() {
                1 => {}
                2 if d[0] != d[1] => {}
                2 => {
                    return bad(format!(
                        "edge {ei}: both faces traverse it in the same direction \
                         (inconsistent orientation)"
                    ))
                }
                n => return bad(format!("edge {ei} is used by {n} faces (need 1 or 2)")),
            }
        }
        let all_two = dirs.iter().all(|d| d.len() == 2);
        if self.closed != all_two {
            return bad(format!(
                "closed is {} but {} edges are used by one face",
                self.closed,
                dirs.iter().filter(|d| d.len() == 1).count()
            ));
        }
        Ok(())
    }
}

fn network_size<'a>(
    vertices: &[Point3<f64>],
    surfaces: impl Iterator<Item = &'a BSplineSurface>,
) -> f64 {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    let pts = vertices
        .iter()
        .chain(surfaces.flat_map(|s| s.ctrl.iter().flatten()));
    for p in pts {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    let d = (hi - lo).norm();
    if d.is_finite() {
        d
    } else {
        0.0
    }
}

/// Test fixture shared by the STEP and IGES writers' and reader's tests: two bicubic patches
/// side by side over [0, 1] x [0, 1] and [1, 2] x [0, 1] sharing the edge x = 1, each on a 5 x 5
/// control grid at spacing 0.25 with z = `height(x, y)`.
#[cfg(test)]
pub(crate) fn two_patch_network(height: fn(f64, f64) -> f64) -> PatchNetwork {
    let k = crate::nurbs::params::Params::uniform(2)
        .unwrap()
        .cubic_knots();
    let patch = |x0: f64| {
        let ctrl = (0..5)
            .map(|i| {
                (0..5)
                    .map(|j| {
                        let (x, y) = (x0 + i as f64 * 0.25, j as f64 * 0.25);
                        Point3::new(x, y, height(x, y))
                    })
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, k.clone(), k.clone(), ctrl).unwrap()
    };
    side_by_side(patch(0.0), patch(1.0))
}

/// Test fixture: the network of two patches side by side, `a`'s side u = 1 being `b`'s side
/// u = 0 (one shared edge), its six vertices the patches' corners.
#[cfg(test)]
pub(crate) fn side_by_side(a: BSplineSurface, b: BSplineSurface) -> PatchNetwork {
    let corner = |s: &BSplineSurface, i: usize, j: usize| {
        let (u, v) = (s.domain_u(), s.domain_v());
        s.evaluate([u.0, u.1][i], [v.0, v.1][j])
    };
    let v = vec![
        corner(&a, 0, 0),
        corner(&a, 1, 0),
        corner(&a, 1, 1),
        corner(&a, 0, 1),
        corner(&b, 1, 0),
        corner(&b, 1, 1),
    ];
    PatchNetwork::from_patches(
        v,
        vec![
            PatchInput {
                surface: a,
                corners: [0, 1, 2, 3],
                same_sense: true,
            },
            PatchInput {
                surface: b,
                corners: [1, 4, 5, 2],
                same_sense: true,
            },
        ],
    )
    .unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nurbs::params::Params;

    /// A bilinear patch as a bicubic (control points on a 4x4 grid between the corners).
    fn flat(c: [Point3<f64>; 4]) -> BSplineSurface {
        let k = Params::uniform(1).unwrap().cubic_knots();
        let ctrl = (0..4)
            .map(|i| {
                (0..4)
                    .map(|j| {
                        let (a, b) = (i as f64 / 3.0, j as f64 / 3.0);
                        Point3::from(
                            c[0].coords * (1.0 - a) * (1.0 - b)
                                + c[1].coords * a * (1.0 - b)
                                + c[2].coords * a * b
                                + c[3].coords * (1.0 - a) * b,
                        )
                    })
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, k.clone(), k, ctrl).unwrap()
    }

    /// The unit cube's six faces, corners counter-clockwise seen from outside.
    fn cube() -> (Vec<Point3<f64>>, Vec<PatchInput>) {
        let v: Vec<Point3<f64>> = (0..8)
            .map(|i| Point3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1], // z = 0, normal -z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let patches = quads
            .iter()
            .map(|q| PatchInput {
                surface: flat([v[q[0]], v[q[1]], v[q[2]], v[q[3]]]),
                corners: q.map(|i| i as u32),
                same_sense: true,
            })
            .collect();
        (v, patches)
    }

    #[test]
    fn cube_network_is_closed_and_valid() {
        let (v, p) = cube();
        let corners: Vec<[u32; 4]> = p.iter().map(|q| q.corners).collect();
        let net = PatchNetwork::from_patches(v, p).unwrap();
        // The quad net comes back as the patches' corners.
        assert_eq!(net.quads(), corners);
        assert_eq!(net.edges.len(), 12);
        assert!(net.closed);
        assert!(net.edge_use_counts().iter().all(|&n| n == 2));
        // Outward normals.
        for f in &net.faces {
            let c = f.surface.evaluate(0.5, 0.5);
            let n = f.surface.normal(0.5, 0.5).unwrap();
            assert!(n.dot(&(c - Point3::new(0.5, 0.5, 0.5))) > 0.0);
        }
    }

    #[test]
    fn open_network_and_broken_networks() {
        let (v, mut p) = cube();
        p.pop();
        let net = PatchNetwork::from_patches(v.clone(), p.clone()).unwrap();
        assert!(!net.closed);
        assert_eq!(net.edge_use_counts().iter().filter(|&&n| n == 1).count(), 4);

        // Claiming closed on an open net fails validation.
        let mut lie = net.clone();
        lie.closed = true;
        assert!(lie.validate().is_err());

        // A face whose boundary no longer matches its edge.
        let mut moved = net.clone();
        moved.faces[0].surface.ctrl[1][0].x += 1e-3;
        assert!(moved.validate().is_err());

        // Flipped orientation of one face.
        let mut flipped = net.clone();
        flipped.faces[2].same_sense = false;
        assert!(flipped.validate().is_err());

        // Out-of-range corner.
        p[0].corners[0] = 99;
        assert!(PatchNetwork::from_patches(v, p).is_err());
    }
}
