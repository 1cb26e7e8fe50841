//! Bounding-volume hierarchy over the triangles of a mesh for exact closest-point queries.
//!
//! Built top-down by splitting the triangles at the median centroid along the longest axis of
//! their bounds (leaves of at most 8 triangles); a query descends nearer child first and prunes
//! every node whose box is farther than the best distance found, so the answer is exact for any
//! triangle shapes (long slivers included).

use crate::mesh::Mesh;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

#[derive(Debug, Clone, Copy)]
struct Node {
    min: Point3<f64>,
    max: Point3<f64>,
    /// Leaf: triangles `start..start + count` of the order; inner: children `start`, `start + 1`.
    start: u32,
    count: u32,
}

/// The hierarchy; it borrows nothing, queries take the mesh.
#[derive(Debug, Clone)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF: usize = 8;

#[inline]
fn box_dist2(p: &Point3<f64>, min: &Point3<f64>, max: &Point3<f64>) -> f64 {
    let mut d = 0.0;
    for k in 0..3 {
        let e = (min[k] - p[k]).max(0.0).max(p[k] - max[k]);
        d += e * e;
    }
    d
}

impl TriangleBvh {
    /// Builds the hierarchy over `mesh.faces`. Errors on a mesh without faces or with face
    /// indices past the vertex list.
    pub fn build(mesh: &Mesh) -> Result<TriangleBvh> {
        if mesh.faces.is_empty() {
            return Err(Error::Degenerate("no triangles".into()));
        }
        let nv = mesh.positions.len();
        if mesh.faces.iter().flatten().any(|&v| v as usize >= nv) {
            return Err(Error::Degenerate("face index past the vertex list".into()));
        }
        let tri_box = |f: &[u32; 3]| {
            let a = mesh.positions[f[0] as usize];
            let b = mesh.positions[f[1] as usize];
            let c = mesh.positions[f[2] as usize];
            (a.inf(&b).inf(&c), a.sup(&b).sup(&c))
        };
        let boxes: Vec<(Point3<f64>, Point3<f64>)> = mesh.faces.iter().map(tri_box).collect();
        let cent: Vec<Point3<f64>> = boxes.iter().map(|(a, b)| nalgebra::center(a, b)).collect();
        let mut order: Vec<u32> = (0..mesh.faces.len() as u32).collect();
        let mut nodes = vec![Node {
            min: Point3::origin(),
            max: Point3::origin(),
            start: 0,
            count: order.len() as u32,
        }];
        // (node index, range start, range end)
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((ni, s, e)) = stack.pop() {
            let mut lo = Point3::from(Vector3::repeat(f64::INFINITY));
            let mut hi = Point3::from(Vector3::repeat(f64::NEG_INFINITY));
            let mut clo = lo;
            let mut chi = hi;
            for &t in &order[s..e] {
                let (a, b) = boxes[t as usize];
                lo = lo.inf(&a);
                hi = hi.sup(&b);
                clo = clo.inf(&cent[t as usize]);
                chi = chi.sup(&cent[t as usize]);
            }
            nodes[ni].min = lo;
            nodes[ni].max = hi;
            if e - s <= LEAF {
                nodes[ni].start = s as u32;
                nodes[ni].count = (e - s) as u32;
                continue;
            }
            let ext = chi - clo;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (s + e) / 2;
            order[s..e].select_nth_unstable_by(mid - s, |a, b| {
                cent[*a as usize][axis]
                    .total_cmp(&cent[*b as usize][axis])
                    .then(a.cmp(b))
            });
            let c = nodes.len();
            nodes[ni].start = c as u32;
            nodes[ni].count = 0;
            for _ in 0..2 {
                nodes.push(Node {
                    min: lo,
                    max: hi,
                    start: 0,
                    count: 0,
                });
            }
            stack.push((c, s, mid));
            stack.push((c + 1, mid, e));
        }
        Ok(TriangleBvh { nodes, order })
    }

    /// The closest point of the mesh to `p`, its triangle index and distance. `mesh` must be
    /// the mesh the hierarchy was built from.
    pub fn closest(&self, mesh: &Mesh, p: &Point3<f64>) -> (Point3<f64>, usize, f64) {
        let mut best = (Point3::origin(), 0usize, f64::INFINITY);
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        stack.push((0, 0.0));
        while let Some((ni, d2)) = stack.pop() {
            if d2 >= best.2 {
                continue;
            }
            let n = &self.nodes[ni as usize];
            if n.count > 0 {
                for &t in &self.order[n.start as usize..(n.start + n.count) as usize] {
                    let [a, b, c] = mesh.faces[t as usize];
                    let q = crate::metrics::deviation::closest_point_on_triangle(
                        p,
                        &mesh.positions[a as usize],
                        &mesh.positions[b as usize],
                        &mesh.positions[c as usize],
                    );
                    let d = (q - p).norm_squared();
                    if d < best.2 {
                        best = (q, t as usize, d);
                    }
                }
            } else {
                let (l, r) = (n.start, n.start + 1);
                let dl = box_dist2(p, &self.nodes[l as usize].min, &self.nodes[l as usize].max);
                let dr = box_dist2(p, &self.nodes[r as usize].min, &self.nodes[r as usize].max);
                // Push the farther first so the nearer is searched first.
                if dl < dr {
                    stack.push((r, dr));
                    stack.push((l, dl));
                } else {
                    stack.push((l, dl));
                    stack.push((r, dr));
                }
            }
        }
        (best.0, best.1, best.2.sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::deviation::closest_point_on_triangle;

    #[test]
    fn matches_brute_force() {
        // A bumpy grid with some long slivers.
        let n = 20;
        let mut m = Mesh::default();
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                m.positions.push(Point3::new(
                    x,
                    y * y,
                    0.1 * (7.0 * x).sin() * (5.0 * y).cos(),
                ));
            }
        }
        for i in 0..n {
            for j in 0..n {
                let v = (i * (n + 1) + j) as u32;
                m.faces.push([v, v + n as u32 + 1, v + 1]);
                m.faces.push([v + 1, v + n as u32 + 1, v + n as u32 + 2]);
            }
        }
        m.faces.push([0, (n * (n + 1)) as u32, n as u32]);
        let bvh = TriangleBvh::build(&m).unwrap();
        for k in 0..200 {
            let t = k as f64 * 0.137;
            let p = Point3::new(t.sin() * 1.2, (1.3 * t).cos(), 0.3 * (2.1 * t).sin());
            let (_, _, d) = bvh.closest(&m, &p);
            let brute = m
                .faces
                .iter()
                .map(|f| {
                    let q = closest_point_on_triangle(
                        &p,
                        &m.positions[f[0] as usize],
                        &m.positions[f[1] as usize],
                        &m.positions[f[2] as usize],
                    );
                    (q - p).norm()
                })
                .fold(f64::INFINITY, f64::min);
            assert!((d - brute).abs() < 1e-12, "{d} {brute}");
        }
        assert!(TriangleBvh::build(&Mesh::default()).is_err());
    }
}
