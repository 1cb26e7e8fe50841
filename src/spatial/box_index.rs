//! Points inside an axis-aligned box, for the domain decomposition's support queries
//! (`implicit::pou`: every octree cell asks for the points in its enlarged cube, seed 003
//! section 3.1).
//!
//! The points are sorted by their Morton (z-order) code on a 2^21 grid over their bounding
//! cube, so that the points of every cell of the implicit octree of code prefixes are one
//! contiguous run; the cells holding more than [`RUN`] points are stored as an explicit tree of
//! runs. A query descends it from the root: a cell whose cube misses the box is skipped, a
//! run of at most [`RUN`] points is tested point by point. The result is the
//! same set a ball query of radius h sqrt(3) filtered to the box gives, at a fraction of the
//! cost: the ball holds two to three times the box's points, and a k-d tree's ball query
//! walks and reports all of them. (Written here because kiddo, the k-d tree crate used
//! elsewhere, has no box query.)

use nalgebra::Point3;

/// Bits per axis of the Morton grid (3 x 21 = 63 bits of a u64 code).
const LEVELS: u32 = 21;
/// Runs this short are tested point by point instead of being split further.
const RUN: usize = 24;

/// Points sorted by Morton code, with their original indices.
#[derive(Debug, Clone)]
pub struct BoxIndex {
    /// Sorted points and their indices in the input.
    pts: Vec<[f64; 3]>,
    index: Vec<u32>,
    /// The cells of the tree, root first; the children of a cell are consecutive.
    nodes: Vec<Node>,
    /// Slack on the cube-versus-box test: cells are pruned only when they miss the box by
    /// more than rounding could move a point across a cell face.
    slack: f64,
}

/// A cell of the Morton octree with points: its run of sorted points and its cube.
#[derive(Debug, Clone, Copy)]
struct Node {
    lo: u32,
    hi: u32,
    /// Lower corner and edge of the cube.
    min: [f64; 3],
    edge: f64,
    /// First child in `nodes` and the number of children (0: test the run point by point).
    first: u32,
    children: u8,
}

/// Spreads the low 21 bits of `x` to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

impl BoxIndex {
    /// Index of `points` (any count; non-finite points are never reported).
    pub fn build(points: &[Point3<f64>]) -> BoxIndex {
        let finite = |p: &&Point3<f64>| p.iter().all(|c| c.is_finite());
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in points.iter().filter(finite) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let size = if lo.x <= hi.x {
            (hi - lo).max().max(f64::MIN_POSITIVE)
        } else {
            1.0
        };
        let cells = (1u64 << LEVELS) as f64;
        let quantize =
            |x: f64, o: f64| (((x - o) / size * cells).floor()).clamp(0.0, cells - 1.0) as u64;
        let mut keyed: Vec<(u64, u32)> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| finite(p))
            .map(|(i, p)| {
                let code = spread(quantize(p.x, lo.x))
                    | (spread(quantize(p.y, lo.y)) << 1)
                    | (spread(quantize(p.z, lo.z)) << 2);
                (code, i as u32)
            })
            .collect();
        keyed.sort_unstable();
        let codes: Vec<u64> = keyed.iter().map(|k| k.0).collect();
        let nodes = tree(&codes, [lo.x, lo.y, lo.z], size);
        BoxIndex {
            nodes,
            pts: keyed
                .iter()
                .map(|&(_, i)| {
                    let p = points[i as usize];
                    [p.x, p.y, p.z]
                })
                .collect(),
            index: keyed.iter().map(|k| k.1).collect(),
            slack: 1e-9 * size + 4.0 * f64::EPSILON * lo.coords.amax(),
        }
    }

    /// Indices (ascending) of the points p with |p_k - c_k| <= h on every axis k.
    pub fn within_box(&self, c: &Point3<f64>, h: f64) -> Vec<usize> {
        // Room for a typical cell's support without regrowing (the implicit's cells hold up
        // to a few hundred points; growing from empty was 2 % of `fit`).
        let mut out = Vec::with_capacity(256);
        if h.is_nan() || h < 0.0 || self.pts.is_empty() {
            return out;
        }
        let c = [c.x, c.y, c.z];
        let misses = |n: &Node| {
            (0..3).any(|k| {
                n.min[k] + n.edge + self.slack < c[k] - h || n.min[k] - self.slack > c[k] + h
            })
        };
        let mut stack = Vec::with_capacity(64);
        stack.push(0u32);
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            if misses(n) {
                continue;
            }
            if n.children > 0 {
                stack.extend(n.first..n.first + n.children as u32);
                continue;
            }
            for i in n.lo as usize..n.hi as usize {
                let p = &self.pts[i];
                if (0..3).all(|k| (p[k] - c[k]).abs() <= h) {
                    out.push(self.index[i] as usize);
                }
            }
        }
        out.sort_unstable();
        out
    }
}

