//! Mesh vertices beside a crease moved onto it, where the edges from them across the crease
//! were left whole by [`super::crease_split`].
//!
//! A vertex that marching cubes put a small fraction of an edge from a crease has its crease
//! points at the very end of its edges across it (or past the end, or folding a triangle), so
//! the split keeps those edges whole, and the triangles on them cut the edge off by up to the
//! vertex's distance from it times the edge's slope (make_parts' block: 0.08 mm at the rim of
//! its through hole, a vertex 0.09 mm below it).
//!
//! **Snap.** For every edge (a, b) still crossing a crease (a and b original vertices of two
//! regions A and B), the crease point nearest to each end is found as the split finds it
//! (Gauss-Newton on f_A = f_B = 0 from the end, [`super::crease_split::meet_point`]); the end
//! nearer to its crease point moves onto it when that is within [`SNAP`] of the edge's length
//! and turns none of the triangles around the vertex over (each keeps its normal within 90
//! degrees of what it was, and its area). A vertex moves once; the spikes (below) move first,
//! then the edges' ends in the order of the faces, an edge one of whose ends moved as a spike
//! being left as it is; so the result does not depend on the thread count.
//!
//! **Spikes** (first). Marching cubes can leave a vertex of region B a whole cell from the
//! crease, between two crease points the split did put in, with only vertices of region A
//! between them around it (at a concave crease, whose inner corner the cubes' triangles cut:
//! make_parts' stepped shaft at its x = 65 shoulder, vertices 1.06 mm along the axis from the
//! crease, with 1.45 mm edges across it). The crease then runs from one crease point out to
//! the vertex and back to the next, and the crease-aligned net follows it (crease distance
//! 2.9e-3 of the diagonal there). Such a vertex, an end of an edge across the crease with two
//! or more crease points among its neighbours, moves onto the crease point found from the
//! nearest chord between two of them onto which it projects inside (from its projection; from
//! the vertex itself, a cell off, the other side's function may no longer be continued), when
//! that is no further from it than the chord's farther end.

use super::crease_split::{crossing_edges, meet_point, tri_normal, CreaseSplitOptions, SideField};
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Largest move, as a fraction of the crossing edge's length (block.stl: 0.35 moves 23 vertices,
/// 0.5 moves 27 and also fixes a spot 7e-4 of the diagonal off at the rim of its hole; a move
/// that would fold a triangle is refused either way).
pub const SNAP: f64 = 0.5;

/// Moves vertices onto the creases (module doc); returns how many moved. `label` gives the
/// region of the vertices before `first_new` (the mesh's vertices before the split).
pub fn snap_to_creases(
    mesh: &mut Mesh,
    field: &dyn SideField,
    label: &[u32],
    first_new: usize,
    opts: &CreaseSplitOptions,
) -> usize {
    let crossing = crossing_edges(&mesh.faces, label, first_new);
    let spikes = spike_moves(mesh, field, label, first_new, &crossing, opts);
    let pos = &mesh.positions;
    // Per edge: the end to move, where, and the other end, if within reach.
    let moves: Vec<Option<(u32, Point3<f64>, u32)>> = crossing
        .par_iter()
        .map(|&(a, b)| {
            let len = (pos[b as usize] - pos[a as usize]).norm();
            let regions = [label[a as usize], label[b as usize]];
            [a, b]
                .into_iter()
                .filter_map(|v| {
                    let p = pos[v as usize];
                    let c = meet_point(field, &regions, p, len, opts)?;
                    let d = (c - p).norm();
                    (d <= SNAP * len).then_some((d, v, c))
                })
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .map(|(_, v, c)| (v, c, if v == a { b } else { a }))
        })
        .collect();
    let ring = face_rings(mesh);
    let mut moved = vec![false; mesh.positions.len()];
    let mut count = 0;
    for (v, c) in spikes {
        if move_unfolded(mesh, &ring, v, c) {
            moved[v as usize] = true;
            count += 1;
        }
    }
    let spiked = moved.clone();
    // An edge one of whose ends moved onto the crease as a spike no longer crosses it there.
    for (v, c, other) in moves.into_iter().flatten() {
        if !moved[v as usize] && !spiked[other as usize] && move_unfolded(mesh, &ring, v, c) {
            moved[v as usize] = true;
            count += 1;
        }
    }
    count
}

