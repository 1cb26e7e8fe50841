//! Indexed triangle meshes and point clouds.
//!
//! One type serves both: a [`Mesh`] whose `faces` are empty is a point cloud. Positions are
//! `f64`; faces index into `positions` with `u32` (4 billion vertices is far past what fits in
//! memory for this tool's inputs).

pub mod adjacency;
pub mod crease_remesh;
pub mod normals;
pub mod retain;
pub mod sample;
pub mod shape;
pub mod subdivide;
pub mod subsample;
pub mod topology;
pub mod unfold;

pub use topology::{BoundaryLoop, Topology};

use nalgebra::{Point3, Vector3};

/// A triangle mesh, or a point cloud when `faces` is empty.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Point3<f64>>,
    /// Per-vertex unit normals, when the input had them or they were estimated.
    pub normals: Option<Vec<Vector3<f64>>>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub faces: Vec<[u32; 3]>,
}

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Aabb {
    pub min: Point3<f64>,
    pub max: Point3<f64>,
}

impl Aabb {
    /// The box of a set of points; `None` when there are none.
    pub fn of(points: &[Point3<f64>]) -> Option<Aabb> {
        let first = points.first()?;
        let mut b = Aabb {
            min: *first,
            max: *first,
        };
        for p in points {
            b.min = b.min.inf(p);
            b.max = b.max.sup(p);
        }
        Some(b)
    }
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).norm()
    }
    /// Centre of the box.
    pub fn center(&self) -> Point3<f64> {
        nalgebra::center(&self.min, &self.max)
    }
}

impl Mesh {
    /// A point cloud (no faces).
    pub fn from_points(positions: Vec<Point3<f64>>, normals: Option<Vec<Vector3<f64>>>) -> Self {
        Mesh {
            positions,
            normals,
            faces: Vec::new(),
        }
    }
    /// True when the mesh has no faces.
    pub fn is_point_cloud(&self) -> bool {
        self.faces.is_empty()
    }
    /// Bounding box of all positions.
    pub fn aabb(&self) -> Option<Aabb> {
        Aabb::of(&self.positions)
    }
    /// Builds the adjacency structure (edges, boundary loops, manifoldness).
    pub fn topology(&self) -> Topology {
        Topology::build(self)
    }
    /// Which vertices some face uses.
    pub fn referenced(&self) -> Vec<bool> {
        let mut used = vec![false; self.positions.len()];
        for f in &self.faces {
            for &v in f {
                used[v as usize] = true;
            }
        }
        used
    }
    /// The positions of the vertices used by faces (all of them for a point cloud), with their
    /// normals. This is "the input points" of a mesh whose unreferenced vertices are debris.
    pub fn referenced_points(&self) -> (Vec<Point3<f64>>, Option<Vec<Vector3<f64>>>) {
        if self.faces.is_empty() {
            return (self.positions.clone(), self.normals.clone());
        }
        let used = self.referenced();
        let pts = self
            .positions
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .map(|(p, _)| *p)
            .collect();
        let nrm = self.normals.as_ref().map(|n| {
            n.iter()
                .zip(&used)
                .filter(|(_, &u)| u)
                .map(|(n, _)| *n)
                .collect()
        });
        (pts, nrm)
    }
    /// Area of triangle `f`.
    pub fn face_area(&self, f: usize) -> f64 {
        0.5 * self.face_cross(f).norm()
    }
    /// Centroid of triangle `f`.
    pub fn face_centroid(&self, f: usize) -> Point3<f64> {
        let [a, b, c] = self.faces[f].map(|v| self.positions[v as usize]);
        Point3::from((a.coords + b.coords + c.coords) / 3.0)
    }
    /// (b - a) x (c - a) of face `f`: twice its area times its unit normal.
    pub fn face_cross(&self, f: usize) -> Vector3<f64> {
        let [a, b, c] = self.faces[f];
        let (a, b, c) = (
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        );
        (b - a).cross(&(c - a))
    }
    /// Mean length of the faces' edges (each edge counted once per face side); 0 without faces.
    pub fn mean_edge_length(&self) -> f64 {
        if self.faces.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0;
        for f in &self.faces {
            for k in 0..3 {
                sum += (self.positions[f[k] as usize] - self.positions[f[(k + 1) % 3] as usize])
                    .norm();
            }
        }
        sum / (3 * self.faces.len()) as f64
    }
    /// Signed volume enclosed (positive for a closed, outward-oriented mesh).
    pub fn signed_volume(&self) -> f64 {
        self.faces
            .iter()
            .map(|f| {
                let a = self.positions[f[0] as usize].coords;
                let b = self.positions[f[1] as usize].coords;
                let c = self.positions[f[2] as usize].coords;
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum()
    }
}
