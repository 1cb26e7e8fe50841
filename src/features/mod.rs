//! Sharp features of the input: the smooth regions (faces) of a machined part and the creases
//! and corners where they meet, detected once and then consulted by the stages of `fit`
//! (the implicit of each region, the quad net whose edges run along the creases, the patches
//! that meet G0 there) instead of branches grown inside each stage.
//!
//! - [`detect`]: the whole detection for the `features` command (noise, regions, creases,
//!   corners), thresholds from the data;
//! - [`segment_mesh`]: regions of a triangle mesh (dihedral angles of its edges);
//! - [`segment_cloud`]: regions of a noisy point cloud (local quadric residuals and normal
//!   bend, region growing, the crease band assigned by distance to each side's surface);
//! - [`merge`]: regions that meet smoothly become one;
//! - [`folds`]: regions of a cloud creased along only part of their common boundary (a rim,
//!   a groove of an organic scan) become one;
//! - [`details`]: small regions of a mesh behind mild creases (organic detail) join a
//!   neighbour;
//! - [`crease_mesh`], [`crease_cloud`]: crease polylines and corners of each kind of input;
//! - [`lines`]: the polylines and corners, and the steps both kinds share;
//! - [`export`]: PLY files of the creases and of the labelled points;
//! - [`face_labels`]: the region of a point on a segmented mesh, from its triangle;
//! - [`net_regions`]: a patch network's quads labelled by region, its crease edges and nodes;
//! - [`local_fit`]: the local quadratic height functions the segmentations use;
//! - [`sharp_choice`]: whether a stage keeps the sharp edges (`--sharp on|off|auto`);
//! - [`union_find`]: disjoint sets.
//!
//! A [`Segmentation`] holds each region's points with one-sided normals (normals beside a
//! crease belong to their own face, not a blend of both), and a labelled point set that answers
//! "which region is the surface near x": the input points of a cloud, the vertices and face
//! centres of a mesh (or, with [`MeshOptions::face_labels`], the triangle a point lies on:
//! [`face_labels`]).

pub mod crease_cloud;
pub mod crease_mesh;
pub mod data_sides;
pub mod details;
pub mod detect;
pub mod export;
pub mod face_labels;
pub mod folds;
pub mod grid_frame;
pub mod lines;
pub mod local_fit;
pub mod merge;
pub mod net_regions;
pub mod segment_cloud;
pub mod segment_mesh;
pub mod sharp_choice;
pub mod sharp_field;
pub mod side_orientation;
pub mod union_find;

use crate::mesh::normals::vertex_normals;
use crate::mesh::Mesh;
use crate::normals::OrientedPoints;
use crate::spatial::KdTree;
use crate::Result;
use nalgebra::{Point3, Vector3};

pub use detect::{detect, DetectOptions, Features};
pub use lines::Crease;
pub use segment_cloud::{segment_cloud, CloudOptions};
pub use segment_mesh::{segment_mesh, MeshOptions};
pub use sharp_choice::{SharpChoice, SharpMode};

/// Two regions that meet at a crease.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RegionPair {
    pub a: u32,
    pub b: u32,
    /// Angle between the two sides' normals across their common boundary, degrees.
    pub dihedral_deg: f64,
    /// Size of the evidence: boundary point pairs (cloud) or common mesh edges (mesh).
    pub boundary_samples: usize,
}

/// The points of one smooth region with unit outward normals of that region alone.
#[derive(Debug, Clone, Default)]
pub struct Region {
    pub points: Vec<Point3<f64>>,
    pub normals: Vec<Vector3<f64>>,
}

/// Options of [`segment`].
#[derive(Debug, Clone, Copy, Default)]
pub struct FeatureOptions {
    pub mesh: MeshOptions,
    pub cloud: CloudOptions,
}

/// What the segmentation found, for the report.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct SegmentStats {
    /// "mesh" (dihedral angles) or "cloud" (local fits).
    pub method: &'static str,
    pub regions: usize,
    /// Region pairs that meet at a crease, with their dihedral angles.
    pub pairs: Vec<RegionPair>,
    /// Points per region.
    pub region_points: Vec<usize>,
    /// Median residual of the cloud's local fits (about its noise), absolute; 0 for a mesh.
    pub sigma: f64,
    pub seconds: f64,
}

/// Smooth regions of an input and the means to ask which region a point is near.
#[derive(Debug)]
pub struct Segmentation {
    pub regions: Vec<Region>,
    /// Labelled points (positions, region of each) and their tree.
    label_points: Vec<Point3<f64>>,
    label_of: Vec<u32>,
    /// The one-sided unit normal of each labelled point (its region's alone), for a cloud.
    label_normals: Option<Vec<Vector3<f64>>>,
    label_kd: KdTree,
    /// A mesh's triangles with their regions (`None` for a cloud).
    faces: Option<face_labels::FaceLabels>,
    pub stats: SegmentStats,
}