/// The spikes' moves (module doc): per vertex before `first_new` with an edge across a crease
/// (`crossing`) and two or more crease points among its neighbours, the crease point found from
/// its projection onto the nearest chord between two of them ([`chord_start`]), if no further
/// than the chord's farther end.
fn spike_moves(
    mesh: &Mesh,
    field: &dyn SideField,
    label: &[u32],
    first_new: usize,
    crossing: &[(u32, u32)],
    opts: &CreaseSplitOptions,
) -> Vec<(u32, Point3<f64>)> {
    let pos = &mesh.positions;
    let mut creased: Vec<Vec<u32>> = vec![Vec::new(); first_new];
    for f in &mesh.faces {
        for k in 0..3 {
            let (v, w) = (f[k], f[(k + 1) % 3]);
            for (v, w) in [(v, w), (w, v)] {
                if (v as usize) < first_new && w as usize >= first_new {
                    let c = &mut creased[v as usize];
                    if !c.contains(&w) {
                        c.push(w);
                    }
                }
            }
        }
    }
    // The region across each vertex's crossing edges (None: no crossing edge; Some(None): two
    // or more regions, a corner).
    let mut across: Vec<Option<Option<u32>>> = vec![None; first_new];
    for &(a, b) in crossing {
        for (v, w) in [(a, b), (b, a)] {
            let r = label[w as usize];
            let e = &mut across[v as usize];
            *e = match *e {
                None => Some(Some(r)),
                Some(Some(s)) if s == r => Some(Some(r)),
                _ => Some(None),
            };
        }
    }
    (0..first_new)
        .into_par_iter()
        .filter_map(|v| {
            let other = across[v]??;
            let p = pos[v];
            let (start, reach) = chord_start(p, &creased[v], pos)?;
            let c = meet_point(field, &[label[v], other], start, reach, opts)?;
            ((c - p).norm() <= reach).then_some((v as u32, c))
        })
        .collect()
}

/// Of the chords between two of the crease points `creased` around a spike at `p`, the nearest
/// to it onto which it projects inside: the projection, and the farther end's distance from p.
fn chord_start(p: Point3<f64>, creased: &[u32], pos: &[Point3<f64>]) -> Option<(Point3<f64>, f64)> {
    let mut best: Option<(f64, Point3<f64>, f64)> = None;
    for (i, &ci) in creased.iter().enumerate() {
        for &cj in &creased[i + 1..] {
            let (a, b) = (pos[ci as usize], pos[cj as usize]);
            let ab = b - a;
            let t = (p - a).dot(&ab) / ab.norm_squared().max(1e-300);
            if !(0.0..=1.0).contains(&t) {
                continue;
            }
            let x = a + ab * t;
            let d = (p - x).norm();
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, x, (a - p).norm().max((b - p).norm())));
            }
        }
    }
    best.map(|(_, x, reach)| (x, reach))
}

/// The faces around each vertex, for [`move_unfolded`].
pub(super) fn face_rings(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
    for (i, f) in mesh.faces.iter().enumerate() {
        for &v in f {
            if let Some(r) = ring.get_mut(v as usize) {
                r.push(i as u32);
            }
        }
    }
    ring
}

