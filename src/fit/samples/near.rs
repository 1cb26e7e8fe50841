//! Keeping an open fit's samples near its data ([`NearData`]).

use crate::polygonize::QuadNet;
use crate::spatial::KdTree;
use nalgebra::Point3;

/// Where samples belong in an open fit: within `radius` of some data point. Away from the data
/// the implicit is an extrapolation, and a section curve between two supported net nodes can
/// run out along it (round the cut of a half scan and back: on the cow cut at its middle an
/// edge 0.2 long reached 1.0 below the cut, 8 % of the diagonal). An edge or interior row with
/// a sample farther than `radius` is made again from points near the chord or Coons patch
/// (projected onto f = 0), and that is kept when it lies at most half as far from the data.
#[derive(Clone, Copy)]
pub struct NearData<'a> {
    pub data: &'a KdTree,
    pub radius: f64,
}

impl std::fmt::Debug for NearData<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NearData")
            .field("points", &self.data.len())
            .field("radius", &self.radius)
            .finish()
    }
}

impl<'a> NearData<'a> {
    /// Samples of `net` kept within half its mean edge length of `data` (a net node lies
    /// within about an edge of the data; its edges' samples, on the surface between two
    /// nodes, nearer).
    pub fn for_net(data: &'a KdTree, net: &QuadNet) -> Self {
        let total: f64 = net
            .edges
            .iter()
            .map(|&[a, b]| (net.nodes[a as usize] - net.nodes[b as usize]).norm())
            .sum();
        let radius = 0.5 * total / net.edges.len().max(1) as f64;
        NearData { data, radius }
    }

    /// Whether `p` lies farther than `radius` from the data.
    pub(super) fn beyond(&self, p: &Point3<f64>) -> bool {
        self.data.nearest(p).1 > self.radius
    }

    /// Distance from the data of the farthest of `points`.
    fn farthest<'p>(&self, points: impl IntoIterator<Item = &'p Point3<f64>>) -> f64 {
        points
            .into_iter()
            .map(|p| self.data.nearest(p).1)
            .fold(0.0, f64::max)
    }
}

/// How much nearer the data a replacement must lie to be taken: at most this share of the
/// original's distance (a section curve is kept over the projected chord or Coons row, whose
/// tangents are only approximate, unless it clearly ran off).
const CLEARLY_NEARER: f64 = 0.5;

/// `x` (an edge's or row's samples, `points` of it), or `other()` when `near` is given, `x`
/// strays farther than `near.radius` from the data and `other()` lies at most
/// [`CLEARLY_NEARER`] times as far.
pub(super) fn keep_near<T>(
    near: Option<NearData>,
    x: T,
    points: impl Fn(&T) -> &[Point3<f64>],
    other: impl FnOnce() -> Option<T>,
) -> T {
    let Some(near) = near else {
        return x;
    };
    let far = near.farthest(points(&x));
    if far <= near.radius {
        return x;
    }
    match other() {
        Some(o) if near.farthest(points(&o)) < CLEARLY_NEARER * far => o,
        _ => x,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::edge_curve::{EdgeMethod, EdgeSamples};
    use nalgebra::Vector3;

    /// An edge of samples along the x axis at height `z` (x from 0 to 1).
    fn edge_at(z: f64, method: EdgeMethod) -> EdgeSamples {
        let points: Vec<Point3<f64>> = (0..=4)
            .map(|k| Point3::new(k as f64 / 4.0, 0.0, z * (k % 4).min(1) as f64))
            .collect();
        let n = points.len();
        EdgeSamples {
            points,
            tangents: vec![Vector3::x(); n],
            normals: vec![Vector3::z(); n],
            residuals: vec![0.0; n],
            method,
            plane_w: Vector3::z(),
        }
    }

    #[test]
    fn a_strayed_edge_gives_way_to_a_clearly_nearer_one() {
        // Data along the x axis.
        let data: Vec<Point3<f64>> = (0..=100)
            .map(|k| Point3::new(k as f64 / 100.0, 0.0, 0.0))
            .collect();
        let tree = KdTree::build(&data).unwrap();
        let near = NearData {
            data: &tree,
            radius: 0.1,
        };
        // Near the data: kept, the alternative not even made.
        fn points(e: &EdgeSamples) -> &[Point3<f64>] {
            &e.points
        }
        let kept = keep_near(Some(near), edge_at(0.05, EdgeMethod::Lines), points, || {
            panic!("no alternative needed")
        });
        assert_eq!(kept.method, EdgeMethod::Lines);
        // Strayed 1.0 off: the chord-like alternative 0.02 off replaces it.
        let swapped = keep_near(Some(near), edge_at(1.0, EdgeMethod::Lines), points, || {
            Some(edge_at(0.02, EdgeMethod::ProjectedChord))
        });
        assert_eq!(swapped.method, EdgeMethod::ProjectedChord);
        // An alternative not at most half as far, or none at all: the section curve stays.
        let same = keep_near(Some(near), edge_at(1.0, EdgeMethod::Lines), points, || {
            Some(edge_at(0.6, EdgeMethod::ProjectedChord))
        });
        assert_eq!(same.method, EdgeMethod::Lines);
        let same = keep_near(Some(near), edge_at(1.0, EdgeMethod::Lines), points, || None);
        assert_eq!(same.method, EdgeMethod::Lines);
        // No data given (a closed fit): as it is, however far.
        let closed = keep_near(None, edge_at(1.0, EdgeMethod::Lines), points, || {
            panic!("a closed fit looks for nothing nearer")
        });
        assert_eq!(closed.method, EdgeMethod::Lines);
    }

    #[test]
    fn radius_is_half_the_mean_edge() {
        let data = vec![Point3::origin()];
        let tree = KdTree::build(&data).unwrap();
        let net = crate::polygonize::QuadNet::new_open(
            vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(2.0, 0.0, 0.0),
                Point3::new(2.0, 2.0, 0.0),
                Point3::new(0.0, 2.0, 0.0),
            ],
            vec![[0, 1, 2, 3]],
        )
        .unwrap();
        let near = NearData::for_net(&tree, &net);
        assert!((near.radius - 1.0).abs() < 1e-12, "{near:?}");
    }
}