impl Segmentation {
    /// A segmentation from regions given directly (tests, callers that segment otherwise): the
    /// labelled points are the regions' own.
    pub fn from_regions(regions: Vec<Region>, stats: SegmentStats) -> Result<Segmentation> {
        let mut label_points = Vec::new();
        let mut label_of = Vec::new();
        let mut label_normals = Vec::new();
        for (r, reg) in regions.iter().enumerate() {
            label_points.extend(reg.points.iter().copied());
            label_of.extend(std::iter::repeat_n(r as u32, reg.points.len()));
            label_normals.extend(
                (0..reg.points.len()).map(|i| reg.normals.get(i).copied().unwrap_or_default()),
            );
        }
        let label_kd = KdTree::build(&label_points)?;
        Ok(Segmentation {
            regions,
            label_points,
            label_of,
            label_normals: Some(label_normals),
            label_kd,
            faces: None,
            stats,
        })
    }

    /// The labelled points and their regions.
    pub fn labelled(&self) -> (&[Point3<f64>], &[u32]) {
        (&self.label_points, &self.label_of)
    }

    /// The tree of the labelled points.
    pub fn label_tree(&self) -> &KdTree {
        &self.label_kd
    }

    /// Region of the labelled point nearest to `x`.
    pub fn region_near(&self, x: &Point3<f64>) -> u32 {
        self.label_of[self.label_kd.nearest(x).0]
    }

    /// Regions of the labelled points among the `k` nearest to `x`, with their counts, most
    /// frequent first (ties by region id).
    pub fn regions_near(&self, x: &Point3<f64>, k: usize) -> Vec<(u32, usize)> {
        let mut v: Vec<u32> = self
            .label_kd
            .knn(x, k)
            .into_iter()
            .map(|(i, _)| self.label_of[i])
            .collect();
        v.sort_unstable();
        let mut out: Vec<(u32, usize)> = Vec::new();
        for l in v {
            match out.last_mut() {
                Some((m, c)) if *m == l => *c += 1,
                _ => out.push((l, 1)),
            }
        }
        out.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        out
    }

    /// The region of each of `points`: the labels of a feature-aware implicit
    /// ([`crate::implicit::PouImplicit::fit_with_regions`]) that keeps every input point. On a
    /// mesh segmented with [`MeshOptions::face_labels`] the region of the triangle each point
    /// lies on ([`face_labels`]), otherwise that of the labelled point nearest to it.
    pub fn labels_of(&self, points: &[Point3<f64>]) -> Vec<u32> {
        match &self.faces {
            Some(f) => f.regions_at(points),
            None => points.iter().map(|p| self.region_near(p)).collect(),
        }
    }