/// Moves vertex `v` to `c` unless a triangle around it (`ring`, [`face_rings`]) turns over or
/// collapses; `true` when it moved.
pub(super) fn move_unfolded(mesh: &mut Mesh, ring: &[Vec<u32>], v: u32, c: Point3<f64>) -> bool {
    let faces = &ring[v as usize];
    let before: Vec<Vector3<f64>> = faces
        .iter()
        .map(|&i| tri_normal(&mesh.positions, &mesh.faces[i as usize]))
        .collect();
    let old = std::mem::replace(&mut mesh.positions[v as usize], c);
    let keeps = faces.iter().zip(&before).all(|(&i, b)| {
        let after = tri_normal(&mesh.positions, &mesh.faces[i as usize]);
        after.dot(b) > 0.0 && after.norm() > 1e-3 * b.norm()
    });
    if !keeps {
        mesh.positions[v as usize] = old;
    }
    keeps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two planes meeting at the crease x = 0 of the roof z = -|x| (region 0 for x < 0, 1 for
    /// x > 0), each side the plane of its half continued past the crease.
    struct Roof;
    impl SideField for Roof {
        fn region(&self, x: &Point3<f64>) -> u32 {
            u32::from(x.x > 0.0)
        }
        fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
            let s = if region == 1 { 1.0 } else { -1.0 };
            // z + s x = 0, normalised.
            let g = Vector3::new(s, 0.0, 1.0) / 2f64.sqrt();
            ((x.z + s * x.x) / 2f64.sqrt(), g)
        }
    }

    /// A strip of the roof across the crease: vertex 1 at x = -0.05 (a twentieth of an edge
    /// beside the crease), the others a whole edge away.
    fn strip() -> Mesh {
        let on = |x: f64, y: f64| Point3::new(x, y, -x.abs());
        Mesh {
            positions: vec![
                on(-1.0, 0.0),
                on(-0.05, 0.0),
                on(1.0, 0.0),
                on(1.0, 1.0),
                on(-1.0, 1.0),
            ],
            faces: vec![[0, 1, 4], [1, 3, 4], [1, 2, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn a_vertex_beside_the_crease_moves_onto_it() {
        let mut m = strip();
        let label = [0, 0, 1, 1, 0];
        let n = snap_to_creases(&mut m, &Roof, &label, 5, &CreaseSplitOptions::default());
        assert_eq!(n, 1);
        let p = m.positions[1];
        assert!(p.x.abs() < 1e-6 && p.z.abs() < 1e-6, "{p}");
        // The far vertices stay.
        assert_eq!(m.positions[0], Point3::new(-1.0, 0.0, -1.0));
        assert_eq!(m.positions[3], Point3::new(1.0, 1.0, -1.0));
    }

    #[test]
    fn a_spike_between_two_crease_points_moves_onto_the_crease() {
        // Vertex 0 on region 1, 1.13 from the crease, fanned by crease points 4 and 5 on it and
        // vertex 1 of region 0 between them: the crease ran 4 - 0 - 5.
        let on = |x: f64, y: f64| Point3::new(x, y, -x.abs());
        let mut m = Mesh {
            positions: vec![
                on(0.8, 0.5),
                on(-1.0, 0.5),
                on(1.0, 1.5),
                on(1.0, -0.5),
                on(0.0, 0.0),
                on(0.0, 1.0),
            ],
            faces: vec![[0, 4, 1], [0, 1, 5], [0, 5, 2], [0, 2, 3], [0, 3, 4]],
            ..Default::default()
        };
        let label = [1, 0, 1, 1];
        let opts = CreaseSplitOptions::default();
        // Too far for the snap of its edge across the crease (half of 1.81).
        let n = snap_to_creases(&mut m, &Roof, &label, 4, &opts);
        assert_eq!(n, 1);
        let p = m.positions[0];
        assert!((p - Point3::new(0.0, 0.5, 0.0)).norm() < 1e-6, "{p}");
        assert_eq!(m.positions[1], on(-1.0, 0.5));
    }

    #[test]
    fn vertices_far_from_the_crease_or_after_the_split_stay() {
        // Every vertex an edge from the crease: nothing within reach.
        let on = |x: f64, y: f64| Point3::new(x, y, -x.abs());
        let mut m = Mesh {
            positions: vec![on(-1.0, 0.0), on(1.0, 0.0), on(1.0, 1.0), on(-1.0, 1.0)],
            faces: vec![[0, 1, 2], [0, 2, 3]],
            ..Default::default()
        };
        let before = m.positions.clone();
        let n = snap_to_creases(
            &mut m,
            &Roof,
            &[0, 1, 1, 0],
            4,
            &CreaseSplitOptions::default(),
        );
        assert_eq!(n, 0);
        assert_eq!(m.positions, before);
        // Vertices from `first_new` on (crease points of the split) are not original ends.
        let mut m = strip();
        let n = snap_to_creases(&mut m, &Roof, &[0], 1, &CreaseSplitOptions::default());
        assert_eq!(n, 0);
    }
}
