//! The smooth regions' surfaces fitted to the data around a point: the sides a crease node of
//! the quad net is put between (`fit --sharp`: the voxel route's
//! [`crate::polygonize::crease_nodes`], and the remesh route's
//! [`crate::polygonize::side_projection`] where they follow their points about as well as the
//! sharp implicit's sides, [`LocalSides::near_checked`]).
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

/// A region's surface fitted to the data is used instead of a reference side
/// ([`LocalSides::near_checked`]) only when its RMS distance from the region's points is at
/// most this many times the reference's plus [`MISFIT_FLOOR`] times the scale. Not below 1:
/// beside a crease the sharp implicit's rounding is confined to the last few tenths of a
/// millimetre, where few points are, so it follows the points as well as the fit to them does
/// (make_parts-style hexnut cloud: 0.0108 against 0.0136 mm on a top face whose implicit side
/// runs 0.035 mm under the true edge there, the fit 0.004); a quadratic over a fillet's strip
/// or round a thin wall misses its points tens of times more (block.stl's fillets: 0.35
/// against 0.008 mm).
pub const MISFIT_RATIO: f64 = 1.5;
/// The floor of that comparison, relative to the scale (a mesh's vertices lie on both).
pub const MISFIT_FLOOR: f64 = 0.001;

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

    /// The points of region `r` among `near` that its surface is fitted to.
    fn region_points(&self, near: &[usize], r: u32) -> Vec<Point3<f64>> {
        let (points, labels) = self.seg.labelled();
        near.iter()
            .filter(|&&i| labels[i] == r)
            .take(MAX_POINTS)
            .map(|&i| points[i])
            .collect()
    }

    /// The surface of region `r` fitted to its points among `near`.
    fn fit(&self, x: &Point3<f64>, near: &[usize], r: u32) -> Option<LocalQuadric> {
        fit_region(*x, &self.region_points(near, r))
    }

    /// The surfaces of `regions` fitted around `x`, or `None` when one cannot be fitted or
    /// `accept` (region, its points, its surface) refuses one.
    fn fitted(
        &self,
        x: &Point3<f64>,
        regions: &[u32],
        accept: impl Fn(u32, &[Point3<f64>], &LocalQuadric) -> bool,
    ) -> Option<Box<dyn SideField + Send + Sync>> {
        let near = self.near_points(x);
        let mut fits = Vec::with_capacity(regions.len());
        for &r in regions {
            let pts = self.region_points(&near, r);
            let q = fit_region(*x, &pts)?;
            if !accept(r, &pts, &q) {
                return None;
            }
            fits.push((r, q));
        }
        Some(Box::new(FittedSides { fits }))
    }
}