    /// [`Self::labels_of`] the `points`, with normals: with [`MeshOptions::face_labels`] those
    /// of their own region alone, from the faces of that region around the triangle each point
    /// lies on ([`face_labels`]); otherwise `normals` as they are (see `reconstruct`).
    pub fn labels_and_normals<'a>(
        &self,
        points: &[Point3<f64>],
        normals: &'a [Vector3<f64>],
    ) -> (Vec<u32>, std::borrow::Cow<'a, [Vector3<f64>]>) {
        match &self.faces {
            Some(f) => {
                let (l, mut n) = f.regions_and_normals_at(points);
                // A degenerate triangle gives no normal: the point keeps its own.
                for (m, given) in n.iter_mut().zip(normals) {
                    if m.norm_squared() == 0.0 {
                        *m = *given;
                    }
                }
                (l, n.into())
            }
            None => (self.labels_of(points), normals.into()),
        }
    }

    /// [`Self::labels_and_normals`] with a third normal per point, of its own region alone, for
    /// judging a crease cell's fit ([`crate::implicit::PouImplicit::fit_with_sides`]). For a
    /// cloud, the one-sided normal of the labelled point nearest to it, the one its region
    /// comes from (one query for both), or the point's own normal in `normals` where that has
    /// none: an estimated normal beside a crease mixes both faces, and can be either face's or
    /// neither's; the one-sided one is its own face's (segmentation step 5,
    /// [`segment_cloud`]). A mesh's points have none (`None`: judged by the normals of
    /// [`Self::labels_and_normals`]): a vertex normal averages the faces around the vertex, so it is never along a crease nor
    /// the other face's alone, and the nearest labelled point (a vertex of either region, or a
    /// triangle's centre) can be the wrong region's (make_parts-style slot plate from its
    /// mesh: a slot's rim 1.2e-3 of the diagonal off with them, 3.8e-4 without).
    #[allow(clippy::type_complexity)]
    pub fn labels_normals_and_sides<'a>(
        &self,
        points: &[Point3<f64>],
        normals: &'a [Vector3<f64>],
    ) -> (
        Vec<u32>,
        std::borrow::Cow<'a, [Vector3<f64>]>,
        Option<Vec<Vector3<f64>>>,
    ) {
        let Some(label_normals) = &self.label_normals else {
            let (labels, normals) = self.labels_and_normals(points, normals);
            return (labels, normals, None);
        };
        let (labels, sides) = points
            .iter()
            .zip(normals)
            .map(|(p, n)| {
                let j = self.label_kd.nearest(p).0;
                let m = label_normals[j];
                (
                    self.label_of[j],
                    if m.norm_squared() > 0.0 { m } else { *n },
                )
            })
            .unzip();
        (labels, normals.into(), Some(sides))
    }

    /// True when there is more than one region (something for the feature-aware stages to do).
    pub fn has_features(&self) -> bool {
        self.regions.len() > 1
    }

    /// Merges every region holding less than `min_fraction` of all region points into the
    /// neighbour it shares the longest boundary with (smallest first; a region with no
    /// neighbour stays): a face smaller than a few patches cannot be given patches of its own,
    /// and its crease would only crowd the net (the ears of an organic model, a small facet
    /// of a coarse mesh). Returns how many regions were merged.
    pub fn absorb_small(&mut self, min_fraction: f64) -> usize {
        let mut merged = 0;
        loop {
            let total: usize = self.regions.iter().map(|r| r.points.len()).sum();
            let small = (0..self.regions.len())
                .filter(|&r| (self.regions[r].points.len() as f64) < min_fraction * total as f64)
                .filter(|&r| {
                    self.stats
                        .pairs
                        .iter()
                        .any(|p| p.a == r as u32 || p.b == r as u32)
                })
                .min_by_key(|&r| (self.regions[r].points.len(), r));
            let Some(r) = small else { break };
            let r = r as u32;
            let into = self
                .stats
                .pairs
                .iter()
                .filter(|p| p.a == r || p.b == r)
                .max_by(|x, y| {
                    x.boundary_samples
                        .cmp(&y.boundary_samples)
                        .then(y.a.cmp(&x.a))
                        .then(y.b.cmp(&x.b))
                })
                .map(|p| if p.a == r { p.b } else { p.a });
            let Some(into) = into else { break };
            let mut sets = union_find::DisjointSets::new(self.regions.len());
            sets.union(r, into);
            self.remap(&sets.labels().0);
            merged += 1;
        }
        merged
    }

    /// Relabels regions by `map` (old region -> new, numbered 0.. in order), merging those that
    /// map to one.
    fn remap(&mut self, map: &[u32]) {
        let count = map.iter().map(|&m| m as usize + 1).max().unwrap_or(0);
        let mut regions = vec![Region::default(); count];
        for (old, reg) in std::mem::take(&mut self.regions).into_iter().enumerate() {
            let dst = &mut regions[map[old] as usize];
            dst.points.extend(reg.points);
            dst.normals.extend(reg.normals);
        }
        self.regions = regions;
        for l in self.label_of.iter_mut() {
            *l = map[*l as usize];
        }
        if let Some(f) = self.faces.as_mut() {
            f.remap(map);
        }
        let pairs = details::remap_pairs(&self.stats.pairs, map);
        self.stats.pairs = pairs;
        self.stats.regions = self.regions.len();
        self.stats.region_points = self.regions.iter().map(|r| r.points.len()).collect();
    }
}

/// Segments `input` (a mesh by its faces, a cloud by `op`, its oriented points) into smooth
/// regions.
pub fn segment(input: &Mesh, op: &OrientedPoints, opts: &FeatureOptions) -> Result<Segmentation> {
    let t = std::time::Instant::now();
    let seg = if input.faces.is_empty() {
        segment_points(op, &opts.cloud)?
    } else {
        segment_faces(input, op, &opts.mesh)?
    };
    Ok(Segmentation {
        stats: SegmentStats {
            seconds: t.elapsed().as_secs_f64(),
            ..seg.stats
        },
        ..seg
    })
}

