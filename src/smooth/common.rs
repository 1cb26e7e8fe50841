//! What the smoothing passes share: options, the report, face geometry, which vertices may move,
//! displacement statistics and the volume constraint.

use crate::error::{Error, Result};
use crate::mesh::adjacency::Adjacency;
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Options every smoothing pass takes besides its own parameters.
#[derive(Clone, Copy, Default)]
pub struct Control<'a> {
    /// Only the flagged vertices move (one flag per vertex; vertices past the slice's end stay).
    /// `None` moves all. [`Adjacency::grow_rings`] widens a set, e.g. a hole fill by k rings.
    pub region: Option<&'a [bool]>,
    /// Called on the calling thread after each iteration with (iterations done, total).
    pub progress: Option<&'a dyn Fn(usize, usize)>,
}

impl std::fmt::Debug for Control<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Control")
            .field(
                "region",
                &self.region.map(|r| r.iter().filter(|&&x| x).count()),
            )
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

/// What a smoothing pass did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SmoothReport {
    /// "anisotropic", "arc" or "centroid".
    pub method: &'static str,
    /// Iterations run.
    pub iterations: usize,
    /// Vertices allowed to move (in the region, on a face, not held on a boundary).
    pub movable_vertices: usize,
    /// Mean distance between the first and the last position over the movable vertices.
    pub mean_displacement: f64,
    /// Largest such distance.
    pub max_displacement: f64,
    /// Mean edge length of the input, the unit of the default parameters.
    pub mean_edge_length: f64,
    /// Wall-clock seconds of the pass (the caller builds the adjacency).
    pub seconds: f64,
    /// The parameters actually used, defaults resolved.
    pub parameters: serde_json::Value,
}

/// Fails on a non-finite coordinate of a vertex some face uses (nothing sensible can be
/// computed around it).
pub(crate) fn check_finite(mesh: &Mesh, adj: &Adjacency) -> Result<()> {
    if !adj.fits(mesh) {
        return Err(Error::InvalidOption(format!(
            "adjacency built for {} vertices and {} faces, mesh has {} and {}",
            adj.vertex_count(),
            adj.face_count,
            mesh.positions.len(),
            mesh.faces.len()
        )));
    }
    let bad = mesh
        .positions
        .par_iter()
        .enumerate()
        .find_first(|(v, p)| {
            adj.ring_offsets[*v] != adj.ring_offsets[*v + 1] && !p.iter().all(|x| x.is_finite())
        })
        .map(|(v, _)| v);
    match bad {
        Some(v) => Err(Error::Degenerate(format!(
            "vertex {v} has a non-finite coordinate"
        ))),
        None => Ok(()),
    }
}

/// Which vertices may move: in the region, on an edge, and (when `fix_boundary`) not on a
/// boundary or non-manifold edge.
pub(crate) fn movable(adj: &Adjacency, region: Option<&[bool]>, fix_boundary: bool) -> Vec<bool> {
    (0..adj.vertex_count())
        .into_par_iter()
        .map(|v| {
            let in_region = region.is_none_or(|r| r.get(v).copied().unwrap_or(false));
            in_region
                && adj.ring_offsets[v] != adj.ring_offsets[v + 1]
                && !(fix_boundary && adj.is_boundary_or_singular(v))
        })
        .collect()
}

/// Per face (b - a) x (c - a): twice the area times the unit normal; zero for a degenerate or
/// non-finite face.
pub(crate) fn face_crosses(
    positions: &[Point3<f64>],
    faces: &[[u32; 3]],
    out: &mut Vec<Vector3<f64>>,
) {
    faces
        .par_iter()
        .map(|f| {
            let a = positions[f[0] as usize];
            let c = (positions[f[1] as usize] - a).cross(&(positions[f[2] as usize] - a));
            if c.iter().all(|x| x.is_finite()) {
                c
            } else {
                Vector3::zeros()
            }
        })
        .collect_into_vec(out);
}

