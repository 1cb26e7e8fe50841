//! Creases put into a triangle mesh extracted from a sharp implicit: every mesh edge whose two
//! ends lie on different smooth regions is split where the two regions' surfaces meet, and
//! every triangle with three regions gets the corner where the three meet (the feature-
//! sensitive step of Kobbelt, Botsch, Schwanecke and Seidel 2001, "Feature sensitive surface
//! extraction from volume data", applied to the mesh after marching cubes rather than inside
//! each cube: marching cubes puts its vertices on the cube edges, so a triangle spanning a
//! crease cuts it off by up to half a cube, whatever the implicit).
//!
//! **Crease point of an edge (a, b)**, a on region A and b on region B: Gauss-Newton on the two
//! sides' functions (the implicit evaluated with region A's, then B's polynomial in the sharp
//! cells, [`SideField`]) from the edge's midpoint, each step the smallest that zeroes their
//! linearization:
//!
//! ```text
//! r = (f_A(x), f_B(x)),  J = [grad f_A; grad f_B] (2 x 3),  x <- x - J^T (J J^T)^-1 r
//! ```
//!
//! which converges to the point of the crease line f_A = f_B = 0 nearest to the start. It is
//! kept when it converged, the two gradients are not near parallel (the sides differ there: a
//! sharp cell covers the point) and it lies between a and b (its projection on the edge within
//! the edge, the angle a-c-b at least [`MIN_APEX_DEG`]): otherwise the edge stays whole. The
//! corner of a triangle with three regions is the same iteration with three functions (a 3 x 3
//! system).
//!
//! **Retriangulation.** An edge split is shared by both triangles of the edge, so the mesh stays
//! closed and manifold. A triangle with one split edge becomes two triangles (the new vertex
//! joined to the opposite corner); with two, a triangle at the corner they share and a quad
//! (split along its shorter diagonal); with three, three corner triangles around a middle one,
//! which is fanned from the corner point when that was found. Every new triangle keeps the
//! orientation of the one it replaces; a triangle one of whose pieces would turn over (a crease
//! point found beside the edge where the surface folds, a corner point off its middle) gives up
//! its splits, round after round, so the splitting never folds the mesh. Where that leaves
//! an edge across the crease between two crease points, it is flipped onto the crease
//! ([`super::crease_flip`]); a vertex beside a crease whose edges across it stayed whole moves
//! onto it ([`super::crease_snap`]).

use crate::mesh::Mesh;
use nalgebra::{Matrix2, Matrix3, Point3, Vector2, Vector3};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// What the splitting needs to know of the surface.
pub trait SideField: Sync {
    /// The smooth region of the surface near `x`.
    fn region(&self, x: &Point3<f64>) -> u32;
    /// f and grad f of the surface of `region`, continued past its creases.
    fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>);
}

/// Options of [`split_at_creases`].
#[derive(Debug, Clone, Copy)]
pub struct CreaseSplitOptions {
    /// Newton steps at most (default 30).
    pub max_steps: usize,
    /// Converged when every |f| is under this fraction of the edge length (default 1e-4).
    pub tolerance: f64,
    /// Smallest sine of the angle between two sides' gradients (default 0.1, about 6 degrees):
    /// below it the sides are one smooth surface there.
    pub min_sine: f64,
}

impl Default for CreaseSplitOptions {
    fn default() -> Self {
        CreaseSplitOptions {
            max_steps: 30,
            tolerance: 1e-4,
            min_sine: 0.1,
        }
    }
}

/// What [`split_at_creases`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct CreaseSplitReport {
    /// Edges whose ends lie on different regions.
    pub crossing_edges: usize,
    /// Of those, split at the crease.
    pub split_edges: usize,
    /// Triangles with three regions.
    pub corner_triangles: usize,
    /// Of those, given their corner point.
    pub corners: usize,
    /// Edges still crossing a crease between two crease points, flipped onto it
    /// ([`super::crease_flip`]).
    pub flipped_edges: usize,
    /// Vertices beside a crease whose edges across it stayed whole, moved onto it
    /// ([`super::crease_snap`]).
    pub snapped_vertices: usize,
    /// Corners the fold guard dropped, and corners where three regions meet around a vertex
    /// and in no triangle ([`super::ring_corners`]), put in by moving the vertex nearest to
    /// each onto it ([`super::corner_snap`]).
    pub snapped_corners: usize,
}

