//! Sharp features of an input for the user and for the stages of `fit`: its noise, its smooth
//! regions (every point labelled), the crease polylines between them and the corners where
//! three or more meet. A mesh goes through [`super::segment_mesh`] and
//! [`super::crease_mesh`] (its creases are mesh edges), a cloud through
//! [`super::segment_cloud`], [`super::folds`] and [`super::crease_cloud`] (its creases are
//! where the two sides' planes meet).
//!
//! Thresholds come from the data: the cloud's tests are in multiples of its noise (the median
//! residual of local quadratic fits, [`crate::implicit::noise`]'s measure) and its point
//! spacing; the mesh's are its mean edge length. One angle is fixed: regions meeting at less
//! than [`DetectOptions::angle_deg`] (20 degrees) are one smooth region (`--angle` overrides).

use super::crease_cloud::{boundary_points, creases_from, BoundaryPoint, CreaseOptions};
use super::crease_mesh::mesh_creases;
use super::details::absorb_details;
use super::folds::merge_folds;
use super::lines::Crease;
use super::segment_cloud::{segment_cloud, CloudLabels, CloudOptions, NONE};
use super::segment_mesh::{segment_mesh, MeshLabels, MeshOptions};
use crate::implicit::noise::estimate_noise;
use crate::mesh::normals::vertex_normals;
use crate::mesh::{Aabb, Mesh};
use crate::normals::{oriented_points, OrientedPoints};
use crate::spatial::KdTree;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use serde::Serialize;

/// Options of [`detect`].
#[derive(Debug, Clone, Copy)]
pub struct DetectOptions {
    /// Regions meeting at a smaller angle are one smooth region, degrees (default 20).
    pub angle_deg: f64,
    /// A mesh crease turning by more than this at one vertex ends there at a corner, degrees
    /// (default 60).
    pub turn_deg: f64,
    /// Regions of a mesh under this fraction of its faces whose creases (mean dihedral of
    /// their edges) are milder than `detail_deg` are surface detail and join a neighbour
    /// ([`super::details`]; default 0.02).
    pub detail_fraction: f64,
    /// See `detail_fraction`, degrees (default 40: spot's horns meet its head at 37.6, a
    /// chamfer its faces at 45, measured 43-45 on noisy clouds).
    pub detail_deg: f64,
    /// Neighbours of the normal estimate of a cloud (default 12).
    pub normal_neighbours: usize,
    pub mesh: MeshOptions,
    pub cloud: CloudOptions,
    pub creases: CreaseOptions,
}

impl Default for DetectOptions {
    fn default() -> Self {
        DetectOptions {
            angle_deg: 20.0,
            turn_deg: 60.0,
            detail_fraction: 0.02,
            detail_deg: 40.0,
            normal_neighbours: 12,
            mesh: MeshOptions::default(),
            cloud: CloudOptions::default(),
            creases: CreaseOptions::default(),
        }
    }
}

/// What [`detect`] found; serialized as the `features` command's JSON.
#[derive(Debug, Clone, Serialize)]
pub struct Features {
    /// "mesh" (dihedral angles of its edges) or "cloud" (local fits).
    pub method: &'static str,
    /// The input's noise: median rms residual of local quadratic fits, in input units.
    pub noise: f64,
    /// Typical point spacing (cloud) or mean edge length (mesh), in input units.
    pub spacing: f64,
    /// Diagonal of the input's bounding box.
    pub diagonal: f64,
    /// The angle under which regions are one, degrees.
    pub angle_deg: f64,
    /// Number of smooth regions.
    pub regions: usize,
    /// Labelled points per region.
    pub region_points: Vec<usize>,
    pub creases: Vec<Crease>,
    pub corners: Vec<[f64; 3]>,
    /// Total length of the crease polylines.
    pub crease_length: f64,
    pub seconds: f64,
    /// The labelled points (a cloud's distinct points, a mesh's referenced vertices).
    #[serde(skip)]
    pub points: Vec<Point3<f64>>,
    /// Region of each of `points`; [`UNLABELLED`] for the few no region took.
    #[serde(skip)]
    pub label: Vec<u32>,
}

