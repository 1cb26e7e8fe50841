//! The sharp implicit as the crease-aware stages see it ([`SideField`]): which smooth region a
//! point lies on, and the implicit on that region's side of every crease. Shared by
//! `reconstruct` (the mesh split at the creases, [`crate::polygonize::crease_split`]) and
//! `fit --sharp` (the net's nodes put on the creases, [`crate::polygonize::crease_nodes`]).

use super::Segmentation;
use crate::implicit::PouImplicit;
use crate::polygonize::crease_split::SideField;
use nalgebra::{Point3, Vector3};

/// Labelled input points looked at by [`SharpField::region`].
pub const REGION_VOTERS: usize = 16;

/// Of the regions among the input points nearest to x, the one whose surface passes nearest
/// to x (the labels of the input points beside a crease are a point spacing uncertain, the
/// sides' surfaces are not); the implicit on that region's side of every crease.
pub struct SharpField<'a> {
    pub seg: &'a Segmentation,
    pub f: &'a PouImplicit,
}

impl SideField for SharpField<'_> {
    fn region(&self, x: &Point3<f64>) -> u32 {
        let near = self.seg.regions_near(x, REGION_VOTERS);
        if near.len() == 1 {
            return near[0].0;
        }
        near.iter()
            .map(|&(r, _)| (r, self.f.side_value_and_gradient(r, x).0.abs()))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            .map_or_else(|| self.seg.region_near(x), |(r, _)| r)
    }
    fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        self.f.side_value_and_gradient(region, x)
    }
}