/// The point where the surfaces of `regions` meet nearest to `start` (two regions: a crease
/// point, three: a corner), or `None` (module doc).
pub fn meet_point(
    field: &dyn SideField,
    regions: &[u32],
    start: Point3<f64>,
    scale: f64,
    opts: &CreaseSplitOptions,
) -> Option<Point3<f64>> {
    let mut x = start;
    for _ in 0..opts.max_steps {
        let s: Vec<(f64, Vector3<f64>)> = regions.iter().map(|&r| field.side(r, &x)).collect();
        // The sides must differ: gradients far from parallel.
        for i in 0..s.len() {
            for j in i + 1..s.len() {
                let (gi, gj) = (s[i].1, s[j].1);
                let sine = gi.cross(&gj).norm() / (gi.norm() * gj.norm()).max(1e-300);
                // (NaN from a zero gradient fails too.)
                if sine.is_nan() || sine < opts.min_sine {
                    return None;
                }
            }
        }
        let done = s.iter().all(|(f, _)| f.abs() <= opts.tolerance * scale);
        if done {
            return Some(x);
        }
        let step = match s.len() {
            2 => {
                let (g0, g1) = (s[0].1, s[1].1);
                let jjt = Matrix2::new(g0.dot(&g0), g0.dot(&g1), g1.dot(&g0), g1.dot(&g1));
                let y = jjt.try_inverse()? * Vector2::new(s[0].0, s[1].0);
                g0 * y.x + g1 * y.y
            }
            3 => {
                let j = Matrix3::from_rows(&[
                    s[0].1.transpose(),
                    s[1].1.transpose(),
                    s[2].1.transpose(),
                ]);
                j.try_inverse()? * Vector3::new(s[0].0, s[1].0, s[2].0)
            }
            _ => return None,
        };
        if !step.iter().all(|c| c.is_finite()) || step.norm() > 2.0 * scale {
            return None;
        }
        x -= step;
    }
    None
}

/// Smallest angle a-c-b, in degrees, at which a crease point c found for the edge (a, b) is
/// kept (module doc). Marching cubes puts both ends of an edge across a crease on the two faces,
/// so the edge cuts off the crease and c lies off it: at a right-angled edge cut symmetrically
/// the angle is 90 degrees (c half the edge off), at the 70-degree edge of a dovetail 70; a
/// crease point much further off (a smaller angle) is a different part of the crease line.
const MIN_APEX_DEG: f64 = 45.0;

/// How far past its edges a triangle with three regions may have the corner it cuts off, in
/// barycentric coordinates of the corner's projection. Marching cubes cuts a corner with a
/// triangle whose vertices lie unevenly far from it, so that the corner's projection along the
/// triangle's normal can fall just outside (the wedge's box corners: down to -0.06); the fold guard
/// then still checks that the fan around the corner does not turn over.
const CORNER_MARGIN: f64 = 0.25;

/// cos of the angle a-c-b (-1 when c lies on the segment).
fn apex_cosine(a: Point3<f64>, b: Point3<f64>, c: Point3<f64>) -> f64 {
    let (u, v) = (a - c, b - c);
    let n = u.norm() * v.norm();
    if n <= 0.0 {
        return -1.0;
    }
    u.dot(&v) / n
}

