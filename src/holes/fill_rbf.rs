//! Local implicit-surface hole filling (seed 000 section 2).
//!
//! 1. **Surface** (section 2.1, eq. 1-2): the interpolation points are the ring's vertices and
//!    the vertices of all faces touching it (one ring of faces, or `rings` of them), with value 0,
//!    plus as many points offset along the vertex normals with positive values, so that the
//!    surface leaves the hole's border with the border's tangent plane (C1). [`hole_samples`]
//!    collects them; any interpolant through them will do (`&dyn Implicit`): by default the
//!    local thin-plate RBF of [`super::rbf_local`].
//! 2. **Planar mesh** (section 2.2, eq. 3-7): the ring is projected onto its mean plane and
//!    meshed by recursive subdivision ([`super::recursive_mesh`]) with the mean edge length
//!    around the hole as the target.
//! 3. **Projection** (section 2.3, eq. 8-12): each new node moves along the plane normal onto
//!    the surface by Newton's method.
//! 4. **Relaxation** (eq. 13): nodes move to the area-weighted centroid of their triangles and
//!    back onto the surface along its normal.
//!
//! Between 3 and 4, 3D Delaunay edge flips ([`super::flip`]) remove the slivers recursive
//! subdivision leaves at the ring (not in the paper). Rings that fold under every plane are cut
//! ([`super::split`]).

use super::flip::delaunay_flips;
use super::neighbourhood::{ring_vertices, VertexFaces};
use super::patch::Patch;
use super::plane::Frame;
use super::recursive_mesh::{recursive_mesh, SplitWeights};
use super::relax::relax_on_surface;
use super::split::{fill_ring, Projection};
use crate::error::{Error, Result};
use crate::implicit::project::{project_along_within, project_gradient_within};
use crate::implicit::Implicit;
use crate::mesh::Mesh;
use nalgebra::{Point2, Point3, Vector3};

/// Options of the implicit-surface fill.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RbfOptions {
    /// Rings of faces around the border whose vertices the surface interpolates (seed 000
    /// Fig. 1 uses one).
    pub rings: usize,
    /// Distance of the off-surface points from the surface, as a multiple of the mean edge
    /// length around the hole.
    pub offset: f64,
    /// Sweeps of centroid relaxation with re-projection (eq. 13).
    pub relax_iterations: usize,
    /// Weights of the split cost (eq. 3).
    pub weights: SplitWeights,
}

impl Default for RbfOptions {
    fn default() -> Self {
        RbfOptions {
            rings: 1,
            offset: 1.0,
            relax_iterations: 3,
            weights: SplitWeights::default(),
        }
    }
}

/// The interpolation points and values around a hole (seed 000 eq. 1-2): every vertex within
/// `rings` face-rings of `boundary` with value 0, and, for each of them with a normal, the point
/// `offset` along the normal with value `offset`. The normals are the face-averaged `normals`,
/// or with `fit_normals` those of [`super::normal_fit`] (which do not lean away from the hole at
/// its border). An offset point that would land closer to another surface point than to its
/// own (a thin part, a sharp fold) is pulled in, halving the offset up to four times, or
/// dropped.
pub fn hole_samples(
    mesh: &Mesh,
    normals: &[Vector3<f64>],
    vf: &VertexFaces,
    boundary: &[u32],
    rings: usize,
    offset: f64,
    fit_normals: bool,
) -> (Vec<Point3<f64>>, Vec<f64>) {
    let verts = ring_vertices(mesh, vf, boundary, rings.max(1));
    let on: Vec<Point3<f64>> = verts.iter().map(|&v| mesh.positions[v as usize]).collect();
    let sample_normals: Vec<Vector3<f64>> = if fit_normals {
        super::normal_fit::fitted_normals(mesh, vf, normals, &verts)
    } else {
        verts.iter().map(|&v| normals[v as usize]).collect()
    };
    let mut pts = on.clone();
    let mut vals = vec![0.0; on.len()];
    for k in 0..verts.len() {
        let n = sample_normals[k];
        if !(n.norm() > 0.5) {
            continue;
        }
        let mut d = offset;
        for _ in 0..5 {
            let q = on[k] + n * d;
            // Closest on-surface point must be the source (ties allowed).
            let own = d * d;
            let clear = on
                .iter()
                .enumerate()
                .all(|(j, p)| j == k || (p - q).norm_squared() >= own * (1.0 - 1e-9));
            if clear {
                pts.push(q);
                vals.push(d);
                break;
            }
            d *= 0.5;
        }
    }
    (pts, vals)
}

/// What the fill did, for the report.
#[derive(Debug, Clone, Default)]
pub struct FillInfo {
    pub projection: Projection,
}

