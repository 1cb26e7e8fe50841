//! The smooth regions' surfaces fitted to the data around a point: the sides a crease node of
//! the quad net is put between (`fit --sharp`, [`crate::polygonize::crease_nodes`]).
//!
//! For each region asked for, the labelled points of that region within `radius` of the point
//! (at most [`MAX_POINTS`], nearest first) are fitted by a local quadratic height function
//! ([`LocalQuadric`], seed 004 eq. 1) in the frame of their own best plane (the principal axis
//! of least spread, so no normals are needed; a plane when they form a strip narrower than
//! [`QUADRATIC_SPREAD`] of its length, whose curvature across they do not fix), then fitted again without the points farther
//! than three times the median distance from the first fit (points carried past the crease
//! into the region). A region with fewer than [`MIN_POINTS`] points there, or with points
//! strung along a line (narrower than [`MIN_SPREAD`] of their length across it: a plane would
//! be free to turn about the line), gives no surface, and the point none.
//!
//! The region of a point (the labels of the net's quads) is, of the regions with at least
//! [`MIN_POINTS`] points within the radius, the one whose fitted surface passes nearest.
//!
//! The sharp implicit's own sides ([`super::sharp_field`]) exist only in its sharp cells, where
//! the one function per side passed its checks; elsewhere the implicit rounds the crease and
//! both sides are the same function. The data do not depend on that, and on a mesh of flat
//! facets they give the planes exactly.

use super::local_fit::{principal_axes, spread, LocalQuadric};
use super::Segmentation;
use crate::polygonize::crease_nodes::LocalSides;
use crate::polygonize::crease_split::SideField;
use nalgebra::{Point3, Vector3};

/// Fewest points of a region for its surface.
pub const MIN_POINTS: usize = 8;
/// Most points of a region fitted.
pub const MAX_POINTS: usize = 120;
/// Points at least this many for a quadratic (a plane below).
pub const QUADRATIC_FROM: usize = 20;
/// Smallest ratio of the points' narrower to wider extent in their plane.
pub const MIN_SPREAD: f64 = 0.15;
/// The same for a quadratic (a plane below).
pub const QUADRATIC_SPREAD: f64 = 0.5;

/// The labelled points of a segmentation, fitted around a point within `radius`.
pub struct DataSides<'a> {
    pub seg: &'a Segmentation,
    pub radius: f64,
}

/// The surfaces of some regions fitted around one point.
pub struct FittedSides {
    fits: Vec<(u32, LocalQuadric)>,
}

impl SideField for FittedSides {
    fn region(&self, x: &Point3<f64>) -> u32 {
        self.fits
            .iter()
            .map(|(r, q)| (*r, q.distance(x).abs()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(u32::MAX, |(r, _)| r)
    }
    fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        match self.fits.iter().find(|(r, _)| *r == region) {
            Some((_, q)) => q.value_and_gradient(x),
            None => (f64::NAN, Vector3::zeros()),
        }
    }
}

impl DataSides<'_> {
    /// Indices of the labelled points within the radius of `x`, nearest first.
    fn near_points(&self, x: &Point3<f64>) -> Vec<usize> {
        let (points, _) = self.seg.labelled();
        let mut near: Vec<(usize, f64)> = self
            .seg
            .label_tree()
            .within(x, self.radius)
            .into_iter()
            .map(|i| (i, (points[i] - x).norm_squared()))
            .collect();
        near.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        near.into_iter().map(|(i, _)| i).collect()
    }

    /// The surface of region `r` fitted to its points among `near`.
    fn fit(&self, x: &Point3<f64>, near: &[usize], r: u32) -> Option<LocalQuadric> {
        let (points, labels) = self.seg.labelled();
        let pts: Vec<Point3<f64>> = near
            .iter()
            .filter(|&&i| labels[i] == r)
            .take(MAX_POINTS)
            .map(|&i| points[i])
            .collect();
        fit_region(*x, &pts)
    }
}

impl LocalSides for DataSides<'_> {
    fn near(&self, x: &Point3<f64>, regions: &[u32]) -> Option<Box<dyn SideField + Send + Sync>> {
        let near = self.near_points(x);
        let mut fits = Vec::with_capacity(regions.len());
        for &r in regions {
            fits.push((r, self.fit(x, &near, r)?));
        }
        Some(Box::new(FittedSides { fits }))
    }

    fn region(&self, x: &Point3<f64>) -> Option<u32> {
        let near = self.near_points(x);
        let labels = self.seg.labelled().1;
        let mut count: std::collections::BTreeMap<u32, usize> = Default::default();
        for &i in &near {
            *count.entry(labels[i]).or_default() += 1;
        }
        let candidates: Vec<u32> = count
            .into_iter()
            .filter(|&(_, n)| n >= MIN_POINTS)
            .map(|(r, _)| r)
            .collect();
        if candidates.len() == 1 {
            return Some(candidates[0]);
        }
        candidates
            .into_iter()
            .filter_map(|r| self.fit(x, &near, r).map(|q| (r, q.distance(x).abs())))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            .map(|(r, _)| r)
    }
}

/// A quadric through `pts` around `centre`, in the frame of their best plane, trimmed once
/// (module doc).
fn fit_region(centre: Point3<f64>, pts: &[Point3<f64>]) -> Option<LocalQuadric> {
    if pts.len() < MIN_POINTS {
        return None;
    }
    let axis = least_spread_axis(pts)?;
    let spread = spread(pts, &axis);
    if spread < MIN_SPREAD {
        return None;
    }
    // A narrow strip of points (a chamfer a patch wide) leaves the curvature across it
    // unfixed: a plane there.
    let quadratic_from = if spread >= QUADRATIC_SPREAD {
        QUADRATIC_FROM
    } else {
        usize::MAX
    };
    let first = LocalQuadric::fit_with(centre, axis, pts, quadratic_from)?;
    let d: Vec<f64> = pts.iter().map(|p| first.distance(p).abs()).collect();
    let mut sorted = d.clone();
    sorted.sort_by(f64::total_cmp);
    let trim = 3.0 * sorted[sorted.len() / 2];
    let kept: Vec<Point3<f64>> = pts
        .iter()
        .zip(&d)
        .filter(|(_, d)| **d <= trim)
        .map(|(p, _)| *p)
        .collect();
    if kept.len() < MIN_POINTS || kept.len() == pts.len() {
        return Some(first);
    }
    LocalQuadric::fit_with(centre, axis, &kept, quadratic_from).or(Some(first))
}

/// The unit direction of least spread of `pts` (the normal of their best plane).
fn least_spread_axis(pts: &[Point3<f64>]) -> Option<Vector3<f64>> {
    principal_axes(pts)?.1[0].try_normalize(1e-12)
}
