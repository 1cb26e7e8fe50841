//! Rings that fold under every projection plane are cut in two and each part is filled on its
//! own plane (seed 002 section 3.2 handles such loops with a user-chosen direction; this does it
//! automatically).
//!
//! The cut is the chord between two ring vertices that best separates the ring into parts that
//! can each be projected: the score adds, for each part, one minus the mean resultant length
//! |sum n_i| / count of its normals (0 when they all agree, near 1 when they spread around), and
//! half the ratio of the chord's length to the shorter way round the ring between its ends
//! (which favours the ring's narrowest neck). It is never an edge the mesh already has. New vertices are placed along the chord, about `target` apart, by the caller
//! (on the implicit surface, or on a circular arc), and both parts share them, so the fills of
//! the parts meet without a crack. Parts that still fold are cut again, up to `max_depth` times.

use super::patch::Patch;
use super::plane::{project_ring, Frame, PlaneKind};
use crate::error::{Error, Result};
use nalgebra::{Point2, Vector3};

/// How a ring was projected: one plane per part.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Projection {
    /// The plane used for each part, in the order the parts were filled.
    pub planes: Vec<PlaneKind>,
}

impl Projection {
    /// Number of parts the ring was cut into (1 when it projected whole).
    pub fn parts(&self) -> usize {
        self.planes.len()
    }
}

/// Meshes one projectable ring: adds faces (and new vertices) to the patch. Arguments: the
/// patch, the ring (local indices, fill order), its projection frame and 2D polygon.
pub type MeshPart<'a> = dyn FnMut(&mut Patch, &[u32], &Frame, &[Point2<f64>]) -> Result<()> + 'a;

/// Creates the `pieces - 1` inner vertices of a chord from local vertex `a` to `b`, in order from
/// `a`, and returns their indices.
pub type ChordNodes<'a> = dyn FnMut(&mut Patch, u32, u32, usize) -> Result<Vec<u32>> + 'a;

/// Fills `ring` (local indices in fill order), cutting it where no plane projects it without
/// folding. See the module doc.
pub fn fill_ring(
    patch: &mut Patch,
    ring: &[u32],
    direction: Option<Vector3<f64>>,
    target: f64,
    max_depth: usize,
    mesh_part: &mut MeshPart<'_>,
    chord: &mut ChordNodes<'_>,
) -> Result<Projection> {
    let mut proj = Projection::default();
    fill_rec(
        patch, ring, direction, target, max_depth, mesh_part, chord, &mut proj,
    )?;
    Ok(proj)
}

#[allow(clippy::too_many_arguments)]
fn fill_rec(
    patch: &mut Patch,
    ring: &[u32],
    direction: Option<Vector3<f64>>,
    target: f64,
    depth_left: usize,
    mesh_part: &mut MeshPart<'_>,
    chord: &mut ChordNodes<'_>,
    proj: &mut Projection,
) -> Result<()> {
    let pts: Vec<_> = ring.iter().map(|&v| patch.positions[v as usize]).collect();
    let nrm: Vec<_> = ring.iter().map(|&v| patch.normals[v as usize]).collect();
    if ring.len() == 3 {
        patch.faces.push([ring[0], ring[1], ring[2]]);
        proj.planes.push(PlaneKind::MeanNormal);
        return Ok(());
    }
    if let Some((frame, poly)) = project_ring(&pts, &nrm, direction) {
        mesh_part(patch, ring, &frame, &poly)?;
        proj.planes.push(frame.kind);
        return Ok(());
    }
    if depth_left == 0 {
        return Err(Error::Degenerate(
            "the hole folds under every projection plane, even after cutting it".into(),
        ));
    }
    let (i, j) = narrowest_chord(patch, ring).ok_or_else(|| {
        Error::Degenerate("the hole folds under every projection plane and cannot be cut".into())
    })?;
    let (a, b) = (ring[i], ring[j]);
    let pieces = ((patch.edge_length(a, b) / target).round() as usize).max(1);
    let inner = chord(patch, a, b, pieces)?;
    if !inner.is_empty() {
        // Both parts hold a .. b over the chord's nodes; neither may join a and b directly.
        patch.mesh_edges.insert(super::patch::key(a, b));
    }
    let m = ring.len();
    // Part 1: i .. j along the ring, back over the chord.
    let mut p1: Vec<u32> = Vec::new();
    let mut k = i;
    loop {
        p1.push(ring[k]);
        if k == j {
            break;
        }
        k = (k + 1) % m;
    }
    p1.extend(inner.iter().rev());
    // Part 2: j .. i along the ring, then over the chord toward j.
    let mut p2: Vec<u32> = Vec::new();
    let mut k = j;
    loop {
        p2.push(ring[k]);
        if k == i {
            break;
        }
        k = (k + 1) % m;
    }
    p2.extend(inner.iter());
    fill_rec(
        patch,
        &p1,
        direction,
        target,
        depth_left - 1,
        mesh_part,
        chord,
        proj,
    )?;
    fill_rec(
        patch,
        &p2,
        direction,
        target,
        depth_left - 1,
        mesh_part,
        chord,
        proj,
    )
}