fn segment_points(op: &OrientedPoints, opts: &CloudOptions) -> Result<Segmentation> {
    let kd = KdTree::build(&op.points)?;
    let creases = crease_cloud::CreaseOptions::default();
    let (l, _, _) = detect::cloud_regions(&op.points, &op.normals, &kd, opts, &creases);
    let mut regions = vec![Region::default(); l.regions];
    let mut label_points = Vec::with_capacity(op.points.len());
    let mut label_of = Vec::with_capacity(op.points.len());
    let mut label_normals = Vec::with_capacity(op.points.len());
    for (i, &r) in l.label.iter().enumerate() {
        if r == segment_cloud::NONE {
            continue;
        }
        regions[r as usize].points.push(op.points[i]);
        regions[r as usize].normals.push(l.normals[i]);
        label_points.push(op.points[i]);
        label_of.push(r);
        label_normals.push(l.normals[i]);
    }
    if label_points.is_empty() {
        return Err(crate::Error::Degenerate(
            "the segmentation left no point in any region".into(),
        ));
    }
    let label_kd = KdTree::build(&label_points)?;
    Ok(Segmentation {
        stats: SegmentStats {
            method: "cloud",
            regions: l.regions,
            pairs: l.pairs,
            region_points: regions.iter().map(|r| r.points.len()).collect(),
            sigma: l.sigma,
            seconds: 0.0,
        },
        regions,
        label_points,
        label_of,
        label_normals: Some(label_normals),
        label_kd,
        faces: None,
    })
}

/// +1 when the mesh's faces wind outward (their vertex normals agree with the oriented points'
/// normals, which the normal stage made to point out), -1 when they wind inward.
fn winding(mesh: &Mesh, op: &OrientedPoints) -> Result<f64> {
    let vn = vertex_normals(mesh);
    let kd = KdTree::build(&op.points)?;
    let used = mesh.referenced();
    let step = (mesh.positions.len() / 2000).max(1);
    let mut vote = 0.0;
    for v in (0..mesh.positions.len()).step_by(step) {
        if used[v] && vn[v].norm_squared() > 0.0 {
            let (j, _) = kd.nearest(&mesh.positions[v]);
            vote += vn[v].dot(&op.normals[j]).signum();
        }
    }
    Ok(if vote < 0.0 { -1.0 } else { 1.0 })
}

fn segment_faces(mesh: &Mesh, op: &OrientedPoints, opts: &MeshOptions) -> Result<Segmentation> {
    // Small regions behind mild creases are surface detail, as `features` reports them:
    // spot's horns are no faces of their own.
    let l = detect::mesh_regions(mesh, opts, &DetectOptions::default())?;
    // Region normals from the faces, turned outward like the whole input's.
    let sign = winding(mesh, op)?;
    let mut regions = Vec::with_capacity(l.regions);
    let mut label_points = Vec::new();
    let mut label_of = Vec::new();
    // Vertices on a crease (used by faces of two regions) are left out of the regions'
    // points, with the samples of the triangles touching them: a remesher or a scanner moves
    // them along and across the feature line (0.037 mm off the fillet of make_parts' block,
    // twice the crease bar), and each region's surface, fitted from its interior and
    // extrapolated half a triangle, puts the crease where the two meet.
    let mut owner = vec![u32::MAX; mesh.positions.len()];
    let mut on_crease = vec![false; mesh.positions.len()];
    for (f, &fl) in mesh.faces.iter().zip(&l.face_label) {
        for &v in f {
            let o = &mut owner[v as usize];
            if *o == u32::MAX {
                *o = fl;
            } else if *o != fl {
                on_crease[v as usize] = true;
            }
        }
    }
    for r in 0..l.regions as u32 {
        let sub = Mesh {
            positions: mesh.positions.clone(),
            normals: None,
            faces: mesh
                .faces
                .iter()
                .zip(&l.face_label)
                .filter(|(_, &fl)| fl == r)
                .map(|(f, _)| *f)
                .collect(),
        };
        let vn: Vec<Vector3<f64>> = vertex_normals(&sub).into_iter().map(|n| n * sign).collect();
        let used = sub.referenced();
        let mut region = Region::default();
        for (i, p) in sub.positions.iter().enumerate() {
            if used[i] && vn[i].norm_squared() > 0.0 && !on_crease[i] {
                region.points.push(*p);
                region.normals.push(vn[i]);
            }
        }
        for f in 0..sub.faces.len() {
            label_points.push(sub.face_centroid(f));
            label_of.push(r);
        }
        for (i, p) in sub.positions.iter().enumerate() {
            if used[i] {
                label_points.push(*p);
                label_of.push(r);
            }
        }
        regions.push(region);
    }
    let label_kd = KdTree::build(&label_points)?;
    let faces = if opts.face_labels {
        Some(face_labels::FaceLabels::new(mesh, l.face_label, sign)?)
    } else {
        None
    };
    Ok(Segmentation {
        stats: SegmentStats {
            method: "mesh",
            regions: l.regions,
            pairs: l.pairs,
            region_points: regions.iter().map(|r| r.points.len()).collect(),
            sigma: 0.0,
            seconds: 0.0,
        },
        regions,
        label_points,
        label_of,
        label_normals: None,
        label_kd,
        faces,
    })
}
