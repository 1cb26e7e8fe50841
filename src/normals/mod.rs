//! Normals for points: estimated (PCA) and oriented (minimum spanning tree) for clouds without
//! them, repaired where the input's own normals are flipped.

pub mod orient;
pub mod pca;

pub use orient::{orient_mst, repair_flips};
pub use pca::estimate_normals;

use crate::mesh::{normals::vertex_normals, Mesh, Topology};
use crate::spatial::KdTree;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// A mesh is sampled on its triangles at this fraction of the bounding-box diagonal where its
/// edges are longer (a scan like the Stanford bunny, edges about 1/170 of the diagonal, gets
/// almost nothing; a coarse model gets enough points to follow its facets).
pub const MESH_SAMPLING: f64 = 100.0;

/// Neighbours used for normal estimation and flip repair unless told otherwise.
pub const DEFAULT_NEIGHBOURS: usize = 12;

/// Where the normals of [`OrientedPoints`] came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum NormalSource {
    /// Area-weighted vertex normals of the input's faces.
    Faces,
    /// The input's own per-vertex normals.
    Given,
    /// PCA estimates oriented by a minimum spanning tree.
    Estimated,
}

/// The points of an input with unit outward normals.
#[derive(Debug, Clone)]
pub struct OrientedPoints {
    /// The input's distinct points first (`..original`), then samples on a coarse mesh's
    /// triangles.
    pub points: Vec<Point3<f64>>,
    pub normals: Vec<Vector3<f64>>,
    /// How many of `points` are input points (exact duplicates merged).
    pub original: usize,
    pub source: NormalSource,
    /// Normals flipped to agree with their neighbours (or all of them, when the whole input was
    /// oriented inwards).
    pub flipped: usize,
    /// Normals that had to be estimated because the input gave none usable for that point.
    pub estimated: usize,
}

/// Merges exactly coinciding points (first occurrence kept, in order), summing their given
/// normals and face normals.
#[allow(clippy::type_complexity)]
fn merge_duplicates(
    points: Vec<Point3<f64>>,
    given: Option<Vec<Vector3<f64>>>,
    normals: Vec<Vector3<f64>>,
) -> (
    Vec<Point3<f64>>,
    Option<Vec<Vector3<f64>>>,
    Vec<Vector3<f64>>,
) {
    let mut first: crate::spatial::fast_hash::IntMap<[u64; 3], usize> = Default::default();
    let mut map = Vec::with_capacity(points.len());
    let mut out = Vec::with_capacity(points.len());
    for p in &points {
        // +0.0 and -0.0 are the same point.
        let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
        let next = out.len();
        let i = *first.entry(key).or_insert(next);
        if i == next {
            out.push(*p);
        }
        map.push(i);
    }
    if out.len() == points.len() {
        return (points, given, normals);
    }
    let sum = |v: &[Vector3<f64>]| {
        let mut acc = vec![Vector3::zeros(); out.len()];
        for (n, &i) in v.iter().zip(&map) {
            acc[i] += n;
        }
        acc
    };
    let given = given.map(|g| sum(&g));
    let normals = if normals.is_empty() {
        normals
    } else {
        sum(&normals)
    };
    (out, given, normals)
}

/// Index of the extreme point (largest or smallest x, y or z) whose normal is best aligned with
/// its axis, and that outward axis direction.
fn extreme_check(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
) -> Option<(usize, Vector3<f64>)> {
    let mut ext = [0usize; 6];
    for (i, p) in points.iter().enumerate() {
        for a in 0..3 {
            if p[a] > points[ext[2 * a]][a] {
                ext[2 * a] = i;
            }
            if p[a] < points[ext[2 * a + 1]][a] {
                ext[2 * a + 1] = i;
            }
        }
    }
    let mut best: Option<(usize, Vector3<f64>, f64)> = None;
    for (e, &i) in ext.iter().enumerate() {
        let mut dir = Vector3::zeros();
        dir[e / 2] = if e % 2 == 0 { 1.0 } else { -1.0 };
        let align = normals[i].dot(&dir).abs();
        if best.is_none_or(|b| align > b.2) {
            best = Some((i, dir, align));
        }
    }
    best.filter(|b| b.2 > 0.0).map(|b| (b.0, b.1))
}

