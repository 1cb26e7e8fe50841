//! Analytic test surfaces with known geometry, for the hole-filling tests and benchmarks: a
//! sphere, a torus and a saddle sheet, meshed finely and consistently (counter-clockwise seen
//! from outside), with the exact distance (or its first-order estimate) to each.

use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// A sphere of radius `r` about the origin meshed as a subdivided cube (`n` x `n` quads per cube
/// face, two triangles each: 12 n^2 triangles), with the cube's coordinates warped by tan so the
/// triangles are nearly uniform.
pub fn cube_sphere(n: usize, r: f64) -> Mesh {
    let n = n.max(1);
    let mut index: HashMap<[usize; 3], u32> = HashMap::new();
    let mut m = Mesh::default();
    let lattice_point = |a: [usize; 3]| {
        let w = |c: usize| (std::f64::consts::FRAC_PI_4 * (2.0 * c as f64 / n as f64 - 1.0)).tan();
        let v = Vector3::new(w(a[0]), w(a[1]), w(a[2]));
        Point3::from(v.normalize() * r)
    };
    // (axis, outward sign, u axis, v axis) with u x v pointing outward.
    let faces = [
        (0, 1, 1, 2),
        (0, 0, 2, 1),
        (1, 1, 2, 0),
        (1, 0, 0, 2),
        (2, 1, 0, 1),
        (2, 0, 1, 0),
    ];
    for &(axis, side, ua, va) in &faces {
        let mut id = |i: usize, j: usize, m: &mut Mesh| {
            let mut a = [0usize; 3];
            a[axis] = side * n;
            a[ua] = i;
            a[va] = j;
            *index.entry(a).or_insert_with(|| {
                m.positions.push(lattice_point(a));
                (m.positions.len() - 1) as u32
            })
        };
        for j in 0..n {
            for i in 0..n {
                let p00 = id(i, j, &mut m);
                let p10 = id(i + 1, j, &mut m);
                let p11 = id(i + 1, j + 1, &mut m);
                let p01 = id(i, j + 1, &mut m);
                m.faces.push([p00, p10, p11]);
                m.faces.push([p00, p11, p01]);
            }
        }
    }
    m
}

/// A torus about the z axis: tube centre radius `big`, tube radius `small`, `nu` x `nv` quads.
pub fn torus(big: f64, small: f64, nu: usize, nv: usize) -> Mesh {
    let (nu, nv) = (nu.max(3), nv.max(3));
    let mut m = Mesh::default();
    for i in 0..nu {
        let u = std::f64::consts::TAU * i as f64 / nu as f64;
        for j in 0..nv {
            let v = std::f64::consts::TAU * j as f64 / nv as f64;
            let rr = big + small * v.cos();
            m.positions
                .push(Point3::new(rr * u.cos(), rr * u.sin(), small * v.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + (j % nv)) as u32;
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            m.faces.push([a, b, c]);
            m.faces.push([a, c, d]);
        }
    }
    m
}

/// Distance from `p` to the torus of [`torus`].
pub fn torus_distance(p: &Point3<f64>, big: f64, small: f64) -> f64 {
    let q = (p.x * p.x + p.y * p.y).sqrt() - big;
    ((q * q + p.z * p.z).sqrt() - small).abs()
}

/// The saddle sheet z = k (x^2 - y^2) over [-a, a]^2, `n` x `n` quads, normals up.
pub fn saddle(n: usize, a: f64, k: f64) -> Mesh {
    let n = n.max(1);
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let x = -a + 2.0 * a * i as f64 / n as f64;
            let y = -a + 2.0 * a * j as f64 / n as f64;
            m.positions.push(Point3::new(x, y, k * (x * x - y * y)));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            m.faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            m.faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    m
}

/// First-order distance from `p` to the saddle of [`saddle`]: |g| / |grad g| for
/// g = z - k (x^2 - y^2).
pub fn saddle_distance(p: &Point3<f64>, k: f64) -> f64 {
    let g = p.z - k * (p.x * p.x - p.y * p.y);
    let grad = Vector3::new(-2.0 * k * p.x, 2.0 * k * p.y, 1.0);
    g.abs() / grad.norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_closed_or_open_as_expected() {
        let s = cube_sphere(6, 2.0);
        let t = s.topology();
        assert!(t.is_closed_manifold());
        assert_eq!(s.faces.len(), 12 * 36);
        assert!(s.signed_volume() > 0.0);
        assert!(s
            .positions
            .iter()
            .all(|p| (p.coords.norm() - 2.0).abs() < 1e-12));
        let tor = torus(2.0, 0.5, 24, 12);
        assert!(tor.topology().is_closed_manifold());
        assert!(tor.signed_volume() > 0.0);
        assert!(tor
            .positions
            .iter()
            .all(|p| torus_distance(p, 2.0, 0.5) < 1e-12));
        let sad = saddle(10, 1.0, 0.5);
        let ts = sad.topology();
        assert_eq!(ts.loops.len(), 1);
        assert!(ts.loops[0].outer_border);
        assert!(sad
            .positions
            .iter()
            .all(|p| saddle_distance(p, 0.5) < 1e-12));
    }
}
