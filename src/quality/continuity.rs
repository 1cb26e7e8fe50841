//! Normal jump across shared patch edges: the angle between the two patches' unit normals at
//! points along every edge that two faces share. On a face, an edge is one side of the
//! parameter rectangle (`Side::LOOP[k]` for `edges[k]`), so the parameters of an edge point on
//! both faces are known exactly and no projection is needed.
//!
//! One bicubic patch per quad cannot be exactly G1 at net vertices whose valence is not 4
//! (Peters & Fan): the report therefore separates edge samples next to such vertices from the
//! rest, so the shortfall is measured where it is, not averaged away.

use crate::nurbs::PatchNetwork;
use rayon::prelude::*;
use serde::Serialize;

/// Summary of normal jumps in degrees.
#[derive(Debug, Clone, Copy, Default, Serialize, PartialEq)]
pub struct AngleStats {
    pub samples: usize,
    pub max: f64,
    pub p95: f64,
    pub mean: f64,
}

impl AngleStats {
    fn of(a: &mut [f64]) -> AngleStats {
        if a.is_empty() {
            return AngleStats::default();
        }
        a.sort_by(f64::total_cmp);
        AngleStats {
            samples: a.len(),
            max: a[a.len() - 1],
            p95: a[((0.95 * a.len() as f64).ceil() as usize).clamp(1, a.len()) - 1],
            mean: a.iter().sum::<f64>() / a.len() as f64,
        }
    }
}

/// Normal jumps over all shared edges, and split by whether the sample lies in the half of an
/// edge next to an irregular vertex (valence != 4).
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct ContinuityReport {
    pub shared_edges: usize,
    pub all_deg: AngleStats,
    pub near_irregular_vertices_deg: AngleStats,
    pub elsewhere_deg: AngleStats,
    pub irregular_vertices: usize,
    /// Samples whose jump exceeds 1, 5 and 10 degrees (out of `all_deg.samples`).
    pub samples_over_1_deg: usize,
    pub samples_over_5_deg: usize,
    pub samples_over_10_deg: usize,
    /// Shared edges with at least one sample over 5 degrees.
    pub edges_over_5_deg: usize,
    /// The largest jumps (at most [`WORST_LISTED`]), largest first: where to look in a CAD
    /// viewer.
    pub worst: Vec<JumpSample>,
}

/// How many of the largest jumps [`ContinuityReport::worst`] lists.
pub const WORST_LISTED: usize = 10;

/// One measured normal jump.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct JumpSample {
    /// Edge index in the network (the order of the STEP EDGE_CURVEs).
    pub edge: usize,
    /// Position along the edge, 0..1 from its first vertex.
    pub t: f64,
    /// Point on the edge (first face's surface), model units.
    pub point: [f64; 3],
    pub angle_deg: f64,
    /// Whether the sample lies in the half of the edge next to an irregular vertex.
    pub near_irregular: bool,
}