/// Splits the edges and triangles of `mesh` that cross creases (module doc).
pub fn split_at_creases(
    mesh: &mut Mesh,
    field: &dyn SideField,
    opts: &CreaseSplitOptions,
) -> CreaseSplitReport {
    let mut report = CreaseSplitReport::default();
    let label: Vec<u32> = mesh.positions.par_iter().map(|p| field.region(p)).collect();
    let crossing = crossing_edges(&mesh.faces, &label, label.len());
    report.crossing_edges = crossing.len();
    let pos = &mesh.positions;
    let found: Vec<Option<Point3<f64>>> = crossing
        .par_iter()
        .map(|&(a, b)| {
            let (pa, pb) = (pos[a as usize], pos[b as usize]);
            let e = pb - pa;
            let len = e.norm();
            if len <= 0.0 {
                return None;
            }
            let mid = Point3::from((pa.coords + pb.coords) * 0.5);
            let regions = [label[a as usize], label[b as usize]];
            let c = meet_point(field, &regions, mid, len, opts)?;
            let t = (c - pa).dot(&e) / (len * len);
            (t > 0.0 && t < 1.0 && apex_cosine(pa, pb, c) <= MIN_APEX_DEG.to_radians().cos())
                .then_some(c)
        })
        .collect();
    // Every candidate becomes a vertex now; those a fold guard rejects are dropped at the end.
    let first_new = mesh.positions.len();
    let mut split: HashMap<(u32, u32), u32> = HashMap::new();
    for (&key, c) in crossing.iter().zip(&found) {
        if let Some(c) = c {
            split.insert(key, mesh.positions.len() as u32);
            mesh.positions.push(*c);
        }
    }
    // Corner points of triangles with three regions and three split edges.
    let all_split = |f: &[u32; 3], split: &HashMap<(u32, u32), u32>| {
        (0..3).all(|k| split.contains_key(&edge_key(f[k], f[(k + 1) % 3])))
    };
    let corner_faces: Vec<usize> = (0..mesh.faces.len())
        .filter(|&i| all_split(&mesh.faces[i], &split))
        .collect();
    report.corner_triangles = corner_faces.len();
    // Each corner with its triangle's longest edge (the reach of corner_snap).
    let corner_pts: Vec<Option<(Point3<f64>, f64)>> = corner_faces
        .par_iter()
        .map(|&i| {
            let f = mesh.faces[i];
            let p = f.map(|v| mesh.positions[v as usize]);
            let centre = mesh.face_centroid(i);
            let scale = (p[1] - p[0])
                .norm()
                .max((p[2] - p[1]).norm())
                .max((p[0] - p[2]).norm());
            let regions = f.map(|v| label[v as usize]);
            let c = meet_point(field, &regions, centre, scale, opts)?;
            // Over the triangle: the barycentric coordinates of its projection over
            // -CORNER_MARGIN.
            let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let inside = (0..3).all(|k| {
                let (u, v) = (p[k], p[(k + 1) % 3]);
                (v - u).cross(&(c - u)).dot(&n) > -CORNER_MARGIN * n.norm_squared()
            });
            inside.then_some((c, scale))
        })
        .collect();
    // Corners around a vertex, in no triangle (super::ring_corners).
    let triangle_corners: Vec<(Point3<f64>, f64)> = corner_pts.iter().flatten().copied().collect();
    let ring = super::ring_corners::ring_corners(
        &mesh.positions[..first_new],
        &mesh.faces,
        &label,
        field,
        opts,
        &triangle_corners,
    );
    let mut corner_of: HashMap<usize, u32> = HashMap::new();
    for (&i, c) in corner_faces.iter().zip(&corner_pts) {
        if let Some((c, _)) = c {
            corner_of.insert(i, mesh.positions.len() as u32);
            mesh.positions.push(*c);
        }
    }
    // Fold guard: a triangle whose pieces would turn against it gives up its splits (and its
    // corner), round after round until no piece turns over.
    for _ in 0..FOLD_ROUNDS {
        let pos = &mesh.positions;
        let bad: Vec<usize> = (0..mesh.faces.len())
            .into_par_iter()
            .filter(|&i| {
                let f = mesh.faces[i];
                let n = tri_normal(pos, &f);
                pieces(&f, &split, corner_of.get(&i).copied(), pos)
                    .iter()
                    .any(|t| tri_normal(pos, t).dot(&n) <= 0.0)
            })
            .collect();
        if bad.is_empty() {
            break;
        }
        // Edges of triangles with a corner point: their splits are dropped last.
        let corner_edges: HashSet<(u32, u32)> = corner_of
            .keys()
            .flat_map(|&i| {
                let f = mesh.faces[i];
                (0..3).map(move |k| edge_key(f[k], f[(k + 1) % 3]))
            })
            .collect();
        for i in bad {
            let f = mesh.faces[i];
            corner_of.remove(&i);
            if !drop_one_split(&f, &mut split, &corner_edges, pos) {
                for k in 0..3 {
                    split.remove(&edge_key(f[k], f[(k + 1) % 3]));
                }
            }
        }
        corner_of.retain(|&i, _| all_split(&mesh.faces[i], &split));
    }
    report.split_edges = split.len();
    report.corners = corner_of.len();
    // Corners the guard dropped, with the longest edge of their triangle as reach.
    let lost: Vec<(Point3<f64>, f64)> = corner_faces
        .iter()
        .zip(&corner_pts)
        .filter(|(i, _)| !corner_of.contains_key(i))
        .filter_map(|(_, c)| *c)
        .chain(ring)
        .collect();
    let mut faces = Vec::with_capacity(mesh.faces.len() + 2 * split.len());
    for (i, f) in mesh.faces.iter().enumerate() {
        faces.extend(pieces(
            f,
            &split,
            corner_of.get(&i).copied(),
            &mesh.positions,
        ));
    }
    mesh.faces = faces;
    // Drop the candidates the guard rejected (unreferenced vertices past `first_new`).
    let used = mesh.referenced();
    let mut map: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    let mut next = first_new as u32;
    for v in first_new..mesh.positions.len() {
        if used[v] {
            map[v] = next;
            mesh.positions[next as usize] = mesh.positions[v];
            next += 1;
        }
    }
    mesh.positions.truncate(next as usize);
    for f in mesh.faces.iter_mut() {
        *f = f.map(|v| map[v as usize]);
    }
    if let Some(n) = &mut mesh.normals {
        n.resize(mesh.positions.len(), Vector3::zeros());
    }
    report.flipped_edges = super::crease_flip::flip_across_creases(mesh, &label, first_new);
    report.snapped_vertices =
        super::crease_snap::snap_to_creases(mesh, field, &label, first_new, opts);
    report.snapped_corners = super::corner_snap::snap_to_corners(mesh, &lost);
    report
}

