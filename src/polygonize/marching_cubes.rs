//! Sparse marching cubes (seed 003 section 3.3, Fig. 3): the zero set of an implicit as a closed,
//! manifold, outward-oriented triangle mesh.
//!
//! Only cubes near the surface are visited: the search starts at the cubes that hold the seed
//! points (the input points) and floods to a neighbouring cube across every face whose corners
//! change sign, so its work is proportional to the surface area, never to the bounding grid.
//! Corner values of one wave of cubes are evaluated in parallel (rayon) and the triangles are
//! emitted in sorted cube order, so the mesh does not depend on the thread count.
//!
//! Triangulation (hand-written rather than a 256-case table, so that every choice is explicit):
//! on each cube face the sign changes are joined by segments; an ambiguous face (two diagonal
//! corners negative, two positive) is resolved by the asymptotic decider (the sign of the
//! bilinear interpolant at its saddle point), which depends only on the face's four values, so
//! both cubes sharing the face choose alike and the surface has no cracks. Segments are oriented
//! with the negative (inside) side consistently on one hand; in each cube they chain into closed
//! loops, each fanned into triangles (or, where a fan diagonal could join two vertices of one cube
//! face and so repeat an edge of the neighbouring cube, starred around a new centre vertex).
//! Every surface edge on a cube face is then shared by exactly the two triangles of the two cubes
//! beside it, and the mesh is a closed 2-manifold (corners outside the domain count as outside,
//! f > 0, which closes the surface there).
//! Vertices sit on grid edges (shared through a hash map) at the linear interpolation of the
//! corner values. Convention: f < 0 inside; triangles are counter-clockwise seen from outside.

use crate::implicit::Implicit;
use crate::mesh::{Aabb, Mesh};
use crate::spatial::fast_hash::{IntMap, IntSet};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Largest grid index per axis (21 bits).
const MAX_CELLS: i64 = (1 << 21) - 2;

/// A regular grid over a box.
#[derive(Debug, Clone, Copy)]
pub struct Grid {
    pub origin: Point3<f64>,
    pub cell: f64,
    /// Number of cubes per axis.
    pub dims: [i64; 3],
}

impl Grid {
    /// Grid of cube edge `cell` covering `domain`.
    pub fn new(domain: &Aabb, cell: f64) -> Result<Grid> {
        if !(cell > 0.0 && cell.is_finite()) {
            return Err(Error::InvalidOption(format!("grid cell size {cell}")));
        }
        let ext = domain.max - domain.min;
        let mut dims = [0i64; 3];
        for k in 0..3 {
            let n = (ext[k] / cell).ceil();
            if !(n.is_finite()) || n > MAX_CELLS as f64 {
                return Err(Error::InvalidOption(format!(
                    "grid of {n} cells per axis is too fine"
                )));
            }
            dims[k] = (n as i64).max(1);
        }
        // Sparse corner values and edge vertices of the crossed cubes (~256 bytes per cube).
        crate::limits::check_surface_grid([ext.x, ext.y, ext.z], cell, 256.0)?;
        Ok(Grid {
            origin: domain.min,
            cell,
            dims,
        })
    }
    #[inline]
    fn key(i: i64, j: i64, k: i64) -> u64 {
        (i as u64) | ((j as u64) << 21) | ((k as u64) << 42)
    }
    #[inline]
    fn unkey(key: u64) -> [i64; 3] {
        let m = (1u64 << 21) - 1;
        [
            (key & m) as i64,
            ((key >> 21) & m) as i64,
            ((key >> 42) & m) as i64,
        ]
    }
    #[inline]
    fn point(&self, g: [i64; 3]) -> Point3<f64> {
        self.origin + Vector3::new(g[0] as f64, g[1] as f64, g[2] as f64) * self.cell
    }
    /// The cube holding `p`, if inside the grid.
    fn cube_of(&self, p: &Point3<f64>) -> Option<[i64; 3]> {
        let mut c = [0i64; 3];
        for k in 0..3 {
            let x = ((p[k] - self.origin[k]) / self.cell).floor();
            if !(x >= 0.0 && x < self.dims[k] as f64) {
                return None;
            }
            c[k] = x as i64;
        }
        Some(c)
    }
    fn corner_inside(&self, g: [i64; 3]) -> bool {
        (0..3).all(|k| g[k] >= 1 && g[k] < self.dims[k])
    }
}