/// The tree of runs over sorted `codes`: a cell with more than [`RUN`] points (above the
/// finest level) gets its non-empty children, found by binary search on the three code bits
/// below its prefix.
fn tree(codes: &[u64], origin: [f64; 3], size: f64) -> Vec<Node> {
    let mut nodes = vec![Node {
        lo: 0,
        hi: codes.len() as u32,
        min: origin,
        edge: size,
        first: 0,
        children: 0,
    }];
    // (node, level, integer corner in units of its edge)
    let mut todo = vec![(0usize, 0u32, [0u64; 3])];
    while let Some((ni, level, cell)) = todo.pop() {
        let (lo, hi) = (nodes[ni].lo as usize, nodes[ni].hi as usize);
        if hi - lo <= RUN || level == LEVELS {
            continue;
        }
        let shift = 3 * (LEVELS - level - 1);
        let edge = size / (1u64 << (level + 1)) as f64;
        let first = nodes.len();
        let mut start = lo;
        for child in 0..8u64 {
            let end = start + codes[start..hi].partition_point(|&x| (x >> shift) & 7 <= child);
            if end > start {
                let corner = [
                    2 * cell[0] + (child & 1),
                    2 * cell[1] + ((child >> 1) & 1),
                    2 * cell[2] + ((child >> 2) & 1),
                ];
                todo.push((nodes.len(), level + 1, corner));
                nodes.push(Node {
                    lo: start as u32,
                    hi: end as u32,
                    min: [0, 1, 2].map(|k| origin[k] + corner[k] as f64 * edge),
                    edge,
                    first: 0,
                    children: 0,
                });
            }
            start = end;
        }
        nodes[ni].first = first as u32;
        nodes[ni].children = (nodes.len() - first) as u8;
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::KdTree;

    fn cloud(n: usize, seed: u64) -> Vec<Point3<f64>> {
        // A deterministic scatter on and around a sphere, with duplicates.
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut v: Vec<Point3<f64>> = (0..n)
            .map(|_| {
                let (a, b, r) = (next() * 6.0, next() * 3.0, 1.0 + 0.05 * next());
                Point3::new(
                    r * a.cos() * b.sin(),
                    r * a.sin() * b.sin(),
                    r * b.cos() + 0.3,
                )
            })
            .collect();
        v.extend_from_within(0..10);
        v
    }

    /// The same set as the k-d tree's ball query filtered to the box, over boxes from a
    /// point-sized one to one holding everything, centred on points and off them.
    #[test]
    fn matches_ball_query_filtered_to_the_box() {
        let pts = cloud(3000, 7);
        let kd = KdTree::build(&pts).unwrap();
        let idx = BoxIndex::build(&pts);
        for (k, h) in [1e-4, 0.01, 0.05, 0.2, 0.7, 3.0].into_iter().enumerate() {
            for j in (0..pts.len()).step_by(97) {
                let c = pts[j] + nalgebra::Vector3::new(0.3, -0.2, 0.1) * (k as f64 * 0.01);
                let mut want = kd.within(&c, h * 3f64.sqrt());
                want.retain(|&i| (0..3).all(|a| (pts[i][a] - c[a]).abs() <= h));
                assert_eq!(idx.within_box(&c, h), want, "h {h} at {j}");
            }
        }
        // Points exactly on the box's faces count.
        let p = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.5, 0.25)];
        let idx = BoxIndex::build(&p);
        assert_eq!(
            idx.within_box(&Point3::new(0.5, 0.25, 0.125), 0.5),
            vec![0, 1]
        );
        assert_eq!(
            idx.within_box(&Point3::new(0.5, 0.25, 0.125), 0.49),
            Vec::<usize>::new()
        );
    }

    #[test]
    fn degenerate_inputs() {
        assert!(BoxIndex::build(&[])
            .within_box(&Point3::origin(), 1.0)
            .is_empty());
        let same = vec![Point3::new(1.0, 2.0, 3.0); 100];
        let idx = BoxIndex::build(&same);
        assert_eq!(idx.within_box(&Point3::new(1.0, 2.0, 3.0), 0.0).len(), 100);
        assert!(idx
            .within_box(&Point3::new(1.0, 2.0, 3.0), f64::NAN)
            .is_empty());
        let with_nan = vec![Point3::new(f64::NAN, 0.0, 0.0), Point3::new(0.0, 0.0, 0.0)];
        assert_eq!(
            BoxIndex::build(&with_nan).within_box(&Point3::origin(), 1.0),
            vec![1]
        );
    }
}