/// The referenced points of `input` (all points of a cloud) with unit outward normals:
/// face normals for a mesh, the given normals for a cloud that has them (flipped ones repaired),
/// otherwise PCA over `k` neighbours oriented by a minimum spanning tree. Errors on empty input
/// or non-finite coordinates.
pub fn oriented_points(input: &Mesh, k: usize) -> Result<OrientedPoints> {
    let k = k.max(4);
    let (points, given, source, normals) = if input.faces.is_empty() {
        let src = if input.normals.is_some() {
            NormalSource::Given
        } else {
            NormalSource::Estimated
        };
        (
            input.positions.clone(),
            input.normals.clone(),
            src,
            Vec::new(),
        )
    } else {
        let used = input.referenced();
        let vn = vertex_normals(input);
        let mut pts = Vec::new();
        let mut nrm = Vec::new();
        for i in 0..input.positions.len() {
            if used[i] {
                pts.push(input.positions[i]);
                nrm.push(vn[i]);
            }
        }
        (pts, None, NormalSource::Faces, nrm)
    };
    if points.is_empty() {
        return Err(Error::Degenerate("no points to reconstruct from".into()));
    }
    if points
        .iter()
        .any(|p| !p.coords.iter().all(|c| c.is_finite()))
    {
        return Err(Error::Degenerate("non-finite point coordinate".into()));
    }
    if let Some(g) = &given {
        if g.len() != points.len() {
            return Err(Error::Degenerate(format!(
                "{} points but {} normals",
                points.len(),
                g.len()
            )));
        }
    }
    // Exact duplicates (seams of a mesh, repeated scan points) carry no information and make
    // spacing estimates and interpolation degenerate: merged, their normals summed.
    let (mut points, mut given, mut normals) = merge_duplicates(points, given, normals);
    let original = points.len();
    // A coarse mesh is sampled on its edges and faces, so that the surface follows the
    // triangles rather than only their corners.
    if source == NormalSource::Faces {
        if let Some(b) = crate::mesh::Aabb::of(&points) {
            let (sp, sn) = crate::mesh::sample::sample_surface(input, b.diagonal() / MESH_SAMPLING);
            points.extend(sp);
            normals.extend(sn);
        }
    }
    if let Some(g) = given.as_mut() {
        g.truncate(points.len());
    }
    let kd = KdTree::build(&points)?;
    let mut flipped = 0;
    let mut estimated = 0;
    match source {
        NormalSource::Estimated => {
            normals = estimate_normals(&points, &kd, k);
            orient_mst(&points, &mut normals, &kd, k);
            estimated = points.len();
        }
        NormalSource::Given | NormalSource::Faces => {
            if let Some(g) = given.take() {
                normals = g;
            }
            for n in normals.iter_mut() {
                *n = n
                    .try_normalize(1e-300)
                    .filter(|u| u.iter().all(|c| c.is_finite()))
                    .unwrap_or_else(Vector3::zeros);
            }
            // Points without a usable normal: PCA, signed by their neighbours.
            let missing: Vec<usize> = (0..points.len())
                .filter(|&i| normals[i].norm_squared() == 0.0)
                .collect();
            if !missing.is_empty() {
                let pca = estimate_normals(&points, &kd, k);
                for &i in &missing {
                    let mut s = 0.0;
                    for (j, _) in kd.knn(&points[i], k + 1) {
                        s += normals[j].dot(&pca[i]);
                    }
                    normals[i] = if s < 0.0 { -pca[i] } else { pca[i] };
                }
                estimated = missing.len();
            }
            // A consistently oriented mesh keeps its normals; otherwise repair local flips.
            let consistent =
                source == NormalSource::Faces && Topology::build(input).misoriented_edges == 0;
            if !consistent {
                flipped += repair_flips(&points, &mut normals, &kd, k);
            }
            // Global outward check.
            if let Some((i, dir)) = extreme_check(&points, &normals) {
                if normals[i].dot(&dir) < 0.0 {
                    for n in normals.iter_mut() {
                        *n = -*n;
                    }
                    flipped = points.len() - flipped;
                }
            }
        }
    }
    Ok(OrientedPoints {
        points,
        normals,
        original,
        source,
        flipped,
        estimated,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron(inward: bool) -> Mesh {
        let p = vec![
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(-1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, -1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(0.0, 0.0, -1.0),
        ];
        let mut f = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        if inward {
            for t in &mut f {
                t.swap(1, 2);
            }
        }
        Mesh {
            positions: p,
            normals: None,
            faces: f,
        }
    }

    #[test]
    fn mesh_normals_point_outwards() {
        for inward in [false, true] {
            let m = octahedron(inward);
            let o = oriented_points(&m, 4).unwrap();
            assert_eq!(o.source, NormalSource::Faces);
            assert_eq!(o.original, 6);
            for (p, n) in o.points.iter().zip(&o.normals).take(o.original) {
                assert!(p.coords.dot(n) > 0.9, "{inward}");
            }
            // Samples on the faces point outwards too.
            for (p, n) in o.points.iter().zip(&o.normals) {
                assert!(p.coords.dot(n) > 0.0, "{inward}");
            }
        }
    }

    #[test]
    fn duplicates_are_merged() {
        let p = vec![
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(-0.0, 0.0, 1.0),
        ];
        let n = vec![Vector3::z(); 5];
        let o = oriented_points(&Mesh::from_points(p, Some(n)), 4).unwrap();
        assert_eq!(o.original, 3);
        assert_eq!(o.points.len(), 3);
        assert!((o.normals[0] - Vector3::z()).norm() < 1e-12);
    }

    #[test]
    fn empty_and_nan_inputs_are_errors() {
        assert!(oriented_points(&Mesh::default(), 8).is_err());
        let m = Mesh::from_points(vec![Point3::new(f64::NAN, 0.0, 0.0)], None);
        assert!(oriented_points(&m, 8).is_err());
    }
}
