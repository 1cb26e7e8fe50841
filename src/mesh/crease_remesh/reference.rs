//! What the remeshed vertices are projected back onto: the input triangles of each region, and
//! the input crease segments between each pair of regions (or along an open boundary).

use crate::metrics::deviation::closest_point_on_triangle;
use crate::spatial::KdTree;
use nalgebra::Point3;
use std::collections::HashMap;

/// Nearest reference elements examined per query (by their centres): the input mesh is taken
/// to be much finer than the target length, so the nearest triangle is among them.
const CANDIDATES: usize = 16;

/// A boundary edge's missing second region.
pub const OPEN: u32 = u32::MAX;

/// Triangles or segments with a tree over their centres.
struct Elements<const N: usize> {
    corners: Vec<[Point3<f64>; N]>,
    tree: Option<KdTree>,
}

impl<const N: usize> Elements<N> {
    fn new(corners: Vec<[Point3<f64>; N]>) -> Self {
        let centres: Vec<Point3<f64>> = corners
            .iter()
            .map(|c| {
                Point3::from(c.iter().map(|p| p.coords).sum::<nalgebra::Vector3<f64>>() / N as f64)
            })
            .collect();
        let tree = KdTree::build(&centres).ok();
        Elements { corners, tree }
    }

    fn closest(
        &self,
        p: &Point3<f64>,
        on: impl Fn(&[Point3<f64>; N]) -> Point3<f64>,
    ) -> Option<Point3<f64>> {
        let tree = self.tree.as_ref()?;
        tree.knn(p, CANDIDATES)
            .into_iter()
            .map(|(i, _)| on(&self.corners[i]))
            .min_by(|a, b| (a - p).norm_squared().total_cmp(&(b - p).norm_squared()))
    }
}

/// The input surface, by region and by crease.
pub struct Reference {
    regions: HashMap<u32, Elements<3>>,
    creases: HashMap<(u32, u32), Elements<2>>,
}

/// The key of the crease between regions `a` and `b` (`b` = [`OPEN`] on a boundary).
pub fn crease_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Reference {
    /// `creases`: the input's crease edges with the two regions they separate.
    pub fn new(
        positions: &[Point3<f64>],
        triangles: &[[u32; 3]],
        labels: &[u32],
        creases: &[([u32; 2], (u32, u32))],
    ) -> Reference {
        let mut by_region: HashMap<u32, Vec<[Point3<f64>; 3]>> = HashMap::new();
        for (t, &l) in triangles.iter().zip(labels) {
            by_region
                .entry(l)
                .or_default()
                .push(t.map(|v| positions[v as usize]));
        }
        let mut by_crease: HashMap<(u32, u32), Vec<[Point3<f64>; 2]>> = HashMap::new();
        for &(e, key) in creases {
            by_crease
                .entry(key)
                .or_default()
                .push(e.map(|v| positions[v as usize]));
        }
        Reference {
            regions: by_region
                .into_iter()
                .map(|(k, v)| (k, Elements::new(v)))
                .collect(),
            creases: by_crease
                .into_iter()
                .map(|(k, v)| (k, Elements::new(v)))
                .collect(),
        }
    }

    /// The nearest point of region `label`'s input triangles.
    pub fn on_region(&self, label: u32, p: &Point3<f64>) -> Option<Point3<f64>> {
        self.regions
            .get(&label)?
            .closest(p, |[a, b, c]| closest_point_on_triangle(p, a, b, c))
    }

    /// The nearest point of the input crease `key` ([`crease_key`]).
    pub fn on_crease(&self, key: (u32, u32), p: &Point3<f64>) -> Option<Point3<f64>> {
        self.creases.get(&key)?.closest(p, |[a, b]| {
            let d = b - a;
            let t = ((p - a).dot(&d) / d.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            a + d * t
        })
    }
}
