//! Analytic test shapes and noise for the smoothing tests.

use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};

/// Deterministic Gaussian noise (xorshift64* + Box-Muller).
pub(crate) struct Noise(u64);

impl Noise {
    pub(crate) fn new(seed: u64) -> Noise {
        Noise(seed.max(1))
    }
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub(crate) fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// Moves every vertex along its (area-weighted) normal by Gaussian noise of `sigma`.
pub(crate) fn add_normal_noise(m: &mut Mesh, sigma: f64, seed: u64) {
    let n = crate::mesh::normals::vertex_normals(m);
    let mut g = Noise::new(seed);
    for (p, n) in m.positions.iter_mut().zip(n) {
        *p += n * (sigma * g.gauss());
    }
}

/// An n x n grid on the unit square in z = 0, unit spacing 1/n.
pub(crate) fn plane(n: u32) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            m.positions
                .push(Point3::new(i as f64 / n as f64, j as f64 / n as f64, 0.0));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            m.faces.push([a, a + 1, a + n + 2]);
            m.faces.push([a, a + n + 2, a + n + 1]);
        }
    }
    m
}

/// The cube [-1, 1]^3 with each side an n x n grid, vertices shared along the edges, faces
/// outward.
pub(crate) fn cube(n: u32) -> Mesh {
    let mut m = Mesh::default();
    let mut index = std::collections::HashMap::new();
    let key = |p: &Point3<f64>| {
        (
            (p.x * 1e6).round() as i64,
            (p.y * 1e6).round() as i64,
            (p.z * 1e6).round() as i64,
        )
    };
    // For each side: normal axis, sign; the two in-plane axes ordered so (u x v) = outward.
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut ids = vec![0u32; ((n + 1) * (n + 1)) as usize];
            for j in 0..=n {
                for i in 0..=n {
                    let mut p = Point3::origin();
                    p[axis] = sign;
                    p[u] = -1.0 + 2.0 * i as f64 / n as f64;
                    p[v] = -1.0 + 2.0 * j as f64 / n as f64;
                    let id = *index.entry(key(&p)).or_insert_with(|| {
                        m.positions.push(p);
                        (m.positions.len() - 1) as u32
                    });
                    ids[(j * (n + 1) + i) as usize] = id;
                }
            }
            for j in 0..n {
                for i in 0..n {
                    let a = ids[(j * (n + 1) + i) as usize];
                    let b = ids[(j * (n + 1) + i + 1) as usize];
                    let c = ids[((j + 1) * (n + 1) + i + 1) as usize];
                    let d = ids[((j + 1) * (n + 1) + i) as usize];
                    if sign > 0.0 {
                        m.faces.push([a, b, c]);
                        m.faces.push([a, c, d]);
                    } else {
                        m.faces.push([a, c, b]);
                        m.faces.push([a, d, c]);
                    }
                }
            }
        }
    }
    m
}

/// Unit sphere: an icosahedron subdivided `levels` times, projected.
pub(crate) fn sphere(levels: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<Vector3<f64>> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vector3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(faces.len() * 4);
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vector3<f64>>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) / 2.0).normalize());
                (pos.len() - 1) as u32
            })
        };
        for f in &faces {
            let ab = midpoint(f[0], f[1], &mut pos);
            let bc = midpoint(f[1], f[2], &mut pos);
            let ca = midpoint(f[2], f[0], &mut pos);
            next.push([f[0], ab, ca]);
            next.push([f[1], bc, ab]);
            next.push([f[2], ca, bc]);
            next.push([ab, bc, ca]);
        }
        faces = next;
    }
    Mesh {
        positions: pos.into_iter().map(Point3::from).collect(),
        normals: None,
        faces,
    }
}

/// Mean angle in degrees between the face normals and `n`.
pub(crate) fn mean_normal_error(m: &Mesh, n: &Vector3<f64>) -> f64 {
    let s: f64 = (0..m.faces.len())
        .map(|f| {
            m.face_cross(f)
                .normalize()
                .dot(n)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        })
        .sum();
    s / m.faces.len() as f64
}

/// True when every coordinate is finite.
pub(crate) fn all_finite(m: &Mesh) -> bool {
    m.positions.iter().all(|p| p.iter().all(|x| x.is_finite()))
}

/// A mesh of troubles: a good quad, a zero-area face (collinear), a face with a repeated vertex,
/// a needle, two coincident vertices with a face between them and a third, an isolated vertex.
pub(crate) fn degenerate() -> Mesh {
    let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
    Mesh {
        positions: vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(1.0, 1.0, 0.1),
            p(0.0, 1.0, 0.0),
            p(2.0, 0.0, 0.0),    // 4: collinear with 0, 1
            p(0.5, 0.5, 1e-300), // 5
            p(0.5, 0.5, 1e-300), // 6: coincident with 5
            p(9.0, 9.0, 9.0),    // 7: isolated
            p(1.0, 1e-15, 0.0),  // 8: needle tip next to 1
        ],
        normals: None,
        faces: vec![
            [0, 1, 2],
            [0, 2, 3],
            [0, 1, 4],
            [1, 1, 2],
            [5, 6, 2],
            [5, 6, 6],
            [1, 8, 2],
            [2, 3, 5],
        ],
    }
}