/// A triangle of the fold guard with two or three splits gives up only one of them when that
/// is enough for none of its pieces to turn over: on a curved crease cut by thin triangles two
/// crease points close together can lie in the wrong order along the crease for the triangle's
/// pieces, while either alone splits it well; dropping both left the edge across the crease,
/// and the neighbour sharing it then lost its splits too (make_parts' block from its mesh: the
/// hole's top rim cut off by 0.07 mm). The first such edge in the triangle's order is dropped,
/// edges of `corner_edges` (the triangles that get a corner point) last; `true` when one was.
fn drop_one_split(
    f: &[u32; 3],
    split: &mut HashMap<(u32, u32), u32>,
    corner_edges: &HashSet<(u32, u32)>,
    pos: &[Point3<f64>],
) -> bool {
    let n = tri_normal(pos, f);
    let mut keys: Vec<(u32, u32)> = (0..3)
        .map(|k| edge_key(f[k], f[(k + 1) % 3]))
        .filter(|e| split.contains_key(e))
        .collect();
    keys.sort_by_key(|e| corner_edges.contains(e));
    if keys.len() < 2 {
        return false;
    }
    for e in keys {
        let Some(v) = split.remove(&e) else { continue };
        if pieces(f, split, None, pos)
            .iter()
            .all(|t| tri_normal(pos, t).dot(&n) > 0.0)
        {
            return true;
        }
        split.insert(e, v);
    }
    false
}

/// Rounds of the fold guard at most.
const FOLD_ROUNDS: usize = 8;

/// An undirected edge's key.
fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// The edges of `faces` between vertices before `first_new` whose ends lie on different regions
/// (`label`), each once as its [`edge_key`], in the order of the faces.
pub(super) fn crossing_edges(
    faces: &[[u32; 3]],
    label: &[u32],
    first_new: usize,
) -> Vec<(u32, u32)> {
    let labelled = |v: u32| (v as usize) < first_new;
    let mut crossing: Vec<(u32, u32)> = Vec::new();
    let mut seen: HashSet<(u32, u32)> = HashSet::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if labelled(a) && labelled(b) && label[a as usize] != label[b as usize] {
                let key = edge_key(a, b);
                if seen.insert(key) {
                    crossing.push(key);
                }
            }
        }
    }
    crossing
}

/// The (unnormalized) normal of triangle `t`.
pub(super) fn tri_normal(pos: &[Point3<f64>], t: &[u32; 3]) -> Vector3<f64> {
    let p = t.map(|v| pos[v as usize]);
    (p[1] - p[0]).cross(&(p[2] - p[0]))
}

