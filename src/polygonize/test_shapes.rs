//! Analytic implicits for the tests of the quad net and the patch samples: sphere, torus, two
//! spheres almost touching, a thin slab, a dumbbell with a thin neck, a cube with rounded edges
//! (a smooth max of its six planes) and a bumpy blob. Each comes with seed points on its surface
//! and a bounding box, as a point cloud would give them.

use crate::implicit::Implicit;
use crate::mesh::Aabb;
use nalgebra::{Point3, Vector3};

pub struct Sphere {
    pub c: Point3<f64>,
    pub r: f64,
}
impl Implicit for Sphere {
    fn value(&self, x: &Point3<f64>) -> f64 {
        (x - self.c).norm() - self.r
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        (x - self.c).try_normalize(0.0).unwrap_or_else(Vector3::z)
    }
}

/// Torus around the z axis, major radius `big`, tube radius `small` (a signed distance).
pub struct Torus {
    pub big: f64,
    pub small: f64,
}
impl Implicit for Torus {
    fn value(&self, x: &Point3<f64>) -> f64 {
        let q = (x.x.hypot(x.y) - self.big).hypot(x.z);
        q - self.small
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        let rho = x.x.hypot(x.y).max(1e-300);
        let d = rho - self.big;
        let q = d.hypot(x.z).max(1e-300);
        Vector3::new(d * x.x / rho / q, d * x.y / rho / q, x.z / q)
    }
}

/// min(f1, f2): the union of two shapes (two components when they do not overlap).
pub struct Union<A, B>(pub A, pub B);
impl<A: Implicit, B: Implicit> Implicit for Union<A, B> {
    fn value(&self, x: &Point3<f64>) -> f64 {
        self.0.value(x).min(self.1.value(x))
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        if self.0.value(x) <= self.1.value(x) {
            self.0.gradient(x)
        } else {
            self.1.gradient(x)
        }
    }
}

/// Capsule: distance to the segment a-b minus r.
pub struct Capsule {
    pub a: Point3<f64>,
    pub b: Point3<f64>,
    pub r: f64,
}
impl Capsule {
    fn foot(&self, x: &Point3<f64>) -> Point3<f64> {
        let ab = self.b - self.a;
        let t = ((x - self.a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
        self.a + ab * t
    }
}
impl Implicit for Capsule {
    fn value(&self, x: &Point3<f64>) -> f64 {
        (x - self.foot(x)).norm() - self.r
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        (x - self.foot(x))
            .try_normalize(0.0)
            .unwrap_or_else(Vector3::z)
    }
}

/// Smooth union (polynomial smooth minimum of radius k): a fillet between the two shapes.
pub struct SmoothUnion<A, B> {
    pub a: A,
    pub b: B,
    pub k: f64,
}
impl<A: Implicit, B: Implicit> Implicit for SmoothUnion<A, B> {
    fn value(&self, x: &Point3<f64>) -> f64 {
        self.value_and_gradient(x).0
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.value_and_gradient(x).1
    }
    fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let (fa, ga) = (self.a.value(x), self.a.gradient(x));
        let (fb, gb) = (self.b.value(x), self.b.gradient(x));
        let h = (0.5 + 0.5 * (fb - fa) / self.k).clamp(0.0, 1.0);
        let v = fb * (1.0 - h) + fa * h - self.k * h * (1.0 - h);
        // d/dx of the blend; h' = (gb - ga) / (2k) inside the blend zone.
        let g = if h > 0.0 && h < 1.0 {
            let dh = (gb - ga) / (2.0 * self.k);
            gb * (1.0 - h) + ga * h + dh * (fa - fb) - dh * (self.k * (1.0 - 2.0 * h))
        } else if h >= 1.0 {
            ga
        } else {
            gb
        };
        (v, g)
    }
}

/// Rounded box: half extents `b` (of the inner box), rounding radius `r` (a signed distance).
pub struct RoundedBox {
    pub b: Vector3<f64>,
    pub r: f64,
}
impl Implicit for RoundedBox {
    fn value(&self, x: &Point3<f64>) -> f64 {
        let q = x.coords.abs() - self.b;
        let outside = q.map(|v| v.max(0.0)).norm();
        outside + q.max().min(0.0) - self.r
    }
}

/// Cube with rounded edges as a smooth maximum of its six planes:
/// f = k ln(sum exp((+-x_i - a) / k)). Faces are at distance a (flat parts), edges rounded with a
/// radius of a few k.
pub struct SoftCube {
    pub a: f64,
    pub k: f64,
}
impl Implicit for SoftCube {
    fn value(&self, x: &Point3<f64>) -> f64 {
        self.value_and_gradient(x).0
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.value_and_gradient(x).1
    }
    fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let m = x.coords.abs().max();
        let mut s = 0.0;
        let mut g = Vector3::zeros();
        for i in 0..3 {
            for sgn in [1.0, -1.0] {
                let e = ((sgn * x[i] - m) / self.k).exp();
                s += e;
                g[i] += sgn * e;
            }
        }
        (m - self.a + self.k * s.ln(), g / s)
    }
}