/// Measures the normal jump at `samples_per_edge` interior points of every shared edge
/// (evenly spaced, (i + 0.5) / n, as cad_check does).
pub fn normal_jumps(net: &PatchNetwork, samples_per_edge: usize) -> ContinuityReport {
    // Which faces use each edge, at which loop position.
    let mut uses: Vec<Vec<(usize, usize, bool)>> = vec![Vec::new(); net.edges.len()];
    for (fi, f) in net.faces.iter().enumerate() {
        for (k, &(e, rev)) in f.edges.iter().enumerate() {
            uses[e as usize].push((fi, k, rev));
        }
    }
    let mut valence = vec![0usize; net.vertices.len()];
    for e in &net.edges {
        valence[e.v[0] as usize] += 1;
        valence[e.v[1] as usize] += 1;
    }
    let irregular: Vec<bool> = valence.iter().map(|&v| v != 4).collect();
    let n = samples_per_edge.max(1);
    let per_edge: Vec<Vec<JumpSample>> = uses
        .par_iter()
        .enumerate()
        .map(|(e, u)| {
            if u.len() != 2 {
                return Vec::new();
            }
            let ev = net.edges[e].v;
            (0..n)
                .filter_map(|i| {
                    let t = (i as f64 + 0.5) / n as f64;
                    let mut normals = [nalgebra::Vector3::zeros(); 2];
                    let mut point = [0.0; 3];
                    for (slot, &(fi, k, rev)) in u.iter().enumerate() {
                        let (uu, vv) = net.side_uv(fi, k, rev, t);
                        let face = &net.faces[fi];
                        if slot == 0 {
                            let p = face.surface.evaluate(uu, vv);
                            point = [p.x, p.y, p.z];
                        }
                        let nrm = face.surface.normal(uu, vv)?;
                        normals[slot] = if face.same_sense { nrm } else { -nrm };
                    }
                    let c = normals[0].dot(&normals[1]).clamp(-1.0, 1.0);
                    let near = if t < 0.5 {
                        irregular[ev[0] as usize]
                    } else {
                        irregular[ev[1] as usize]
                    };
                    Some(JumpSample {
                        edge: e,
                        t,
                        point,
                        angle_deg: c.acos().to_degrees(),
                        near_irregular: near,
                    })
                })
                .collect()
        })
        .collect();
    let mut all = Vec::new();
    let mut near = Vec::new();
    let mut far = Vec::new();
    let mut worst: Vec<JumpSample> = Vec::new();
    for s in per_edge.iter().flatten() {
        all.push(s.angle_deg);
        if s.near_irregular {
            near.push(s.angle_deg);
        } else {
            far.push(s.angle_deg);
        }
        worst.push(*s);
    }
    // Deterministic: by angle, ties by edge and position.
    worst.sort_by(|a, b| {
        b.angle_deg
            .total_cmp(&a.angle_deg)
            .then(a.edge.cmp(&b.edge))
            .then(a.t.total_cmp(&b.t))
    });
    let over = |d: f64| all.iter().filter(|&&a| a > d).count();
    let (samples_over_1_deg, samples_over_5_deg, samples_over_10_deg) =
        (over(1.0), over(5.0), over(10.0));
    let edges_over_5_deg = per_edge
        .iter()
        .filter(|e| e.iter().any(|s| s.angle_deg > 5.0))
        .count();
    worst.truncate(WORST_LISTED);
    ContinuityReport {
        samples_over_1_deg,
        samples_over_5_deg,
        samples_over_10_deg,
        edges_over_5_deg,
        shared_edges: uses.iter().filter(|u| u.len() == 2).count(),
        all_deg: AngleStats::of(&mut all),
        near_irregular_vertices_deg: AngleStats::of(&mut near),
        elsewhere_deg: AngleStats::of(&mut far),
        irregular_vertices: irregular.iter().filter(|&&x| x).count(),
        worst,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nurbs::BSplineSurface;
    use nalgebra::Point3;

    /// A flat bicubic patch with corners a (u,v)=(0,0), b (1,0), c (1,1), d (0,1).
    fn flat(a: Point3<f64>, b: Point3<f64>, c: Point3<f64>, d: Point3<f64>) -> BSplineSurface {
        let knots = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let ctrl = (0..4)
            .map(|i| {
                let s = i as f64 / 3.0;
                (0..4)
                    .map(|j| {
                        let t = j as f64 / 3.0;
                        let bottom = a + (b - a) * s;
                        let top = d + (c - d) * s;
                        bottom + (top - bottom) * t
                    })
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, knots.clone(), knots, ctrl).unwrap()
    }

    #[test]
    fn bent_pair_measures_the_fold_angle() {
        let alpha = 10f64.to_radians();
        let v = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(1.0 + alpha.cos(), 0.0, alpha.sin()),
            Point3::new(1.0 + alpha.cos(), 1.0, alpha.sin()),
        ];
        let a = flat(v[0], v[1], v[2], v[3]);
        let b = flat(v[1], v[4], v[5], v[2]);
        let net = crate::nurbs::network::side_by_side(a, b);
        let r = normal_jumps(&net, 5);
        assert_eq!(r.shared_edges, 1);
        assert_eq!(r.all_deg.samples, 5);
        assert!((r.all_deg.max - 10.0).abs() < 1e-9, "{r:?}");
        assert!((r.all_deg.mean - 10.0).abs() < 1e-9, "{r:?}");

        // Deviation: a point 0.25 above the first patch, and one on the second.
        let pts = [
            Point3::new(0.5, 0.5, 0.25),
            Point3::new(1.0 + 0.5 * alpha.cos(), 0.3, 0.5 * alpha.sin()),
        ];
        let d = crate::quality::deviation_from_patches(&net, &pts, 2.0);
        assert!((d.distances[0] - 0.25).abs() < 1e-9, "{:?}", d.distances);
        assert!(d.distances[1] < 1e-9, "{:?}", d.distances);
        assert!((d.stats.relative.max - 0.125).abs() < 1e-9);
    }
}