/// Unit vertex normals from the face crosses (area weighted); zero where undefined.
pub(crate) fn vertex_normals(
    adj: &Adjacency,
    crosses: &[Vector3<f64>],
    out: &mut Vec<Vector3<f64>>,
) {
    (0..adj.vertex_count())
        .into_par_iter()
        .map(|v| {
            let s: Vector3<f64> = adj
                .faces_of_vertex(v)
                .iter()
                .map(|&f| crosses[f as usize])
                .sum();
            let l = s.norm();
            if l > 0.0 && l.is_finite() {
                s / l
            } else {
                Vector3::zeros()
            }
        })
        .collect_into_vec(out);
}

/// Mean mesh edge length over the unique edges; 0 without edges.
pub(crate) fn mean_edge_length(positions: &[Point3<f64>], adj: &Adjacency) -> f64 {
    if adj.edges.is_empty() {
        return 0.0;
    }
    let lens: Vec<f64> = adj
        .edges
        .par_iter()
        .map(|e| (positions[e[0] as usize] - positions[e[1] as usize]).norm())
        .collect();
    ordered_sum(&lens) / lens.len() as f64
}

/// Sum in a fixed order (chunks summed in parallel, chunk sums added in sequence), so the result
/// does not depend on the thread count.
pub(crate) fn ordered_sum(x: &[f64]) -> f64 {
    let parts: Vec<f64> = x.par_chunks(8192).map(|c| c.iter().sum::<f64>()).collect();
    parts.iter().sum()
}

/// Mean and max distance between `before` and `after` over the movable vertices.
pub(crate) fn displacement_stats(
    before: &[Point3<f64>],
    after: &[Point3<f64>],
    movable: &[bool],
) -> (usize, f64, f64) {
    let d: Vec<f64> = before
        .par_iter()
        .zip(after)
        .zip(movable)
        .map(|((a, b), &m)| if m { (a - b).norm() } else { 0.0 })
        .collect();
    let n = movable.iter().filter(|&&m| m).count();
    let max = d.iter().copied().fold(0.0, f64::max);
    let mean = if n > 0 {
        ordered_sum(&d) / n as f64
    } else {
        0.0
    };
    (n, mean, max)
}

/// Volume constraint for the consistently oriented, edge-manifold components of a mesh: after
/// each iteration the movable vertices of such a component are moved along the volume gradient
/// (grad_v Vol = 1/6 sum over the faces at v of their crosses) by the one Newton step that restores
/// the component's initial volume. Mean-curvature flow shrinks a closed surface at a rate set by
/// its curvature (a sphere of radius R by 2 s / R per step); this undoes the shrinkage without
/// touching the shape's details, the volume-preserving variant of the flow.
///
/// An open component's volume is that of the surface with its holes capped by cones to the
/// component's initial centroid: while the boundary stays fixed the caps do not move, so the
/// constraint is exactly "no net motion along the normals" and holds an open scan or a hole fill
/// from sinking as well.
pub(crate) struct VolumeConstraint {
    /// Component per vertex (`u32::MAX` for vertices without faces).
    vertex_component: Vec<u32>,
    /// Component per face.
    face_component: Vec<u32>,
    /// Whether the component is consistently oriented with no edge of three or more faces.
    closed: Vec<bool>,
    /// Initial centroid per component, the apex of the hole caps.
    origin: Vec<Vector3<f64>>,
    /// Initial volume per component.
    target: Vec<f64>,
}

