//! The region of a point on a segmented mesh, from the triangle it lies on.
//!
//! A mesh is segmented by its faces ([`super::segment_mesh`]), and the fit's points are its
//! vertices and samples on its triangles ([`crate::mesh::sample::sample_surface`]). The
//! nearest labelled vertex or face centre (what a cloud's points are labelled by) puts a
//! sample beside a crease in the wrong region half the time: a vertex on the crease is a
//! labelled point of both regions, and a face centre on the other side is as near as one on
//! the sample's own. A face of the other region then bends that region's side of a sharp
//! function away from its plane (a V block's groove root from its mesh: samples 0.1 mm up one
//! flank labelled as the other, the root 0.07 mm off). The triangle a point lies on
//! (the closest one, exactly, through a [`TriangleBvh`]) names its region: a sample inside a
//! triangle gets that triangle's, a point on a crease (at distance 0 from the faces of both
//! sides) either one, and it lies on both.
//!
//! The normal there is that region's alone: at each corner of a triangle the area-weighted
//! normal of the faces of the triangle's region around that vertex, interpolated
//! barycentrically at the closest point. A mesh's vertex normals average the faces of both
//! sides of a crease, so a vertex on a crease (and every sample of a triangle touching it)
//! carried a normal up to half the dihedral off its face: a sharp function's side is framed
//! by its points' normals, and a hole's rim in a flank (a V block's) was left to a smooth fit
//! when a fifth of the hole's points on it had normals along the flank.