/// What `fit`'s report says of the features (`fit --features`): the counts of [`Features`].
#[derive(Debug, Clone, Serialize)]
pub struct FeatureSummary {
    pub method: &'static str,
    pub noise: f64,
    pub regions: usize,
    pub creases: usize,
    pub corners: usize,
    /// Total crease length, in input units and as a fraction of the bounding-box diagonal.
    pub crease_length: f64,
    pub crease_length_rel: f64,
    pub seconds: f64,
}

impl Features {
    /// The counts for a report.
    pub fn summary(&self) -> FeatureSummary {
        FeatureSummary {
            method: self.method,
            noise: self.noise,
            regions: self.regions,
            creases: self.creases.len(),
            corners: self.corners.len(),
            crease_length: self.crease_length,
            crease_length_rel: if self.diagonal > 0.0 {
                self.crease_length / self.diagonal
            } else {
                0.0
            },
            seconds: self.seconds,
        }
    }
}

/// Label of a point no region took.
pub const UNLABELLED: u32 = NONE;

/// Finds the noise, smooth regions, creases and corners of `input` (a mesh when it has faces,
/// else a cloud).
pub fn detect(input: &Mesh, opts: &DetectOptions) -> Result<Features> {
    let t = std::time::Instant::now();
    let op = if input.faces.is_empty() {
        Some(oriented_points(input, opts.normal_neighbours)?)
    } else {
        None
    };
    let mut f = detect_oriented(input, op.as_ref(), opts)?;
    f.seconds = t.elapsed().as_secs_f64();
    Ok(f)
}

/// [`detect`] with a cloud's oriented points already at hand (`fit` has them): `op` is used
/// when `input` has no faces and must then be given.
pub fn detect_oriented(
    input: &Mesh,
    op: Option<&OrientedPoints>,
    opts: &DetectOptions,
) -> Result<Features> {
    let t = std::time::Instant::now();
    if !(opts.angle_deg > 0.0 && opts.angle_deg < 180.0) {
        return Err(Error::InvalidOption(format!(
            "the crease angle must be between 0 and 180 degrees, not {}",
            opts.angle_deg
        )));
    }
    let found = if input.faces.is_empty() {
        let op = op.ok_or_else(|| {
            Error::InvalidOption("feature detection on a cloud needs its oriented points".into())
        })?;
        detect_cloud(op, opts)?
    } else {
        detect_mesh(input, opts)?
    };
    let mut region_points = vec![0; found.regions];
    for &l in &found.label {
        if l != UNLABELLED {
            region_points[l as usize] += 1;
        }
    }
    Ok(Features {
        method: found.method,
        noise: found.noise,
        spacing: found.spacing,
        diagonal: Aabb::of(&found.points).map_or(0.0, |b| b.diagonal()),
        angle_deg: opts.angle_deg,
        regions: found.regions,
        region_points,
        // (+ 0.0: an empty f64 sum is -0.0.)
        crease_length: found.creases.iter().map(Crease::length).sum::<f64>() + 0.0,
        creases: found.creases,
        corners: found.corners.iter().map(|c| [c.x, c.y, c.z]).collect(),
        seconds: t.elapsed().as_secs_f64(),
        points: found.points,
        label: found.label,
    })
}