/// The pair of ring positions (i < j, not neighbours, not joined by a mesh edge) of least score
/// (see the module doc). Prefix sums make each candidate O(1).
fn narrowest_chord(patch: &Patch, ring: &[u32]) -> Option<(usize, usize)> {
    let m = ring.len();
    if m < 4 {
        return None;
    }
    // Arc length and normal sums from ring[0] to each ring position.
    let mut cum = vec![0.0; m + 1];
    let mut nsum = vec![Vector3::zeros(); m + 1];
    for k in 0..m {
        cum[k + 1] = cum[k] + patch.edge_length(ring[k], ring[(k + 1) % m]);
        nsum[k + 1] = nsum[k] + patch.normals[ring[k] as usize];
    }
    let (total, ntotal) = (cum[m], nsum[m]);
    let mut best: Option<(f64, usize, usize)> = None;
    for i in 0..m {
        for j in i + 2..m {
            if i == 0 && j == m - 1 {
                continue;
            }
            let (a, b) = (ring[i], ring[j]);
            if a == b || patch.is_mesh_edge(a, b) {
                continue;
            }
            let along = cum[j] - cum[i];
            let around = along.min(total - along);
            if !(around > 0.0) {
                continue;
            }
            // Part 1 holds positions i..=j, part 2 j..=i (both hold the chord's ends).
            let n1 = nsum[j + 1] - nsum[i];
            let n2 = ntotal - nsum[j] + nsum[i + 1];
            let (c1, c2) = ((j - i + 1) as f64, (m - (j - i) + 1) as f64);
            let spread = (1.0 - n1.norm() / c1) + (1.0 - n2.norm() / c2);
            let cost = spread + 0.5 * patch.edge_length(a, b) / around;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, i, j));
            }
        }
    }
    best.map(|(_, i, j)| (i, j))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    /// The border of a band 0.2 high wound three quarters around a helix, normals pointing
    /// away from the axis: no plane has every normal on its side, so it must be cut.
    #[test]
    fn folded_ring_is_cut_and_both_parts_filled() {
        let mut pts = Vec::new();
        let path = |t: f64| {
            // A 3/4 turn helix: folds when projected along any direction.
            let a = 1.5 * std::f64::consts::PI * t;
            (
                Point3::new(a.cos(), a.sin(), 0.8 * t),
                Vector3::new(-a.sin(), a.cos(), 0.8),
            )
        };
        let n = 24;
        // Counter-clockwise seen from outside (the radial normals): along the lower edge, back
        // along the upper one.
        for k in 0..=n {
            let (p, _) = path(k as f64 / n as f64);
            pts.push(p - Vector3::new(0.0, 0.0, 0.1));
        }
        for k in (0..=n).rev() {
            let (p, _) = path(k as f64 / n as f64);
            pts.push(p + Vector3::new(0.0, 0.0, 0.1));
        }
        let len = pts.len();
        let normals: Vec<Vector3<f64>> = pts
            .iter()
            .map(|p| Vector3::new(p.x, p.y, 0.0).normalize())
            .collect();
        let mut patch =
            Patch::from_ring(pts, normals, (0..len as u32).collect(), Default::default());
        let ring: Vec<u32> = (0..len as u32).collect();
        let mut mesh_part = |p: &mut Patch, r: &[u32], _f: &Frame, poly: &[Point2<f64>]| {
            let forbidden = |i: usize, j: usize| p.is_mesh_edge(r[i], r[j]);
            let pm = super::super::recursive_mesh::recursive_mesh(
                poly,
                10.0,
                Default::default(),
                &forbidden,
            )?;
            assert_eq!(pm.points.len(), r.len(), "no inner nodes at this target");
            for t in &pm.triangles {
                p.faces.push([r[t[0]], r[t[1]], r[t[2]]]);
            }
            Ok(())
        };
        let mut chord = |p: &mut Patch, a: u32, b: u32, pieces: usize| {
            let (pa, pb) = (p.positions[a as usize], p.positions[b as usize]);
            let mut out = Vec::new();
            for k in 1..pieces {
                let t = k as f64 / pieces as f64;
                out.push(p.add_vertex(pa + (pb - pa) * t, Vector3::z()));
            }
            Ok(out)
        };
        let proj = fill_ring(&mut patch, &ring, None, 0.1, 6, &mut mesh_part, &mut chord).unwrap();
        assert!(proj.parts() >= 2, "{proj:?}");
        assert!(
            patch.check_topology().is_ok(),
            "{:?}",
            patch.check_topology()
        );
    }
}