/// A sphere of radius r with bumps of amplitude `amp` and angular frequency `w`: a non-convex
/// blob with features of size about pi / w.
pub struct Blob {
    pub r: f64,
    pub amp: f64,
    pub w: f64,
}
impl Implicit for Blob {
    fn value(&self, x: &Point3<f64>) -> f64 {
        let w = self.w;
        x.coords.norm() - self.r - self.amp * (w * x.x).sin() * (w * x.y).sin() * (w * x.z).sin()
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        let w = self.w;
        let (sx, sy, sz) = ((w * x.x).sin(), (w * x.y).sin(), (w * x.z).sin());
        let (cx, cy, cz) = ((w * x.x).cos(), (w * x.y).cos(), (w * x.z).cos());
        let n = x.coords.try_normalize(0.0).unwrap_or_else(Vector3::z);
        n - Vector3::new(cx * sy * sz, sx * cy * sz, sx * sy * cz) * (self.amp * w)
    }
}

/// A smooth implicit from oriented points (IMLS, Kolluri 2005): f(x) = sum w_i n_i . (x - p_i) /
/// sum w_i with compactly supported weights w_i = (1 - |x - p_i|^2 / R^2)^4, R = 3 sigma, plus a positive bias c sigma (1 - W / W_ref)^2 where the weight sum W falls below
/// W_ref (sparse data: holes), so the zero set closes over holes. Far from every point it is
/// the distance to the nearest point. Test-only stand-in for the real implicit.
pub struct Imls {
    tree: kiddo::ImmutableKdTree<f64, 3>,
    pts: Vec<Point3<f64>>,
    nrm: Vec<Vector3<f64>>,
    sigma: f64,
    w_ref: f64,
}

impl Imls {
    pub fn new(pts: Vec<Point3<f64>>, nrm: Vec<Vector3<f64>>, sigma: f64) -> Imls {
        // Points without a usable normal (unreferenced vertices) are left out.
        let (pts, nrm): (Vec<_>, Vec<_>) = pts
            .into_iter()
            .zip(nrm)
            .filter(|(_, n)| n.iter().all(|x| x.is_finite()) && n.norm() > 0.5)
            .unzip();
        let entries: Vec<[f64; 3]> = pts.iter().map(|p| [p.x, p.y, p.z]).collect();
        let tree = kiddo::ImmutableKdTree::new_from_slice(&entries).unwrap();
        let mut f = Imls {
            tree,
            pts,
            nrm,
            sigma,
            w_ref: 1.0,
        };
        let mut ws: Vec<f64> = (0..f.pts.len())
            .step_by(97)
            .map(|i| f.weights(&f.pts[i]).2)
            .collect();
        ws.sort_by(f64::total_cmp);
        f.w_ref = 0.3 * ws[ws.len() / 2];
        f
    }
    /// (A, grad A, W, grad W) of the weighted sums.
    fn weights(&self, x: &Point3<f64>) -> (f64, Vector3<f64>, f64, Vector3<f64>) {
        let r2 = 9.0 * self.sigma * self.sigma;
        let found = self
            .tree
            .query(&[x.x, x.y, x.z])
            .within::<kiddo::SquaredEuclidean<f64>>(r2)
            .unsorted()
            .execute();
        let (mut a, mut ga, mut w, mut gw) = (0.0, Vector3::zeros(), 0.0, Vector3::zeros());
        for r in found {
            let i = r.item as usize;
            let d = x - self.pts[i];
            let q = 1.0 - d.norm_squared() / r2;
            if q <= 0.0 {
                continue;
            }
            let phi = q.powi(4);
            let dphi = d * (-8.0 / r2 * q.powi(3));
            let plane = self.nrm[i].dot(&d);
            a += phi * plane;
            ga += dphi * plane + self.nrm[i] * phi;
            w += phi;
            gw += dphi;
        }
        (a, ga, w, gw)
    }
}

impl Implicit for Imls {
    fn value(&self, x: &Point3<f64>) -> f64 {
        self.value_and_gradient(x).0
    }
    fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.value_and_gradient(x).1
    }
    fn value_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let near = self
            .tree
            .query(&[x.x, x.y, x.z])
            .nearest_one::<kiddo::SquaredEuclidean<f64>>()
            .execute();
        let i = near.item as usize;
        let (a, ga, w, gw) = self.weights(x);
        let e = 1e-3 * self.w_ref;
        let f_near = self.nrm[i].dot(&(x - self.pts[i]));
        // f = (A + e F_near) / (W + e), since W F = A.
        let den = w + e;
        let f = (a + e * f_near) / den;
        let g = (ga + self.nrm[i] * e - gw * f) / den;
        (f, g)
    }
}