fn detect_cloud(op: &OrientedPoints, opts: &DetectOptions) -> Result<Found> {
    let points = &op.points[..op.original];
    let normals = &op.normals[..op.original];
    let kd = KdTree::build(points)?;
    let cloud = CloudOptions {
        crease_deg: opts.angle_deg,
        ..opts.cloud
    };
    // No detail absorption here: a cloud's pair angles come from local fits (a chamfer's
    // 45 degrees reads 40-44), too close to an organic detail's to tell them apart.
    let (labels, spacing, found) = cloud_regions(points, normals, &kd, &cloud, &opts.creases);
    let found =
        found.unwrap_or_else(|| boundary_points(points, &labels, &kd, spacing, &opts.creases));
    let (creases, corners) = creases_from(&found, spacing, &opts.creases);
    Ok(Found {
        method: "cloud",
        noise: labels.sigma,
        spacing,
        regions: labels.regions,
        creases,
        corners,
        points: points.to_vec(),
        label: labels.label,
    })
}

/// The smooth regions of a cloud ([`segment_cloud`], then [`super::folds`]), its typical
/// spacing, and the boundary points of the regions when the folds left them as they were
/// (`None` after a merge: the caller that needs them computes them again). One pipeline for
/// [`detect`] and [`super::segment`].
pub(super) fn cloud_regions(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    kd: &KdTree,
    cloud: &CloudOptions,
    creases: &CreaseOptions,
) -> (CloudLabels, f64, Option<Vec<BoundaryPoint>>) {
    let mut labels = segment_cloud(points, normals, kd, cloud);
    let spacing = crate::reconstruct::mean_spacing(points, kd);
    let found = boundary_points(points, &labels, kd, spacing, creases);
    // Pairs that only fold in places are one surface; their samples go with them.
    let merged = merge_folds(points, &mut labels, &found, spacing, creases);
    (labels, spacing, (merged == 0).then_some(found))
}

/// The smooth regions of a mesh's faces ([`segment_mesh`]), with the small regions behind mild
/// creases absorbed as surface detail ([`absorb_details`], `opts.detail_fraction` and
/// `opts.detail_deg`). One pipeline for [`detect`] and [`super::segment`].
pub(super) fn mesh_regions(
    input: &Mesh,
    mesh_opts: &MeshOptions,
    opts: &DetectOptions,
) -> Result<MeshLabels> {
    let mut labels = segment_mesh(input, mesh_opts)?;
    (labels.regions, labels.pairs) = absorb_details(
        &mut labels.face_label,
        labels.regions,
        &labels.pairs,
        opts.detail_fraction,
        opts.detail_deg,
    );
    Ok(labels)
}

/// What each kind of input yields, before the common figures are added.
struct Found {
    method: &'static str,
    noise: f64,
    spacing: f64,
    regions: usize,
    creases: Vec<Crease>,
    corners: Vec<Point3<f64>>,
    points: Vec<Point3<f64>>,
    label: Vec<u32>,
}

fn detect_mesh(input: &Mesh, opts: &DetectOptions) -> Result<Found> {
    let mesh_opts = MeshOptions {
        crease_deg: opts.angle_deg,
        ..opts.mesh
    };
    let labels = mesh_regions(input, &mesh_opts, opts)?;
    let (creases, corners) = mesh_creases(input, &labels, opts.turn_deg)?;
    // Vertex labels: the region of a vertex's first face (a crease vertex belongs to both).
    let used = input.referenced();
    let mut vlabel = vec![UNLABELLED; input.positions.len()];
    for (face, &l) in input.faces.iter().zip(&labels.face_label) {
        for &v in face {
            let x = &mut vlabel[v as usize];
            *x = (*x).min(l);
        }
    }
    let vn = vertex_normals(input);
    let (mut points, mut normals, mut label) = (Vec::new(), Vec::new(), Vec::new());
    for v in 0..input.positions.len() {
        if used[v] {
            points.push(input.positions[v]);
            normals.push(vn[v]);
            label.push(vlabel[v]);
        }
    }
    let kd = KdTree::build(&points)?;
    let noise = estimate_noise(&points, &normals, &kd, 20, 2000);
    Ok(Found {
        method: "mesh",
        noise,
        spacing: input.mean_edge_length(),
        regions: labels.regions,
        creases,
        corners,
        points,
        label,
    })
}