#[inline]
fn corner(c: [i64; 3], bits: usize) -> [i64; 3] {
    [
        c[0] + (bits & 1) as i64,
        c[1] + ((bits >> 1) & 1) as i64,
        c[2] + ((bits >> 2) & 1) as i64,
    ]
}

/// The six faces as (axis, side, corner bits in counter-clockwise order seen from outside).
fn faces() -> [(usize, usize, [usize; 4]); 6] {
    let mut out = [(0, 0, [0; 4]); 6];
    let mut n = 0;
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for s in 0..2 {
            // (b, c) cycle (0,0),(1,0),(1,1),(0,1) turns about +a.
            let mut cyc = [(0, 0), (1, 0), (1, 1), (0, 1)];
            if s == 0 {
                cyc.reverse();
            }
            let mut bits = [0usize; 4];
            for (i, (x, y)) in cyc.iter().enumerate() {
                bits[i] = (s << a) | (x << b) | (y << c);
            }
            out[n] = (a, s, bits);
            n += 1;
        }
    }
    out
}

/// Edge of the cube between corner bits `a` and `b` (differing in one bit) as (lower bits, axis).
#[inline]
fn edge_id(a: usize, b: usize) -> usize {
    let lo = a & b;
    let axis = (a ^ b).trailing_zeros() as usize;
    lo * 3 + axis
}

/// The surface loops inside one cube: all crossing cube-edge ids (lower corner bits * 3 + axis)
/// loop after loop, with each loop's length; oriented so that the fan triangles face outwards.
/// At most 12 edges in at most 4 loops.
#[derive(Debug, Default)]
struct Loops {
    edges: [u8; 12],
    lens: [u8; 4],
    count: usize,
}

fn cube_loops(v: &[f64; 8], faces: &[(usize, usize, [usize; 4]); 6]) -> Loops {
    let mut next = [u8::MAX; 24];
    for (_, _, bits) in faces {
        let fv = [v[bits[0]], v[bits[1]], v[bits[2]], v[bits[3]]];
        let neg = [fv[0] < 0.0, fv[1] < 0.0, fv[2] < 0.0, fv[3] < 0.0];
        // Crossings in counter-clockwise order: (edge id, is P = positive-to-negative).
        let mut cr: [(usize, bool); 4] = [(0, false); 4];
        let mut m = 0;
        for i in 0..4 {
            let j = (i + 1) % 4;
            if neg[i] != neg[j] {
                cr[m] = (edge_id(bits[i], bits[j]), !neg[i]);
                m += 1;
            }
        }
        match m {
            2 => {
                let (p, q) = if cr[0].1 {
                    (cr[0], cr[1])
                } else {
                    (cr[1], cr[0])
                };
                next[p.0] = q.0 as u8;
            }
            4 => {
                // Asymptotic decider: the bilinear interpolant's value at its saddle.
                let den = fv[0] + fv[2] - fv[1] - fv[3];
                let saddle = if den != 0.0 {
                    (fv[0] * fv[2] - fv[1] * fv[3]) / den
                } else {
                    0.0
                };
                let connect_negatives = saddle < 0.0;
                for i in 0..4 {
                    if cr[i].1 {
                        let q = if connect_negatives {
                            cr[(i + 3) % 4]
                        } else {
                            cr[(i + 1) % 4]
                        };
                        next[cr[i].0] = q.0 as u8;
                    }
                }
            }
            _ => {}
        }
    }
    let mut out = Loops::default();
    let mut seen = [false; 24];
    let mut total = 0usize;
    for s in 0..24 {
        if next[s] == u8::MAX || seen[s] {
            continue;
        }
        let first = total;
        let mut e = s;
        while e != u8::MAX as usize && !seen[e] && total < 12 {
            seen[e] = true;
            out.edges[total] = e as u8;
            total += 1;
            e = next[e] as usize;
        }
        let len = total - first;
        if len >= 3 && out.count < 4 {
            out.lens[out.count] = len as u8;
            out.count += 1;
        } else {
            total = first;
        }
    }
    out
}

/// The two cube faces (axis * 2 + side) holding cube edge `e` (lower corner bits * 3 + axis).
#[inline]
fn edge_faces(e: u8) -> [u8; 2] {
    let (lo, axis) = ((e / 3) as usize, (e % 3) as usize);
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    [
        (b * 2 + ((lo >> b) & 1)) as u8,
        (c * 2 + ((lo >> c) & 1)) as u8,
    ]
}