/// Fills the patch's ring on `surface` (steps 2-4 of the module doc). `target` is the edge
/// length to aim for, `size` the hole's size (the farthest a node may move when projected).
pub fn fill_on_surface(
    patch: &mut Patch,
    surface: &dyn Implicit,
    target: f64,
    size: f64,
    direction: Option<Vector3<f64>>,
    opts: &RbfOptions,
) -> Result<FillInfo> {
    let n = patch.ring_len() as u32;
    let ring: Vec<u32> = (0..n).collect();
    let tol = 1e-7 * target;
    let max_dist = size.max(target);
    let weights = opts.weights;
    let mut mesh_part =
        |p: &mut Patch, r: &[u32], frame: &Frame, poly: &[Point2<f64>]| -> Result<()> {
            let forbidden = |i: usize, j: usize| p.is_mesh_edge(r[i], r[j]);
            let pm = recursive_mesh(poly, target, weights, &forbidden)?;
            let mut ids: Vec<u32> = r.to_vec();
            for q in &pm.points[r.len()..] {
                let start = frame.to_3d(q);
                let x = project_along_within(surface, &start, &frame.normal, max_dist, tol)
                    .or_else(|| project_gradient_within(surface, &start, max_dist, tol))
                    .ok_or_else(|| {
                        Error::Numerical(
                            "a fill node has no surface point along the plane normal".into(),
                        )
                    })?;
                // The normal is set from the surface once the nodes have settled.
                ids.push(p.add_vertex(x, frame.normal));
            }
            for t in &pm.triangles {
                p.faces.push([ids[t[0]], ids[t[1]], ids[t[2]]]);
            }
            Ok(())
        };
    let mut chord = |p: &mut Patch, a: u32, b: u32, pieces: usize| -> Result<Vec<u32>> {
        let (pa, pb) = (p.positions[a as usize], p.positions[b as usize]);
        let mut out = Vec::with_capacity(pieces.saturating_sub(1));
        for k in 1..pieces {
            let start = pa + (pb - pa) * (k as f64 / pieces as f64);
            let x = project_gradient_within(surface, &start, max_dist, tol).ok_or_else(|| {
                Error::Numerical("a chord node has no surface point nearby".into())
            })?;
            let nrm = unit_gradient(surface, &x).unwrap_or_else(Vector3::z);
            out.push(p.add_vertex(x, nrm));
        }
        Ok(out)
    };
    let projection = fill_ring(
        patch,
        &ring,
        direction,
        target,
        4,
        &mut mesh_part,
        &mut chord,
    )?;
    delaunay_flips(patch, 20);
    let settled = relax_on_surface(patch, surface, opts.relax_iterations, max_dist, tol);
    for (v, &ok) in settled.iter().enumerate().skip(n as usize) {
        if !ok {
            if let Some(g) = unit_gradient(surface, &patch.positions[v]) {
                patch.normals[v] = g;
            }
        }
    }
    check_orientation(patch)?;
    Ok(FillInfo { projection })
}

/// grad f / |grad f| at `x`, when defined.
fn unit_gradient(f: &dyn Implicit, x: &Point3<f64>) -> Option<Vector3<f64>> {
    let g = f.gradient(x);
    let l = g.norm();
    (l > 0.0 && l.is_finite()).then(|| g / l)
}

/// Every fill face with a projected node must face the way the surface's gradient points
/// (outward) at its vertices (the new vertices' normals are the unit gradients); a face that
/// does not is a fold. Faces of ring vertices only are left to the
/// self-intersection check: their shape is the ring's, not the projection's, and where the ring
/// itself doubles back (a small bump cut in half) they can face any way without folding.
fn check_orientation(patch: &Patch) -> Result<()> {
    for f in &patch.faces {
        if f.iter().all(|&v| patch.is_fixed(v)) {
            continue;
        }
        let nf = patch.face_cross(f);
        let g: Vector3<f64> = f.iter().map(|&v| patch.normals[v as usize]).sum();
        if !(nf.dot(&g) > 0.0) {
            return Err(Error::Numerical(
                "the projected fill folds over (a face points against the surface normal)".into(),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sphere(f64);
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - self.0
        }
        fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
            x.coords.normalize()
        }
    }

    /// A ring of 30 points at polar angle 0.4 on the unit sphere, filled on the exact sphere:
    /// every new vertex must be on the sphere and the fill closed and outward.
    #[test]
    fn cap_on_an_exact_sphere() {
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
        let target = std::f64::consts::TAU * th.sin() / n as f64;
        let info = fill_on_surface(
            &mut patch,
            &Sphere(1.0),
            target,
            0.8,
            None,
            &RbfOptions::default(),
        )
        .unwrap();
        assert_eq!(info.projection.parts(), 1);
        assert!(
            patch.check_topology().is_ok(),
            "{:?}",
            patch.check_topology()
        );
        assert!(patch.positions.len() > n + 20);
        for p in &patch.positions {
            assert!((p.coords.norm() - 1.0).abs() < 1e-6);
        }
    }
}
