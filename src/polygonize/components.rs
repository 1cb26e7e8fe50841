//! Removal of surface components that the data does not support.
//!
//! A blended implicit can have small closed sheets of its zero set near the data where a single
//! local function extrapolates (a cubic bending back near a corner of its support). Every real
//! part of the surface is the nearest surface for many input points; a spurious sheet lies
//! beside the real surface and is the nearest surface for (almost) none. So each input point
//! votes for the component of its nearest triangle, and components with fewer than
//! `min_points` votes are removed.

use crate::mesh::retain::retain_faces;
use crate::mesh::{Mesh, Topology};
use crate::spatial::TriangleBvh;
use crate::Result;
use nalgebra::Point3;
use rayon::prelude::*;

/// The mesh without the components that are the nearest surface for fewer than `min_points` of
/// `points`, and the number of components removed. A mesh with a single component is returned
/// unchanged.
pub fn keep_supported_components(
    mesh: Mesh,
    points: &[Point3<f64>],
    min_points: usize,
) -> Result<(Mesh, usize)> {
    if mesh.faces.is_empty() {
        return Ok((mesh, 0));
    }
    let topo = Topology::build(&mesh);
    if topo.components.len() <= 1 {
        return Ok((mesh, 0));
    }
    let bvh = TriangleBvh::build(&mesh)?;
    let nearest: Vec<u32> = points
        .par_iter()
        .map(|p| topo.face_component[bvh.closest(&mesh, p).1])
        .collect();
    let mut votes = vec![0usize; topo.components.len()];
    for c in nearest {
        votes[c as usize] += 1;
    }
    let keep_comp: Vec<bool> = votes.iter().map(|&v| v >= min_points).collect();
    let removed = keep_comp.iter().filter(|k| !**k).count();
    if removed == 0 {
        return Ok((mesh, 0));
    }
    let keep: Vec<bool> = topo
        .face_component
        .iter()
        .map(|&c| keep_comp[c as usize])
        .collect();
    Ok((retain_faces(&mesh, &keep), removed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::Implicit;
    use crate::mesh::Aabb;
    use crate::polygonize::marching_cubes;

    /// A big sphere and a tiny one beside it.
    struct Two;
    impl Implicit for Two {
        fn value(&self, x: &Point3<f64>) -> f64 {
            let a = x.coords.norm() - 0.6;
            let b = (x - Point3::new(0.85, 0.0, 0.0)).norm() - 0.1;
            a.min(b)
        }
    }

    #[test]
    fn drops_the_unsupported_bubble() {
        let dom = Aabb {
            min: Point3::new(-1.0, -1.0, -1.0),
            max: Point3::new(1.0, 1.0, 1.0),
        };
        let seeds = vec![Point3::new(0.6, 0.0, 0.0), Point3::new(0.95, 0.0, 0.0)];
        let m = marching_cubes(&Two, &seeds, &dom, 0.05).unwrap();
        assert_eq!(Topology::build(&m).components.len(), 2);
        // Data only on the big sphere.
        let pts: Vec<_> = (0..200)
            .map(|i| {
                let t = i as f64 * 0.7;
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / 200.0;
                let r = (1.0 - z * z).sqrt();
                Point3::new(-0.6 * r * t.cos().abs(), 0.6 * r * t.sin(), 0.6 * z)
            })
            .collect();
        let (k, removed) = keep_supported_components(m, &pts, 3).unwrap();
        assert_eq!(removed, 1);
        assert_eq!(Topology::build(&k).components.len(), 1);
        assert!(Topology::build(&k).is_closed_manifold());
    }
}