impl VolumeConstraint {
    pub(crate) fn new(mesh: &Mesh, adj: &Adjacency) -> VolumeConstraint {
        let nv = mesh.positions.len();
        let mut vertex_component = vec![u32::MAX; nv];
        let mut ncomp = 0u32;
        let mut stack = Vec::new();
        for s in 0..nv {
            if vertex_component[s] != u32::MAX || adj.faces_of_vertex(s).is_empty() {
                continue;
            }
            vertex_component[s] = ncomp;
            stack.push(s as u32);
            while let Some(v) = stack.pop() {
                for &u in adj.neighbors_of(v as usize) {
                    if vertex_component[u as usize] == u32::MAX {
                        vertex_component[u as usize] = ncomp;
                        stack.push(u);
                    }
                }
            }
            ncomp += 1;
        }
        let mut closed = vec![true; ncomp as usize];
        for (e, ed) in adj.edges.iter().enumerate() {
            let fs = adj.faces_of_edge(e);
            let c = vertex_component[ed[0] as usize] as usize;
            let ok = fs.len() == 1
                || fs.len() == 2 && {
                    // The two faces must walk the edge in opposite directions.
                    let dir = |f: u32| {
                        let t = mesh.faces[f as usize];
                        (0..3).any(|k| t[k] == ed[0] && t[(k + 1) % 3] == ed[1])
                    };
                    dir(fs[0]) != dir(fs[1])
                };
            if !ok {
                closed[c] = false;
            }
        }
        let face_component: Vec<u32> = mesh
            .faces
            .iter()
            .map(|f| vertex_component[f[0] as usize])
            .collect();
        let mut origin = vec![Vector3::zeros(); ncomp as usize];
        let mut count = vec![0usize; ncomp as usize];
        for (p, &c) in mesh.positions.iter().zip(&vertex_component) {
            if c != u32::MAX {
                origin[c as usize] += p.coords;
                count[c as usize] += 1;
            }
        }
        for (o, n) in origin.iter_mut().zip(&count) {
            *o /= (*n).max(1) as f64;
        }
        let mut vc = VolumeConstraint {
            vertex_component,
            face_component,
            closed,
            origin,
            target: Vec::new(),
        };
        vc.target = vc.volumes(&mesh.faces, &mesh.positions);
        vc
    }

    /// True when no component is constrained.
    pub(crate) fn is_empty(&self) -> bool {
        !self.closed.iter().any(|&c| c)
    }

    /// Volume per component (holes capped to `origin`): per-face terms in parallel, added in
    /// face order.
    fn volumes(&self, faces: &[[u32; 3]], positions: &[Point3<f64>]) -> Vec<f64> {
        let terms: Vec<f64> = faces
            .par_iter()
            .zip(&self.face_component)
            .map(|(f, &c)| {
                if c == u32::MAX || !self.closed[c as usize] {
                    return 0.0;
                }
                let o = self.origin[c as usize];
                let a = positions[f[0] as usize].coords - o;
                let b = positions[f[1] as usize].coords - o;
                let d = positions[f[2] as usize].coords - o;
                a.dot(&b.cross(&d)) / 6.0
            })
            .collect();
        let mut vol = vec![0.0; self.closed.len()];
        for (t, &c) in terms.iter().zip(&self.face_component) {
            if c != u32::MAX {
                vol[c as usize] += t;
            }
        }
        vol
    }

    /// Restores the initial volumes by one Newton step along `grads`, the volume gradient per
    /// vertex (zero where a vertex may not move), which may be taken at the positions before the
    /// last smoothing step: the volume error left is of second order and the next call, aiming at
    /// the initial volume again, removes it.
    pub(crate) fn apply(
        &self,
        faces: &[[u32; 3]],
        positions: &mut [Point3<f64>],
        grads: &[Vector3<f64>],
    ) {
        if self.is_empty() {
            return;
        }
        let vol = self.volumes(faces, positions);
        let mut g2 = vec![0.0; self.closed.len()];
        for (g, &c) in grads.iter().zip(&self.vertex_component) {
            if c != u32::MAX {
                g2[c as usize] += g.norm_squared();
            }
        }
        let tau: Vec<f64> = (0..self.closed.len())
            .map(|c| {
                let t = (self.target[c] - vol[c]) / g2[c];
                if self.closed[c] && t.is_finite() {
                    t
                } else {
                    0.0
                }
            })
            .collect();
        positions
            .par_iter_mut()
            .zip(grads)
            .zip(&self.vertex_component)
            .for_each(|((p, g), &c)| {
                if c != u32::MAX {
                    *p += g * tau[c as usize];
                }
            });
    }
}
