//! Shape quality of a quad net lying on an implicit surface: corner angles in 3D, flipped and
//! degenerate quads, distance of the nodes from f = 0.
//!
//! - Corner angle at corner k: the angle between the edges to corners k + 1 and k - 1, in 3D.
//! - Quad normal: N = (p2 - p0) x (p3 - p1), the cross product of the diagonals.
//! - Flipped: N . n <= 0, with n the implicit's normal at the quad centre (the centroid
//!   projected onto f = 0), or a reflex corner, `(p[k+1] - p[k]) x (p[k-1] - p[k]) . N <= 0`
//!   (a "dart" or bow-tie quad). Either gives a folded patch. Corner normals are not compared
//!   with the node normals: a quad wrapping the rim of a thin plate has corners on opposite
//!   faces and is still a good patch.
//! - Degenerate: a corner angle under 1 degree or over 179 degrees, or an edge shorter than
//!   1e-6 of the mean edge.
//! - Residual: max |f| / |grad f| over nodes (a first-order distance).

use super::newton::{project, NewtonOptions};
use super::quad_net::QuadNet;
use crate::implicit::Implicit;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Quality numbers of a net (angles in degrees).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NetQuality {
    pub min_angle_deg: f64,
    pub mean_angle_deg: f64,
    pub max_angle_deg: f64,
    /// Mean of |angle - 90 degrees| over all corners (the mean angle itself is about 90 for any
    /// net of nearly planar quads).
    pub mean_deviation_deg: f64,
    pub flipped: usize,
    pub degenerate: usize,
    /// max over nodes of |f| / |grad f|.
    pub max_residual: f64,
    /// Mean edge length.
    pub mean_edge: f64,
}

/// Per-quad shape: angles in degrees, flipped / degenerate flags.
#[derive(Debug, Clone, Copy)]
pub(crate) struct QuadShape {
    pub min: f64,
    pub sum: f64,
    pub max: f64,
    pub dev: f64,
    pub flipped: bool,
    pub degenerate: bool,
}

/// Shape of a quad given the surface normal `n` at its centre.
pub(crate) fn quad_shape(p: &[Point3<f64>; 4], n: &Vector3<f64>) -> QuadShape {
    let nq = (p[2] - p[0]).cross(&(p[3] - p[1]));
    let mut mn = f64::INFINITY;
    let mut mx = 0.0f64;
    let mut sum = 0.0;
    let mut dev = 0.0;
    let dn = nq.dot(n);
    let mut flipped = dn <= 0.0 || dn.is_nan();
    for k in 0..4 {
        let a = p[(k + 1) % 4] - p[k];
        let b = p[(k + 3) % 4] - p[k];
        let ang = a.angle(&b).to_degrees();
        let ang = if ang.is_finite() { ang } else { 0.0 };
        mn = mn.min(ang);
        mx = mx.max(ang);
        sum += ang;
        dev += (ang - 90.0).abs();
        let dc = a.cross(&b).dot(&nq);
        if dc <= 0.0 || dc.is_nan() {
            flipped = true;
        }
    }
    QuadShape {
        min: mn,
        sum,
        max: mx,
        dev,
        flipped,
        degenerate: mn < 1.0 || mx > 179.0,
    }
}

/// Unit normals of f at the quad centres. Where the unit normals at the four corners agree
/// (each within about 45 degrees of their mean) the normalized mean serves, at no cost;
/// otherwise (a quad wrapping a tight rim) the centroid is projected onto f = 0 (steps capped
/// at `h`) and the gradient there is used.
pub fn quad_normals<I: Implicit + ?Sized>(
    f: &I,
    net: &QuadNet,
    node_normals: &[Vector3<f64>],
    scale: f64,
    h: f64,
) -> Vec<Vector3<f64>> {
    let opt = NewtonOptions {
        tol: 1e-9 * scale,
        accept: 1e-6 * scale,
        max_step: h,
        max_iter: 20,
    };
    net.quads
        .par_iter()
        .map(|q| {
            let ns = q.map(|i| node_normals[i as usize]);
            let mean = (ns[0] + ns[1] + ns[2] + ns[3]).try_normalize(1e-12);
            if let Some(m) = mean {
                if ns.iter().all(|n| n.dot(&m) > 0.7) {
                    return m;
                }
            }
            let c = Point3::from(
                q.iter()
                    .map(|&i| net.nodes[i as usize].coords)
                    .sum::<Vector3<f64>>()
                    * 0.25,
            );
            let g = match project(f, c, &opt) {
                Ok((_, g)) => g,
                Err(_) => f.gradient(&c),
            };
            g.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
        })
        .collect()
}