/// Closes the boundary loops of a mesh with fans around each loop's centroid, sampled at about
/// `spacing`, and returns the extra points with their normals (consistent with the mesh's
/// orientation).
pub fn hole_fill_points(m: &crate::Mesh, spacing: f64) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
    let topo = m.topology();
    let (mut pts, mut nrm) = (Vec::new(), Vec::new());
    for lp in &topo.loops {
        let v: Vec<Point3<f64>> = lp
            .vertices
            .iter()
            .map(|&i| m.positions[i as usize])
            .collect();
        let c = Point3::from(v.iter().map(|p| p.coords).sum::<Vector3<f64>>() / v.len() as f64);
        for k in 0..v.len() {
            let (p, q) = (v[k], v[(k + 1) % v.len()]);
            // Faces walk p -> q; the fan face walks q -> p -> c.
            let n = (p - q).cross(&(c - q));
            let Some(n) = n.try_normalize(1e-300) else {
                continue;
            };
            let steps = (((c - p).norm().max((c - q).norm())) / spacing)
                .ceil()
                .max(1.0) as usize;
            for a in 0..=steps {
                for b in 0..=steps - a {
                    if a + b == 0 {
                        continue; // the centre, added once below
                    }
                    let (sa, sb) = (a as f64 / steps as f64, b as f64 / steps as f64);
                    if sa + sb >= 1.0 {
                        continue; // on the loop itself: mesh vertices are there
                    }
                    pts.push(c + (p - c) * sa + (q - c) * sb);
                    nrm.push(n);
                }
            }
        }
        let n: Vector3<f64> = (0..v.len())
            .map(|k| (v[k] - v[(k + 1) % v.len()]).cross(&(c - v[(k + 1) % v.len()])))
            .sum();
        if let Some(n) = n.try_normalize(1e-300) {
            pts.push(c);
            nrm.push(n);
        }
    }
    (pts, nrm)
}

/// Vertices and triangles of a simple OBJ (`v x y z`, `f a b c` with 1-based indices, `a/b/c`
/// forms allowed).
pub fn load_obj(path: &str) -> crate::Mesh {
    let text = std::fs::read_to_string(path).unwrap();
    let mut m = crate::Mesh::default();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let v: Vec<f64> = it.take(3).map(|x| x.parse().unwrap()).collect();
                m.positions.push(Point3::new(v[0], v[1], v[2]));
            }
            Some("f") => {
                let v: Vec<u32> = it
                    .map(|x| x.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..v.len() - 1 {
                    m.faces.push([v[0], v[k], v[k + 1]]);
                }
            }
            _ => {}
        }
    }
    m
}

/// `n` points on the zero set, found by projecting a Fibonacci sphere of radius `rad` around
/// `c` along the gradient.
pub fn seeds_on<I: Implicit + ?Sized>(
    f: &I,
    c: Point3<f64>,
    rad: f64,
    n: usize,
) -> Vec<Point3<f64>> {
    let opt = super::newton::NewtonOptions::new(rad, 0.25 * rad);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .filter_map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            let p = c + Vector3::new(rho * t.cos(), rho * t.sin(), z) * rad;
            super::newton::project(f, p, &opt).ok().map(|(q, _)| q)
        })
        .collect()
}

pub fn aabb(min: [f64; 3], max: [f64; 3]) -> Aabb {
    Aabb {
        min: Point3::from(min),
        max: Point3::from(max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Analytic gradients agree with central differences.
    #[test]
    fn gradients_match_differences() {
        fn check<I: Implicit>(f: &I, p: Point3<f64>) {
            let h = 1e-6;
            let mut d = Vector3::zeros();
            for k in 0..3 {
                let (mut a, mut b) = (p, p);
                a[k] += h;
                b[k] -= h;
                d[k] = (f.value(&a) - f.value(&b)) / (2.0 * h);
            }
            let g = f.value_and_gradient(&p).1;
            assert!((g - d).norm() < 1e-6, "{g} vs {d}");
        }
        let p = Point3::new(0.31, -0.47, 0.52);
        check(
            &Torus {
                big: 0.6,
                small: 0.2,
            },
            p,
        );
        check(&SoftCube { a: 0.5, k: 0.05 }, p);
        check(
            &Blob {
                r: 0.7,
                amp: 0.05,
                w: 9.0,
            },
            p,
        );
        check(
            &SmoothUnion {
                a: Sphere {
                    c: Point3::new(0.3, -0.4, 0.3),
                    r: 0.3,
                },
                b: Capsule {
                    a: Point3::origin(),
                    b: Point3::new(1.0, 0.0, 0.0),
                    r: 0.1,
                },
                k: 0.2,
            },
            p,
        );
    }
}