use crate::mesh::Mesh;
use crate::spatial::fast_hash::IntMap;
use crate::spatial::TriangleBvh;
use crate::Result;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Barycentric weights of `q` (in the plane of the triangle `a b c`), clamped to the triangle
/// and summing to 1; equal weights on a degenerate triangle.
fn barycentric(q: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> [f64; 3] {
    let (e0, e1, d) = (b - a, c - a, q - a);
    let (d00, d01, d11) = (e0.dot(&e0), e0.dot(&e1), e1.dot(&e1));
    let (d20, d21) = (d.dot(&e0), d.dot(&e1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= f64::EPSILON * d00 * d11 || !den.is_finite() {
        return [1.0 / 3.0; 3];
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

/// A mesh's triangles with the region of each.
#[derive(Debug, Clone)]
pub struct FaceLabels {
    mesh: Mesh,
    bvh: TriangleBvh,
    label: Vec<u32>,
    /// Unit normals of each face's region at its three corners (module doc).
    corner: Vec<[Vector3<f64>; 3]>,
}

impl FaceLabels {
    /// The triangles of `mesh` (positions and faces; its normals are not kept) labelled by
    /// `label` (one region per face); `sign` is +1 when the faces wind outward, -1 when
    /// inward. Errors on a mesh without faces, on face indices past the vertex list, or on a
    /// label count that is not the face count.
    pub fn new(mesh: &Mesh, label: Vec<u32>, sign: f64) -> Result<FaceLabels> {
        if label.len() != mesh.faces.len() {
            return Err(crate::Error::Degenerate(format!(
                "{} face labels for {} faces",
                label.len(),
                mesh.faces.len()
            )));
        }
        let mesh = Mesh {
            positions: mesh.positions.clone(),
            normals: None,
            faces: mesh.faces.clone(),
        };
        let bvh = TriangleBvh::build(&mesh)?;
        // Area-weighted normal sums per (vertex, region).
        let mut sum: IntMap<(u32, u32), Vector3<f64>> = IntMap::default();
        for (fi, f) in mesh.faces.iter().enumerate() {
            let c = mesh.face_cross(fi);
            if c.iter().all(|x| x.is_finite()) {
                for &v in f {
                    *sum.entry((v, label[fi])).or_insert_with(Vector3::zeros) += c;
                }
            }
        }
        let corner = mesh
            .faces
            .iter()
            .zip(&label)
            .map(|(f, &r)| {
                f.map(|v| {
                    sum.get(&(v, r))
                        .and_then(|n| n.try_normalize(1e-300))
                        .map_or_else(Vector3::zeros, |n| n * sign)
                })
            })
            .collect();
        Ok(FaceLabels {
            mesh,
            bvh,
            label,
            corner,
        })
    }

    /// The region of the triangle closest to `x` and that region's unit normal there (module
    /// doc; zero on a degenerate triangle).
    pub fn region_and_normal_at(&self, x: &Point3<f64>) -> (u32, Vector3<f64>) {
        let (q, fi, _) = self.bvh.closest(&self.mesh, x);
        let f = self.mesh.faces[fi];
        let [a, b, c] = f.map(|v| self.mesh.positions[v as usize]);
        let w = barycentric(&q, &a, &b, &c);
        let n = self.corner[fi]
            .iter()
            .zip(w)
            .map(|(m, t)| m * t)
            .sum::<Vector3<f64>>();
        let n = n
            .try_normalize(1e-300)
            .or_else(|| {
                self.corner[fi]
                    .iter()
                    .find(|m| m.norm_squared() > 0.0)
                    .copied()
            })
            .unwrap_or_else(Vector3::zeros);
        (self.label[fi], n)
    }

    /// [`Self::region_and_normal_at`] of every point, in order.
    pub fn regions_and_normals_at(&self, points: &[Point3<f64>]) -> (Vec<u32>, Vec<Vector3<f64>>) {
        points
            .par_iter()
            .map(|x| self.region_and_normal_at(x))
            .unzip()
    }

    /// The region of the triangle closest to `x`.
    pub fn region_at(&self, x: &Point3<f64>) -> u32 {
        self.label[self.bvh.closest(&self.mesh, x).1]
    }

    /// [`Self::region_at`] of every point, in order.
    pub fn regions_at(&self, points: &[Point3<f64>]) -> Vec<u32> {
        points.par_iter().map(|x| self.region_at(x)).collect()
    }

    /// Relabels the faces by `map` (old region -> new).
    pub fn remap(&mut self, map: &[u32]) {
        for l in self.label.iter_mut() {
            *l = map[*l as usize];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of a V: face 0 in the plane z = y over y > 0 (region 3), face 1 in
    /// z = -y over y < 0 (region 5), meeting on the x axis.
    fn v() -> Mesh {
        Mesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(2.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 1.0),
                Point3::new(1.0, -1.0, 1.0),
            ],
            normals: None,
            faces: vec![[0, 1, 2], [1, 0, 3]],
        }
    }

    #[test]
    fn a_point_beside_the_crease_gets_its_own_triangle_s_region() {
        let f = FaceLabels::new(&v(), vec![3, 5], 1.0).unwrap();
        // 0.05 up each flank, beside the crease; a nearest-centre rule could give either.
        assert_eq!(f.region_at(&Point3::new(0.2, 0.05, 0.05)), 3);
        assert_eq!(f.region_at(&Point3::new(1.8, -0.05, 0.05)), 5);
        assert_eq!(
            f.regions_at(&[Point3::new(1.0, 0.9, 0.9), Point3::new(1.0, -0.9, 0.9)]),
            vec![3, 5]
        );
        let mut g = f.clone();
        g.remap(&[0, 0, 0, 1, 0, 1]);
        assert_eq!(g.region_at(&Point3::new(0.2, 0.05, 0.05)), 1);
    }

    #[test]
    fn labels_must_match_the_faces() {
        assert!(FaceLabels::new(&v(), vec![3], 1.0).is_err());
        let empty = Mesh {
            positions: vec![],
            normals: None,
            faces: vec![],
        };
        assert!(FaceLabels::new(&empty, vec![], 1.0).is_err());
    }

    #[test]
    fn the_normal_on_a_crease_is_its_own_region_s() {
        let f = FaceLabels::new(&v(), vec![3, 5], 1.0).unwrap();
        let s = std::f64::consts::FRAC_1_SQRT_2;
        // A sample beside the crease, and the crease vertex itself (averaged over both faces
        // by vertex normals: straight up).
        let (r, n) = f.region_and_normal_at(&Point3::new(0.2, 0.05, 0.05));
        let up = if n.z > 0.0 { 1.0 } else { -1.0 };
        assert_eq!(r, 3);
        assert!((n - Vector3::new(0.0, -s, s) * up).norm() < 1e-12, "{n}");
        let (r, n) = f.region_and_normal_at(&Point3::new(1.8, -0.05, 0.05));
        assert_eq!(r, 5);
        assert!((n - Vector3::new(0.0, s, s) * up).norm() < 1e-12, "{n}");
        // Turned by the winding sign.
        let g = FaceLabels::new(&v(), vec![3, 5], -1.0).unwrap();
        let (_, m) = g.region_and_normal_at(&Point3::new(0.2, 0.05, 0.05));
        assert!(
            (m + n.norm() * Vector3::new(0.0, -s, s) * up).norm() < 1e-12,
            "{m}"
        );
    }
}

#[cfg(test)]
mod segmentation_tests {
    use crate::features::{segment, FeatureOptions, MeshOptions};
    use crate::normals::oriented_points;

    #[test]
    fn a_box_mesh_s_points_get_one_sided_normals_with_the_option() {
        let mesh = crate::features::crease_mesh::tests::box_mesh(8);
        let op = oriented_points(&mesh, 12).unwrap();
        let axis_aligned =
            |n: &nalgebra::Vector3<f64>| n.iter().any(|c| (c.abs() - 1.0).abs() < 1e-9);
        let opts = |face_labels| FeatureOptions {
            mesh: MeshOptions {
                face_labels,
                ..Default::default()
            },
            ..Default::default()
        };
        let seg = segment(&mesh, &op, &opts(true)).unwrap();
        assert_eq!(seg.regions.len(), 6);
        let (l, n) = seg.labels_and_normals(&op.points, &op.normals);
        assert_eq!(l.len(), op.points.len());
        let off: Vec<_> = (0..n.len())
            .filter(|&i| !axis_aligned(&n[i]))
            .map(|i| (op.points[i], n[i], l[i]))
            .collect();
        assert!(
            off.is_empty(),
            "normals off their faces: {:?} of {} regions {}",
            &off[..off.len().min(3)],
            n.len(),
            seg.regions.len()
        );
        // Each point on its region's face: one coordinate fixed per region.
        for r in 0..seg.regions.len() as u32 {
            let on: Vec<usize> = (0..l.len()).filter(|&i| l[i] == r).collect();
            let k = (0..3).find(|&k| n[on[0]][k].abs() > 0.5).unwrap();
            assert!(on
                .iter()
                .all(|&i| (op.points[i][k] - op.points[on[0]][k]).abs() < 1e-9));
        }
        // Without it, the vertices on the edges keep the mesh's averaged normals.
        let seg = segment(&mesh, &op, &opts(false)).unwrap();
        let (_, n) = seg.labels_and_normals(&op.points, &op.normals);
        assert!(!n.iter().all(axis_aligned));
        // A mesh's crease cells are judged by those normals alone: no one-sided ones.
        let (_, m, sides) = seg.labels_normals_and_sides(&op.points, &op.normals);
        assert_eq!(m, n);
        assert!(sides.is_none());
    }

    #[test]
    fn a_box_cloud_s_points_beside_its_edges_get_their_own_face_s_normal() {
        // Points every 0.05 on the faces of the box [-1, 1]^3, no normals: PCA normals
        // (12 neighbours) beside an edge lean toward the other face; one-sided ones do not.
        let (mut pos, mut truth) = (Vec::new(), Vec::new());
        let k = 40;
        for axis in 0..3 {
            for side in [-1.0, 1.0] {
                for i in 0..k {
                    for j in 0..k {
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        let mut x = nalgebra::Point3::origin();
                        x[axis] = side;
                        x[u] = -1.0 + 2.0 * (i as f64 + 0.5) / k as f64;
                        x[v] = -1.0 + 2.0 * (j as f64 + 0.5) / k as f64;
                        pos.push(x);
                        truth.push(nalgebra::Vector3::ith(axis, side));
                    }
                }
            }
        }
        let cloud = crate::mesh::Mesh {
            positions: pos,
            normals: None,
            faces: Vec::new(),
        };
        let op = oriented_points(&cloud, 12).unwrap();
        let seg = segment(&cloud, &op, &FeatureOptions::default()).unwrap();
        assert_eq!(seg.regions.len(), 6);
        let (labels, _, sides) = seg.labels_normals_and_sides(&op.points, &op.normals);
        assert_eq!(labels, seg.labels_of(&op.points));
        let off = |n: &[nalgebra::Vector3<f64>]| {
            op.points
                .iter()
                .zip(n)
                .filter(|(p, m)| {
                    let t = truth[pos_index(&cloud.positions, p)];
                    m.dot(&t) < 10f64.to_radians().cos()
                })
                .count()
        };
        let sides = sides.expect("a cloud has one-sided normals");
        let (pca, one_sided) = (off(&op.normals), off(&sides));
        assert!(pca > 100, "{pca}");
        assert!(one_sided * 20 < pca, "one-sided {one_sided} PCA {pca}");
    }

    /// Index of `p` among `positions` (the oriented points keep the cloud's points).
    fn pos_index(positions: &[nalgebra::Point3<f64>], p: &nalgebra::Point3<f64>) -> usize {
        positions.iter().position(|q| q == p).unwrap_or(usize::MAX)
    }
}