/// Unit normals grad f / |grad f| at the nodes (zero where the gradient vanishes).
pub fn node_normals<I: Implicit + ?Sized>(f: &I, nodes: &[Point3<f64>]) -> Vec<Vector3<f64>> {
    nodes
        .par_iter()
        .map(|p| {
            f.gradient(p)
                .try_normalize(0.0)
                .unwrap_or_else(Vector3::zeros)
        })
        .collect()
}

/// Node residuals |f| / |grad f|.
pub fn node_residuals<I: Implicit + ?Sized>(f: &I, nodes: &[Point3<f64>]) -> Vec<f64> {
    nodes
        .par_iter()
        .map(|p| {
            let (v, g) = f.value_and_gradient(p);
            let r = v.abs() / g.norm();
            if r.is_finite() {
                r
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// Quality of `net` given the normals at the quad centres and the node residuals.
pub fn quality_with(net: &QuadNet, quad_normals: &[Vector3<f64>], residuals: &[f64]) -> NetQuality {
    let per: Vec<QuadShape> = net
        .quads
        .par_iter()
        .zip(quad_normals.par_iter())
        .map(|(q, n)| quad_shape(&q.map(|i| net.nodes[i as usize]), n))
        .collect();
    let edge_len: Vec<f64> = net
        .edges
        .iter()
        .map(|e| (net.nodes[e[0] as usize] - net.nodes[e[1] as usize]).norm())
        .collect();
    let mean_edge = edge_len.iter().sum::<f64>() / edge_len.len().max(1) as f64;
    let short: Vec<bool> = edge_len
        .iter()
        .map(|&l| l <= 1e-6 * mean_edge || l.is_nan())
        .collect();
    let mut q = NetQuality {
        min_angle_deg: f64::INFINITY,
        mean_angle_deg: 0.0,
        max_angle_deg: 0.0,
        mean_deviation_deg: 0.0,
        flipped: 0,
        degenerate: 0,
        max_residual: residuals.iter().fold(0.0, |a: f64, &b| a.max(b)),
        mean_edge,
    };
    for (i, s) in per.iter().enumerate() {
        q.min_angle_deg = q.min_angle_deg.min(s.min);
        q.max_angle_deg = q.max_angle_deg.max(s.max);
        q.mean_angle_deg += s.sum;
        q.mean_deviation_deg += s.dev;
        q.flipped += s.flipped as usize;
        let sh = net.quad_edges[i].iter().any(|&e| short[e as usize]);
        q.degenerate += (s.degenerate || sh) as usize;
    }
    let corners = (4 * per.len().max(1)) as f64;
    q.mean_angle_deg /= corners;
    q.mean_deviation_deg /= corners;
    q
}

/// Per quad of `net` on the implicit `f`: flipped (its normal against f's gradient at its
/// centre) or degenerate by its shape, as [`net_quality`] counts them (which also counts a
/// quad with an edge of near-zero length as degenerate).
pub fn folded_quads<I: Implicit + ?Sized>(net: &QuadNet, f: &I, scale: f64, h: f64) -> Vec<bool> {
    let n = quad_normals(f, net, &node_normals(f, &net.nodes), scale, h);
    net.quads
        .par_iter()
        .zip(n.par_iter())
        .map(|(q, n)| {
            let s = quad_shape(&q.map(|i| net.nodes[i as usize]), n);
            s.flipped || s.degenerate
        })
        .collect()
}

/// Quality of `net` on the implicit `f`; `scale` is the model size (for tolerances), `h` the
/// nominal edge length.
pub fn net_quality<I: Implicit + ?Sized>(net: &QuadNet, f: &I, scale: f64, h: f64) -> NetQuality {
    let n = quad_normals(f, net, &node_normals(f, &net.nodes), scale, h);
    let r = node_residuals(f, &net.nodes);
    quality_with(net, &n, &r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::quad_net::tests::cube;

    struct Ball;
    impl Implicit for Ball {
        fn value(&self, x: &Point3<f64>) -> f64 {
            (x - Point3::new(0.5, 0.5, 0.5)).norm() - 0.75f64.sqrt()
        }
    }

    #[test]
    fn cube_on_its_circumsphere() {
        let (nodes, quads) = cube();
        let net = QuadNet::new(nodes, quads).unwrap();
        let q = net_quality(&net, &Ball, 2.0, 1.0);
        assert!((q.min_angle_deg - 90.0).abs() < 1e-9);
        assert!((q.mean_angle_deg - 90.0).abs() < 1e-9);
        assert_eq!(q.flipped, 0);
        assert_eq!(q.degenerate, 0);
        assert!(q.max_residual < 1e-6);
        // Reversing every quad flips all of them.
        let (nodes, quads) = cube();
        let rev = quads.iter().map(|q| [q[0], q[3], q[2], q[1]]).collect();
        let net = QuadNet::new(nodes, rev).unwrap();
        assert_eq!(net_quality(&net, &Ball, 2.0, 1.0).flipped, 6);
    }
}