/// The triangles that replace `f` given the split edges and its corner point (module doc,
/// "Retriangulation"), in `f`'s orientation.
fn pieces(
    f: &[u32; 3],
    split: &HashMap<(u32, u32), u32>,
    corner: Option<u32>,
    pos: &[Point3<f64>],
) -> Vec<[u32; 3]> {
    let m: [Option<u32>; 3] =
        [0, 1, 2].map(|k| split.get(&edge_key(f[k], f[(k + 1) % 3])).copied());
    let dist2 = |a: u32, b: u32| (pos[a as usize] - pos[b as usize]).norm_squared();
    match m {
        [None, None, None] => vec![*f],
        [Some(x), Some(y), Some(z)] => {
            // x on (f0, f1), y on (f1, f2), z on (f2, f0).
            let mut out = vec![[f[0], x, z], [x, f[1], y], [z, y, f[2]]];
            match corner {
                Some(o) => out.extend([[x, y, o], [y, z, o], [z, x, o]]),
                None => out.push([x, y, z]),
            }
            out
        }
        _ if m.iter().flatten().count() == 1 => {
            // Rotated so that the split edge is (a, b).
            let k = (0..3).find(|&k| m[k].is_some()).unwrap_or(0);
            let (a, b, c) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            let x = m[k].unwrap_or(a);
            vec![[a, x, c], [x, b, c]]
        }
        _ => {
            // Rotated so that the whole edge is (b, c): a is the corner both splits share,
            // x on (a, b), y on (c, a).
            let k = (0..3).find(|&k| m[(k + 1) % 3].is_none()).unwrap_or(0);
            let (a, b, c) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            let (x, y) = (m[k].unwrap_or(a), m[(k + 2) % 3].unwrap_or(a));
            // The quad (x, b, c, y) along its shorter diagonal, unless only the other keeps
            // both halves facing the triangle's way: two crease points close together on a
            // curved crease make the quad a dart, and the fold guard would then drop both
            // splits (and the next triangle's, in a cascade).
            let n = tri_normal(pos, f);
            let faces_on = |t: &[[u32; 3]; 2]| t.iter().all(|t| tri_normal(pos, t).dot(&n) > 0.0);
            let along_xc = [[x, b, c], [x, c, y]];
            let along_by = [[x, b, y], [b, c, y]];
            let shorter_xc = dist2(x, c) <= dist2(b, y);
            let quad = match (faces_on(&along_xc), faces_on(&along_by)) {
                (true, false) => along_xc,
                (false, true) => along_by,
                _ if shorter_xc => along_xc,
                _ => along_by,
            };
            vec![[a, x, y], quad[0], quad[1]]
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::mesh::Topology;

    /// The cube [-1, 1]^3 as a sharp field: region k of face k (0..6: -x, +x, -y, +y, -z, +z),
    /// each side the plane of its face.
    pub(in crate::polygonize) struct Cube;
    impl SideField for Cube {
        fn region(&self, x: &Point3<f64>) -> u32 {
            let a = x.coords.abs();
            let k = a.imax();
            (2 * k + usize::from(x[k] > 0.0)) as u32
        }
        fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
            let k = (region / 2) as usize;
            let s = if region % 2 == 1 { 1.0 } else { -1.0 };
            (s * x[k] - 1.0, Vector3::ith(k, s))
        }
    }

    /// A subdivided icosahedron ([`crate::smooth::testing::sphere`]) pushed onto the cube along
    /// rays: every vertex on a face, triangles cutting the edges and corners (a marching-cubes
    /// mesh of a cube looks like this).
    fn rounded_cube(levels: u32) -> Mesh {
        let mut m = crate::smooth::testing::sphere(levels);
        // Rays nudged off the exact edges so that every vertex has one face.
        for p in m.positions.iter_mut() {
            let d = Vector3::new(p.x + 1e-3, p.y + 2e-3, p.z + 3e-3);
            *p = Point3::from(d / d.abs().max());
        }
        m
    }

    #[test]
    fn cube_edges_and_corners_come_back() {
        let mut mesh = rounded_cube(4);
        let before = Topology::build(&mesh);
        assert!(before.is_closed_manifold());
        let r = split_at_creases(&mut mesh, &Cube, &CreaseSplitOptions::default());
        assert!(
            r.split_edges > 0 && r.split_edges == r.crossing_edges,
            "{r:?}"
        );
        assert_eq!(r.corners, r.corner_triangles);
        assert!(Topology::build(&mesh).is_closed_manifold());
        // Every new vertex on an edge of the cube (two coordinates at +-1), the corners on
        // corners.
        let on_edges = mesh
            .positions
            .iter()
            .filter(|p| {
                p.coords
                    .iter()
                    .filter(|c| (c.abs() - 1.0).abs() < 1e-6)
                    .count()
                    >= 2
            })
            .count();
        assert!(on_edges >= r.split_edges + r.corners, "{on_edges} {r:?}");
        let corners = mesh
            .positions
            .iter()
            .filter(|p| p.coords.iter().all(|c| (c.abs() - 1.0).abs() < 1e-6))
            .count();
        assert_eq!(corners, 8, "{r:?}");
        // No triangle spans two faces any more: each lies in one face plane.
        for f in &mesh.faces {
            let p = f.map(|v| mesh.positions[v as usize]);
            let in_plane = (0..3).any(|k| {
                let v = p[0][k];
                (v.abs() - 1.0).abs() < 1e-6 && p.iter().all(|q| (q[k] - v).abs() < 1e-6)
            });
            assert!(in_plane, "{p:?}");
        }
        // Outward orientation kept: positive volume.
        assert!(mesh.signed_volume() > 7.0, "{}", mesh.signed_volume());
    }

    #[test]
    fn a_corner_just_past_its_triangle_comes_back() {
        // A triangle on three faces of the cube whose corner (1, 1, 1) projects just outside
        // it (barycentric -0.04 across one edge), as marching cubes cuts a corner unevenly.
        let mut mesh = Mesh {
            positions: vec![
                Point3::new(1.0, 0.58, 0.73),
                Point3::new(0.68, 1.0, 0.8),
                Point3::new(0.74, 0.52, 1.0),
            ],
            faces: vec![[0, 1, 2]],
            ..Default::default()
        };
        let r = split_at_creases(&mut mesh, &Cube, &CreaseSplitOptions::default());
        assert_eq!((r.split_edges, r.corners), (3, 1), "{r:?}");
        let corner = Point3::new(1.0, 1.0, 1.0);
        assert!(
            mesh.positions.iter().any(|p| (p - corner).norm() < 1e-6),
            "{:?}",
            mesh.positions
        );
        assert_eq!(mesh.faces.len(), 6);
    }

    #[test]
    fn an_acute_edge_cut_off_by_an_edge_is_split() {
        // The wedge 0 <= atan2(y, x) <= 70 degrees along the z axis: face A the half-plane
        // y = 0, face B at 70 degrees. The edge (a, b) cuts the crease off with the crease
        // point 0.71 of its length away (the angle a-c-b is 70 degrees).
        struct Wedge;
        const OPEN: f64 = 70.0;
        impl SideField for Wedge {
            fn region(&self, x: &Point3<f64>) -> u32 {
                u32::from(x.y.atan2(x.x).to_degrees() > 0.5 * OPEN)
            }
            fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
                let n = match region {
                    0 => Vector3::new(0.0, -1.0, 0.0),
                    _ => {
                        let t = OPEN.to_radians();
                        Vector3::new(-t.sin(), t.cos(), 0.0)
                    }
                };
                (n.dot(&x.coords), n)
            }
        }
        let t = OPEN.to_radians();
        let b = |z: f64| Point3::new(0.4 * t.cos(), 0.4 * t.sin(), z);
        let mut mesh = Mesh {
            positions: vec![
                Point3::new(0.4, 0.0, 0.0),
                b(0.0),
                Point3::new(0.4, 0.0, 1.0),
                b(-1.0),
            ],
            // Both triangles cross the crease; (0, 1) is the edge that cuts it off.
            faces: vec![[1, 0, 2], [0, 1, 3]],
            ..Default::default()
        };
        let r = split_at_creases(&mut mesh, &Wedge, &CreaseSplitOptions::default());
        assert!(r.split_edges >= 1, "{r:?}");
        assert!(
            mesh.positions.iter().any(|p| p.coords.norm() < 1e-6),
            "no vertex on the crease at the origin: {:?}",
            mesh.positions
        );
        // Every triangle now lies in one face: no triangle cuts the crease any more.
        for f in &mesh.faces {
            let regions: HashSet<u32> = f
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .filter(|p| p.x.hypot(p.y) > 1e-6)
                .map(|p| Wedge.region(&p))
                .collect();
            assert!(regions.len() <= 1, "{f:?} {:?}", mesh.positions);
        }
    }

    #[test]
    fn a_dart_quad_is_split_along_the_diagonal_that_does_not_fold() {
        // Crease points x on (a, b) and y on (c, a) leave the quad (x, b, c, y) a dart, reflex
        // at y: its shorter diagonal (x, c) turns a half over, the other does not.
        let pos = vec![
            Point3::new(0.0, 0.0, 0.0),   // b
            Point3::new(1.0, 0.0, 0.0),   // c
            Point3::new(0.5, 1.0, 0.0),   // a
            Point3::new(0.25, 0.5, 0.0),  // x on (a, b)
            Point3::new(0.95, 0.03, 0.0), // y on (c, a)
        ];
        let f = [0, 1, 2];
        let split: HashMap<(u32, u32), u32> = [(edge_key(2, 0), 3), (edge_key(1, 2), 4)]
            .into_iter()
            .collect();
        assert!((pos[3] - pos[1]).norm() < (pos[0] - pos[4]).norm());
        let n = tri_normal(&pos, &f);
        let p = pieces(&f, &split, None, &pos);
        assert_eq!(p.len(), 3);
        assert!(p.iter().all(|t| tri_normal(&pos, t).dot(&n) > 0.0), "{p:?}");
    }

    #[test]
    fn crossed_crease_points_give_up_one_split_not_both() {
        // The triangle (b, c, a) facing +z, crease points found for its edges (c, a) and
        // (a, b) in the wrong order (x of (a, b) right of y of (c, a)): the corner piece (a, x,
        // y) turns over whatever the quad's diagonal, either split alone does not.
        let pos = vec![
            Point3::new(0.0, 0.0, 0.0), // b
            Point3::new(1.0, 0.0, 0.0), // c
            Point3::new(0.5, 1.0, 0.0), // a
            Point3::new(0.6, 0.5, 0.0), // x on (a, b)
            Point3::new(0.4, 0.5, 0.0), // y on (c, a)
        ];
        let f = [0, 1, 2];
        let both: HashMap<(u32, u32), u32> = [(edge_key(2, 0), 3), (edge_key(1, 2), 4)]
            .into_iter()
            .collect();
        let n = tri_normal(&pos, &f);
        let folds = |s: &HashMap<(u32, u32), u32>| {
            pieces(&f, s, None, &pos)
                .iter()
                .any(|t| tri_normal(&pos, t).dot(&n) <= 0.0)
        };
        assert!(folds(&both));
        let mut split = both.clone();
        assert!(drop_one_split(&f, &mut split, &HashSet::new(), &pos));
        assert_eq!(split.len(), 1);
        assert!(!folds(&split));
        // One split only: nothing to choose.
        let mut one: HashMap<(u32, u32), u32> = [(edge_key(2, 0), 3)].into_iter().collect();
        assert!(!drop_one_split(&f, &mut one, &HashSet::new(), &pos));
        assert_eq!(one.len(), 1);
    }

    #[test]
    fn smooth_fields_split_nothing() {
        struct Ball;
        impl SideField for Ball {
            fn region(&self, x: &Point3<f64>) -> u32 {
                u32::from(x.x > 0.0)
            }
            fn side(&self, _: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
                (x.coords.norm() - 1.0, x.coords.normalize())
            }
        }
        let mut mesh = rounded_cube(3);
        for p in mesh.positions.iter_mut() {
            *p = Point3::from(p.coords.normalize());
        }
        let faces = mesh.faces.clone();
        let r = split_at_creases(&mut mesh, &Ball, &CreaseSplitOptions::default());
        assert!(r.crossing_edges > 0);
        assert_eq!(r.split_edges, 0);
        assert_eq!(mesh.faces, faces);
    }
}