/// True when two non-consecutive vertices of a loop lie on one cube face, so that a fan
/// diagonal between them might also be a triangle edge in the neighbouring cube.
fn fan_could_repeat(edges: &[u8]) -> bool {
    let n = edges.len();
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (a, b) = (edge_faces(edges[i]), edge_faces(edges[j]));
            if a.iter().any(|x| b.contains(x)) {
                return true;
            }
        }
    }
    false
}

/// Polygonizes the zero set of `f` reachable from the cubes holding `seeds`, on a grid of cube
/// edge `cell` over `domain`. Corners outside the domain count as outside (f > 0), so the mesh is
/// closed even where the zero set would leave the domain.
pub fn marching_cubes<F: Implicit + ?Sized>(
    f: &F,
    seeds: &[Point3<f64>],
    domain: &Aabb,
    cell: f64,
) -> Result<Mesh> {
    let grid = Grid::new(domain, cell)?;
    let mut values: IntMap<u64, f64> = IntMap::default();
    let eval = |values: &mut IntMap<u64, f64>, cubes: &[[i64; 3]]| {
        let mut need: Vec<u64> = Vec::new();
        for c in cubes {
            for b in 0..8 {
                let g = corner(*c, b);
                let k = Grid::key(g[0], g[1], g[2]);
                if !values.contains_key(&k) {
                    need.push(k);
                }
            }
        }
        need.sort_unstable();
        need.dedup();
        let vals: Vec<f64> = need
            .par_iter()
            .map(|&k| {
                let g = Grid::unkey(k);
                if !grid.corner_inside(g) {
                    return 1.0;
                }
                let v = f.value(&grid.point(g));
                if v.is_nan() {
                    1.0
                } else {
                    v
                }
            })
            .collect();
        values.reserve(need.len());
        for (k, v) in need.into_iter().zip(vals) {
            values.insert(k, v);
        }
    };
    let cube_values = |values: &IntMap<u64, f64>, c: [i64; 3]| -> [f64; 8] {
        let mut v = [0.0; 8];
        for (b, x) in v.iter_mut().enumerate() {
            let g = corner(c, b);
            *x = values
                .get(&Grid::key(g[0], g[1], g[2]))
                .copied()
                .unwrap_or(1.0);
        }
        v
    };

    let mut frontier: Vec<[i64; 3]> = seeds.iter().filter_map(|p| grid.cube_of(p)).collect();
    frontier.sort_unstable();
    frontier.dedup();
    let mut visited: IntSet<u64> = frontier
        .iter()
        .map(|c| Grid::key(c[0], c[1], c[2]))
        .collect();
    let fcs = faces();
    let mut active: Vec<([i64; 3], [f64; 8])> = Vec::new();
    let mut first_wave = true;
    while !frontier.is_empty() {
        eval(&mut values, &frontier);
        let mut next = Vec::new();
        for &c in &frontier {
            let v = cube_values(&values, c);
            let nneg = v.iter().filter(|x| **x < 0.0).count();
            if nneg == 0 || nneg == 8 {
                if first_wave {
                    // A seed's own cube may just miss the surface: try its neighbours once.
                    for b in 0..27 {
                        let n = [c[0] + b % 3 - 1, c[1] + (b / 3) % 3 - 1, c[2] + b / 9 - 1];
                        if (0..3).all(|k| n[k] >= 0 && n[k] < grid.dims[k])
                            && visited.insert(Grid::key(n[0], n[1], n[2]))
                        {
                            next.push(n);
                        }
                    }
                }
                continue;
            }
            active.push((c, v));
            for (a, s, bits) in &fcs {
                let negs = bits.iter().filter(|&&b| v[b] < 0.0).count();
                if negs == 0 || negs == 4 {
                    continue;
                }
                let mut n = c;
                n[*a] += if *s == 1 { 1 } else { -1 };
                if n[*a] < 0 || n[*a] >= grid.dims[*a] {
                    continue;
                }
                if visited.insert(Grid::key(n[0], n[1], n[2])) {
                    next.push(n);
                }
            }
        }
        next.sort_unstable();
        frontier = next;
        first_wave = false;
    }
    drop(values);
    drop(visited);
    active.sort_unstable_by_key(|a| a.0);

    let mut mesh = Mesh::default();
    let mut vert: IntMap<(u64, u8), u32> = IntMap::default();
    vert.reserve(active.len() * 2);
    mesh.faces.reserve(active.len() * 2);
    mesh.positions.reserve(active.len());
    for (c, v) in &active {
        let loops = cube_loops(v, &fcs);
        let mut at = 0usize;
        for l in 0..loops.count {
            let len = loops.lens[l] as usize;
            let mut ids = [0u32; 12];
            for (k, &e) in loops.edges[at..at + len].iter().enumerate() {
                let e = e as usize;
                let (lo, axis) = (e / 3, e % 3);
                let hi = lo | (1 << axis);
                let ga = corner(*c, lo);
                let key = (Grid::key(ga[0], ga[1], ga[2]), axis as u8);
                ids[k] = *vert.entry(key).or_insert_with(|| {
                    let (fa, fb) = (v[lo], v[hi]);
                    let t = (fa / (fa - fb)).clamp(0.01, 0.99);
                    let pa = grid.point(ga);
                    let pb = grid.point(corner(*c, hi));
                    mesh.positions.push(pa + (pb - pa) * t);
                    (mesh.positions.len() - 1) as u32
                });
            }
            let edges = &loops.edges[at..at + len];
            if len > 3 && fan_could_repeat(edges) {
                // A fan diagonal between two vertices on one cube face could also be an edge of
                // the neighbouring cube's triangles (a non-manifold edge): a star around a new
                // centre vertex, private to this cube, instead.
                let centre = ids[..len]
                    .iter()
                    .map(|&i| mesh.positions[i as usize].coords)
                    .sum::<Vector3<f64>>()
                    / len as f64;
                mesh.positions.push(Point3::from(centre));
                let m = (mesh.positions.len() - 1) as u32;
                for k in 0..len {
                    mesh.faces.push([m, ids[k], ids[(k + 1) % len]]);
                }
            } else {
                for k in 1..len - 1 {
                    mesh.faces.push([ids[0], ids[k], ids[k + 1]]);
                }
            }
            at += len;
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;

    struct Sphere(f64);
    impl Implicit for Sphere {
        fn value(&self, x: &Point3<f64>) -> f64 {
            x.coords.norm() - self.0
        }
    }
    struct Torus(f64, f64);
    impl Implicit for Torus {
        fn value(&self, x: &Point3<f64>) -> f64 {
            let q = (x.x * x.x + x.y * x.y).sqrt() - self.0;
            (q * q + x.z * x.z).sqrt() - self.1
        }
    }
    /// Two spheres that nearly touch: many ambiguous faces.
    struct Pair;
    impl Implicit for Pair {
        fn value(&self, x: &Point3<f64>) -> f64 {
            let a = (x - Point3::new(-0.51, 0.0, 0.0)).norm() - 0.5;
            let b = (x - Point3::new(0.51, 0.03, 0.0)).norm() - 0.5;
            a.min(b)
        }
    }

    fn euler(m: &Mesh) -> i64 {
        let t = Topology::build(m);
        m.positions.len() as i64 - t.edges.len() as i64 + m.faces.len() as i64
    }

    fn domain(r: f64) -> Aabb {
        Aabb {
            min: Point3::new(-r, -r, -r),
            max: Point3::new(r, r, r),
        }
    }

    #[test]
    fn sphere_is_closed_genus_zero_and_outward() {
        let seeds = vec![Point3::new(0.7, 0.0, 0.0)];
        let m = marching_cubes(&Sphere(0.7), &seeds, &domain(1.0), 0.05).unwrap();
        assert!(Topology::build(&m).is_closed_manifold());
        assert_eq!(euler(&m), 2);
        assert!(m.signed_volume() > 0.0);
        let v = m.signed_volume();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.343;
        assert!((v - exact).abs() < 0.02 * exact, "{v} {exact}");
        for p in &m.positions {
            assert!((p.coords.norm() - 0.7).abs() < 0.01);
        }
    }

    #[test]
    fn torus_has_euler_zero() {
        let seeds = vec![Point3::new(0.8, 0.0, 0.0)];
        let m = marching_cubes(&Torus(0.6, 0.2), &seeds, &domain(1.0), 0.043).unwrap();
        assert!(Topology::build(&m).is_closed_manifold());
        assert_eq!(euler(&m), 0);
        assert!(m.signed_volume() > 0.0);
    }

    #[test]
    fn ambiguous_faces_stay_watertight() {
        for cell in [0.037, 0.05, 0.061, 0.083] {
            let seeds = vec![Point3::new(-1.01, 0.0, 0.0), Point3::new(1.01, 0.03, 0.0)];
            let m = marching_cubes(&Pair, &seeds, &domain(1.2), cell).unwrap();
            let t = Topology::build(&m);
            assert!(t.is_closed_manifold(), "cell {cell}");
            assert!(m.signed_volume() > 0.0);
        }
    }

    /// A wavy field with many saddles: lots of ambiguous faces and loops of 4 to 7 vertices.
    struct Waves;
    impl Implicit for Waves {
        fn value(&self, x: &Point3<f64>) -> f64 {
            (7.0 * x.x).sin() * (5.0 * x.y).cos() + (6.0 * x.z).sin() * (4.0 * x.x).cos()
                - 0.2 * (9.0 * x.y).sin()
                + x.coords.norm_squared()
                - 0.8
        }
    }

    /// Independent pseudo-random values at the corners of a grid of edge 0.1 (every kind of
    /// cube configuration, ambiguous faces everywhere), positive outside a ball.
    struct Noise;
    impl Implicit for Noise {
        fn value(&self, x: &Point3<f64>) -> f64 {
            if x.coords.norm() > 0.9 {
                return 1.0;
            }
            let k = x.coords.map(|c| (c * 10.0).round() as i64);
            let mut h = (k.x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ (k.y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
                ^ (k.z as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
            h ^= h >> 29;
            h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
            h ^= h >> 32;
            (h % 2001) as f64 / 1000.0 - 1.0
        }
    }

    #[test]
    fn random_corner_values_stay_manifold() {
        let seeds: Vec<_> = (0..2000)
            .map(|i| {
                let t = i as f64 * 0.731;
                Point3::new(
                    t.sin() * 0.8,
                    (1.37 * t).cos() * 0.8,
                    (0.53 * t).sin() * 0.8,
                )
            })
            .collect();
        let m = marching_cubes(&Noise, &seeds, &domain(1.0), 0.1).unwrap();
        let t = Topology::build(&m);
        assert!(m.faces.len() > 1000);
        assert!(
            t.is_closed_manifold(),
            "boundary {} non-manifold edges {} vertices {}",
            t.boundary_edge_count(),
            t.non_manifold_edges.len(),
            t.non_manifold_vertices.len()
        );
    }

    #[test]
    fn saddles_stay_manifold() {
        for cell in [0.031, 0.047, 0.063, 0.089, 0.13] {
            let seeds: Vec<_> = (0..200)
                .map(|i| {
                    let t = i as f64 * 0.31;
                    Point3::new(t.sin() * 0.9, (1.7 * t).cos() * 0.9, (0.7 * t).sin() * 0.9)
                })
                .collect();
            let m = marching_cubes(&Waves, &seeds, &domain(1.3), cell).unwrap();
            let t = Topology::build(&m);
            assert!(!m.faces.is_empty());
            assert!(
                t.is_closed_manifold(),
                "cell {cell}: boundary {} non-manifold edges {} vertices {}",
                t.boundary_edge_count(),
                t.non_manifold_edges.len(),
                t.non_manifold_vertices.len()
            );
        }
    }

    #[test]
    fn surface_leaving_the_domain_is_capped() {
        let seeds = vec![Point3::new(0.6, 0.6, 0.3)];
        let m = marching_cubes(&Sphere(0.9), &seeds, &domain(0.8), 0.05).unwrap();
        assert!(Topology::build(&m).is_closed_manifold());
        assert_eq!(euler(&m), 2);
    }

    #[test]
    fn bad_cell_size_is_an_error() {
        assert!(marching_cubes(&Sphere(0.5), &[], &domain(1.0), 0.0).is_err());
        assert!(marching_cubes(&Sphere(0.5), &[], &domain(1.0), 1e-9).is_err());
        let m = marching_cubes(&Sphere(0.5), &[], &domain(1.0), 0.1).unwrap();
        assert!(m.faces.is_empty());
    }
}