impl LocalSides for DataSides<'_> {
    fn near(&self, x: &Point3<f64>, regions: &[u32]) -> Option<Box<dyn SideField + Send + Sync>> {
        self.fitted(x, regions, |_, _, _| true)
    }

    fn near_checked(
        &self,
        x: &Point3<f64>,
        regions: &[u32],
        reference: &dyn SideField,
        scale: f64,
    ) -> Option<Box<dyn SideField + Send + Sync>> {
        self.fitted(x, regions, |r, pts, q| {
            let rms = |d: &dyn Fn(&Point3<f64>) -> f64| {
                (pts.iter().map(|p| d(p).powi(2)).sum::<f64>() / pts.len() as f64).sqrt()
            };
            let own = rms(&|p| q.distance(p));
            let theirs = rms(&|p| {
                let (f, g) = reference.side(r, p);
                f / g.norm().max(1e-300)
            });
            // (NaN, from a side without a gradient, refuses too.)
            own <= MISFIT_RATIO * theirs + MISFIT_FLOOR * scale
        })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{segment, FeatureOptions};
    use crate::mesh::Mesh;
    use crate::normals::oriented_points;

    /// Axis-aligned planes, one per region: (region, axis k, offset a, sign s) is the side
    /// s (x_k - a) (a box's faces, shifted at will).
    struct Planes(Vec<(u32, usize, f64, f64)>);
    impl SideField for Planes {
        fn region(&self, _: &Point3<f64>) -> u32 {
            u32::MAX
        }
        fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
            let (_, k, at, sign) = *self.0.iter().find(|s| s.0 == region).unwrap();
            (sign * (x[k] - at), Vector3::ith(k, sign))
        }
    }

    /// A closed cylinder of radius `r` on z in [0, 1]: `n` facets round, `rows` rows high.
    fn cylinder(r: f64, n: usize, rows: usize) -> Mesh {
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for j in 0..=rows {
            for i in 0..n {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                positions.push(Point3::new(
                    r * t.cos(),
                    r * t.sin(),
                    j as f64 / rows as f64,
                ));
            }
        }
        let id = |i: usize, j: usize| (j * n + i % n) as u32;
        for j in 0..rows {
            for i in 0..n {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        for (z, j) in [(0.0, 0), (1.0, rows)] {
            positions.push(Point3::new(0.0, 0.0, z));
            let c = positions.len() as u32 - 1;
            for i in 0..n {
                let (a, b) = (id(i, j), id(i + 1, j));
                faces.push(if j == 0 { [c, b, a] } else { [c, a, b] });
            }
        }
        Mesh {
            positions,
            normals: None,
            faces,
        }
    }

    #[test]
    fn a_box_s_faces_fitted_to_the_data_replace_sides_that_miss_them() {
        let mesh = crate::features::crease_mesh::tests::box_mesh(8);
        let op = oriented_points(&mesh, 12).unwrap();
        let seg = segment(&mesh, &op, &FeatureOptions::default()).unwrap();
        let l = seg.labels_of(&[Point3::new(1.0, 0.5, 1.0), Point3::new(1.0, 1.0, 0.5)]);
        let (top, side) = (l[0], l[1]);
        assert_ne!(top, side);
        let data = DataSides {
            seg: &seg,
            radius: 0.4,
        };
        // The implicit's sides 0.05 inside the faces (a rounded crease): the data's planes
        // are taken, and meet on the true edge.
        let inside = Planes(vec![(top, 2, 0.95, 1.0), (side, 1, 0.95, 1.0)]);
        let x = Point3::new(1.0, 0.97, 0.97);
        let local = data.near_checked(&x, &[top, side], &inside, 0.1).unwrap();
        let opts = crate::polygonize::crease_split::CreaseSplitOptions::default();
        let y = crate::polygonize::crease_split::meet_point(
            local.as_ref(),
            &[top, side],
            x,
            0.1,
            &opts,
        )
        .unwrap();
        assert!((y - Point3::new(1.0, 1.0, 1.0)).norm() < 1e-6, "{y}");
        // Sides on the faces: the data's fit is as good, and taken too (the same planes).
        let exact = Planes(vec![(top, 2, 1.0, 1.0), (side, 1, 1.0, 1.0)]);
        assert!(data.near_checked(&x, &[top, side], &exact, 0.1).is_some());
    }

    #[test]
    fn a_fit_that_misses_its_points_is_not_taken_over_a_side_that_follows_them() {
        // A thin cylinder fitted within a radius wider than it: its wall's points go all round,
        // and no height function over one plane follows them.
        let mesh = cylinder(0.25, 48, 8);
        let op = oriented_points(&mesh, 12).unwrap();
        let seg = segment(&mesh, &op, &FeatureOptions::default()).unwrap();
        let l = seg.labels_of(&[Point3::new(0.25, 0.0, 0.5), Point3::new(0.0, 0.0, 1.0)]);
        let (wall, top) = (l[0], l[1]);
        assert_ne!(wall, top);
        struct Exact(u32);
        impl SideField for Exact {
            fn region(&self, _: &Point3<f64>) -> u32 {
                u32::MAX
            }
            fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
                if region == self.0 {
                    let r = x.x.hypot(x.y);
                    (r - 0.25, Vector3::new(x.x / r, x.y / r, 0.0))
                } else {
                    (x.z - 1.0, Vector3::z())
                }
            }
        }
        let data = DataSides {
            seg: &seg,
            radius: 1.0,
        };
        let x = Point3::new(0.25, 0.0, 1.0);
        assert!(data.near(&x, &[wall, top]).is_some());
        assert!(data
            .near_checked(&x, &[wall, top], &Exact(wall), 0.1)
            .is_none());
    }
}
