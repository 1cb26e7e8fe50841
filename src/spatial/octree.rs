//! Adaptive octree for domain decomposition (seed 003 section 3.1, seed 004 section 2.1).
//!
//! The space around the points is a root cube that is split recursively into eight children.
//! Whether a cell is split is decided by a caller-supplied rule (more than a maximum number of
//! points, or a local fit that misses its tolerance); a cell that is not split becomes a leaf
//! carrying a payload (the local function) and a *support* box, usually the cell enlarged by an
//! overlap factor so that neighbouring supports overlap (seed 003 recommends about 10 %).
//!
//! Queries return the leaves whose support contains a point without scanning all leaves: every
//! node stores the bounding box of the supports in its subtree (its *reach*), and a query only
//! descends into nodes whose reach contains the point. Every terminal node (one without
//! children) also keeps the list of leaves whose support meets its cube, in that traversal's
//! order: a query inside the root cube walks down to the terminal node holding the point (one
//! child per level) and tests only that list, with the same leaves in the same order as the
//! full traversal (so sums over them round identically), several times faster where supports
//! overlap widely.
//!
//! Construction is level by level; the cells of one level are decided in parallel (rayon) and
//! collected in order, so the tree is the same for any thread count.

use crate::mesh::Aabb;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// An axis-aligned cube: `min` corner and edge length.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cube {
    pub min: Point3<f64>,
    pub size: f64,
}

impl Cube {
    /// The cube centred on the box `b`, with edge `(1 + 2 margin)` times its longest side
    /// (a degenerate box gets edge 1).
    pub fn around(b: &Aabb, margin: f64) -> Cube {
        let ext = b.max - b.min;
        let mut size = ext.max() * (1.0 + 2.0 * margin);
        if size.is_nan() || size <= 0.0 || !size.is_finite() {
            size = 1.0;
        }
        let c = b.center();
        Cube {
            min: c - Vector3::repeat(0.5 * size),
            size,
        }
    }
    pub fn center(&self) -> Point3<f64> {
        self.min + Vector3::repeat(0.5 * self.size)
    }
    pub fn max(&self) -> Point3<f64> {
        self.min + Vector3::repeat(self.size)
    }
    /// Child `i` (bit 0: upper half in x, bit 1: in y, bit 2: in z).
    pub fn child(&self, i: usize) -> Cube {
        let h = 0.5 * self.size;
        Cube {
            min: self.min
                + Vector3::new(
                    if i & 1 != 0 { h } else { 0.0 },
                    if i & 2 != 0 { h } else { 0.0 },
                    if i & 4 != 0 { h } else { 0.0 },
                ),
            size: h,
        }
    }
    /// Which child holds `p` (points on the mid planes go to the upper child).
    pub fn child_of(&self, p: &Point3<f64>) -> usize {
        let c = self.center();
        (p.x >= c.x) as usize | (((p.y >= c.y) as usize) << 1) | (((p.z >= c.z) as usize) << 2)
    }
    /// The cube as a box scaled about its centre by `factor`.
    pub fn scaled_box(&self, factor: f64) -> Aabb {
        let c = self.center();
        let h = Vector3::repeat(0.5 * self.size * factor);
        Aabb {
            min: c - h,
            max: c + h,
        }
    }
    /// Closed containment test.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        let m = self.max();
        (0..3).all(|k| p[k] >= self.min[k] && p[k] <= m[k])
    }
}

/// What the split rule sees of a cell.
#[derive(Debug)]
pub struct CellContext<'a> {
    pub cube: Cube,
    pub depth: u32,
    /// Indices of the points inside the cell.
    pub points: &'a [u32],
    /// False at the maximum depth: the rule must then make a leaf.
    pub can_split: bool,
}

/// The split rule's answer.
#[derive(Debug)]
pub enum Decision<T> {
    /// Keep the cell as a leaf with this payload and support box.
    Leaf { payload: T, support: Aabb },
    /// Split the cell into eight children.
    Split,
}

#[derive(Debug, Clone)]
struct Node {
    cube: Cube,
    /// Index of the first of eight consecutive children; 0 for a leaf (the root is never a child).
    first_child: u32,
    /// Leaf index for leaves, `u32::MAX` for inner nodes.
    leaf: u32,
    /// Bounding box of the supports of all leaves below (empty box when none).
    reach: Aabb,
}

/// The adaptive octree with one payload per leaf.
#[derive(Debug, Clone)]
pub struct Octree<T> {
    nodes: Vec<Node>,
    payloads: Vec<T>,
    supports: Vec<Aabb>,
    leaf_cubes: Vec<Cube>,
    leaf_depths: Vec<u32>,
    /// Per node, the range in `candidates` of the leaves whose support meets the node's cube
    /// (empty for inner nodes): `candidates[candidate_start[n]..candidate_start[n + 1]]`.
    candidate_start: Vec<u32>,
    candidates: Vec<u32>,
}

/// Closed intersection of a support box and a cube.
fn box_meets_cube(b: &Aabb, c: &Cube) -> bool {
    let m = c.max();
    (0..3).all(|k| b.min[k] <= m[k] && b.max[k] >= c.min[k])
}

fn empty_box() -> Aabb {
    Aabb {
        min: Point3::from(Vector3::repeat(f64::INFINITY)),
        max: Point3::from(Vector3::repeat(f64::NEG_INFINITY)),
    }
}

fn box_contains(b: &Aabb, p: &Point3<f64>) -> bool {
    (0..3).all(|k| p[k] >= b.min[k] && p[k] <= b.max[k])
}

/// Depth-first walk over the nodes whose reach passes `hit`, calling `f` for each leaf whose
/// support passes it; children in order 0..8 after their parent.
#[inline]
fn traverse<H: Fn(&Aabb) -> bool, F: FnMut(usize)>(
    nodes: &[Node],
    supports: &[Aabb],
    hit: H,
    mut f: F,
) {
    let mut stack = [0u32; 256];
    let mut top = 1usize;
    stack[0] = 0;
    while top > 0 {
        top -= 1;
        let n = &nodes[stack[top] as usize];
        if !hit(&n.reach) {
            continue;
        }
        if n.leaf != u32::MAX && hit(&supports[n.leaf as usize]) {
            f(n.leaf as usize);
        }
        if n.first_child != 0 {
            for c in (n.first_child..n.first_child + 8).rev() {
                if top < stack.len() {
                    stack[top] = c;
                    top += 1;
                }
            }
        }
    }
}

impl<T: Send> Octree<T> {
    /// Builds the tree over `points` inside `root` (points outside the root cube are ignored),
    /// splitting a cell whenever `decide` answers [`Decision::Split`] and the depth is below
    /// `max_depth`.
    pub fn build<F>(root: Cube, points: &[Point3<f64>], max_depth: u32, decide: F) -> Octree<T>
    where
        F: Fn(&CellContext) -> Decision<T> + Sync,
    {
        let inside: Vec<u32> = (0..points.len() as u32)
            .filter(|&i| root.contains(&points[i as usize]))
            .collect();
        let mut nodes = vec![Node {
            cube: root,
            first_child: 0,
            leaf: u32::MAX,
            reach: empty_box(),
        }];
        let mut payloads = Vec::new();
        let mut supports = Vec::new();
        let mut leaf_cubes = Vec::new();
        let mut leaf_depths = Vec::new();
        let mut level: Vec<(usize, Vec<u32>)> = vec![(0, inside)];
        let mut depth = 0u32;
        while !level.is_empty() {
            let decisions: Vec<Decision<T>> = level
                .par_iter()
                .map(|(ni, pts)| {
                    decide(&CellContext {
                        cube: nodes[*ni].cube,
                        depth,
                        points: pts,
                        can_split: depth < max_depth,
                    })
                })
                .collect();
            let mut next = Vec::new();
            for ((ni, pts), d) in level.into_iter().zip(decisions) {
                match d {
                    Decision::Leaf { payload, support } => {
                        nodes[ni].leaf = payloads.len() as u32;
                        payloads.push(payload);
                        supports.push(support);
                        leaf_cubes.push(nodes[ni].cube);
                        leaf_depths.push(depth);
                    }
                    Decision::Split if depth >= max_depth => {
                        // The rule ignored `can_split`: keep an empty leaf-less node.
                    }
                    Decision::Split => {
                        let cube = nodes[ni].cube;
                        let first = nodes.len();
                        nodes[ni].first_child = first as u32;
                        let mut parts: [Vec<u32>; 8] = Default::default();
                        for &p in &pts {
                            parts[cube.child_of(&points[p as usize])].push(p);
                        }
                        for (i, part) in parts.into_iter().enumerate() {
                            nodes.push(Node {
                                cube: cube.child(i),
                                first_child: 0,
                                leaf: u32::MAX,
                                reach: empty_box(),
                            });
                            next.push((first + i, part));
                        }
                    }
                }
            }
            level = next;
            depth += 1;
        }
        // Reaches bottom-up: children always come after their parent.
        for ni in (0..nodes.len()).rev() {
            let mut r = empty_box();
            if nodes[ni].leaf != u32::MAX {
                let s = supports[nodes[ni].leaf as usize];
                r.min = r.min.inf(&s.min);
                r.max = r.max.sup(&s.max);
            }
            if nodes[ni].first_child != 0 {
                let f = nodes[ni].first_child as usize;
                for child in &nodes[f..f + 8] {
                    r.min = r.min.inf(&child.reach.min);
                    r.max = r.max.sup(&child.reach.max);
                }
            }
            nodes[ni].reach = r;
        }
        let mut tree = Octree {
            nodes,
            payloads,
            supports,
            leaf_cubes,
            leaf_depths,
            candidate_start: Vec::new(),
            candidates: Vec::new(),
        };
        tree.index_candidates();
        tree
    }

    /// Fills `candidate_start` / `candidates` (module doc): for each terminal node, the leaves
    /// whose support meets its cube, found by the traversal of `for_each_support` with the
    /// point test replaced by a cube test (so in the order that traversal visits them).
    fn index_candidates(&mut self) {
        let (nodes, supports) = (&self.nodes, &self.supports);
        let lists: Vec<Vec<u32>> = (0..nodes.len())
            .into_par_iter()
            .map(|ni| {
                let n = &nodes[ni];
                if n.first_child != 0 {
                    return Vec::new();
                }
                let cube = n.cube;
                let mut out = Vec::new();
                traverse(
                    nodes,
                    supports,
                    |b| box_meets_cube(b, &cube),
                    |l| out.push(l as u32),
                );
                out
            })
            .collect();
        let mut start = Vec::with_capacity(lists.len() + 1);
        let mut all = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        for l in lists {
            start.push(all.len() as u32);
            all.extend(l);
        }
        start.push(all.len() as u32);
        self.candidate_start = start;
        self.candidates = all;
    }

    /// Calls `f(leaf index)` for every leaf whose support box contains `x`, in a fixed order.
    /// Returns the terminal node whose cube holds `x` (see [`Octree::terminal_nodes`]), or
    /// None outside the root cube.
    #[inline]
    pub fn for_each_support<F: FnMut(usize)>(&self, x: &Point3<f64>, mut f: F) -> Option<usize> {
        let mut n = &self.nodes[0];
        if !n.cube.contains(x) {
            // Outside the root cube (within a support's overlap beyond it): full traversal.
            traverse(&self.nodes, &self.supports, |b| box_contains(b, x), f);
            return None;
        }
        let mut ni = 0usize;
        while n.first_child != 0 {
            ni = n.first_child as usize + n.cube.child_of(x);
            n = &self.nodes[ni];
        }
        let (a, b) = (self.candidate_start[ni], self.candidate_start[ni + 1]);
        for &l in &self.candidates[a as usize..b as usize] {
            if box_contains(&self.supports[l as usize], x) {
                f(l as usize);
            }
        }
        Some(ni)
    }

    /// The nodes without children (leaves, and cells left without a payload) as (node index,
    /// cube): they tile the root cube. Node indices run below [`Octree::node_count`].
    pub fn terminal_nodes(&self) -> impl Iterator<Item = (usize, Cube)> + '_ {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.first_child == 0)
            .map(|(i, n)| (i, n.cube))
    }

    /// The leaf whose cell contains `x`, if any.
    pub fn leaf_at(&self, x: &Point3<f64>) -> Option<usize> {
        let mut n = &self.nodes[0];
        if !n.cube.contains(x) {
            return None;
        }
        loop {
            if n.first_child == 0 {
                return (n.leaf != u32::MAX).then_some(n.leaf as usize);
            }
            n = &self.nodes[n.first_child as usize + n.cube.child_of(x)];
        }
    }

    /// The root cube.
    pub fn root(&self) -> Cube {
        self.nodes[0].cube
    }
    /// Leaf payloads, indexed by leaf.
    pub fn payloads(&self) -> &[T] {
        &self.payloads
    }
    /// Leaf support boxes.
    pub fn supports(&self) -> &[Aabb] {
        &self.supports
    }
    /// Leaf cells.
    pub fn leaf_cubes(&self) -> &[Cube] {
        &self.leaf_cubes
    }
    /// Leaf depths (root = 0).
    pub fn leaf_depths(&self) -> &[u32] {
        &self.leaf_depths
    }
    /// Number of nodes (inner and leaves).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud() -> Vec<Point3<f64>> {
        // Points on a helix-like curve, unevenly spread.
        (0..2000)
            .map(|i| {
                let t = i as f64 / 2000.0;
                Point3::new((t * 20.0).cos() * t, (t * 20.0).sin() * t, t * t)
            })
            .collect()
    }

    fn build(max_points: usize) -> (Vec<Point3<f64>>, Octree<usize>) {
        let pts = cloud();
        let root = Cube::around(&Aabb::of(&pts).unwrap(), 0.05);
        let t = Octree::build(root, &pts, 12, |c| {
            if c.points.len() > max_points && c.can_split {
                Decision::Split
            } else {
                Decision::Leaf {
                    payload: c.points.len(),
                    support: c.cube.scaled_box(1.1),
                }
            }
        });
        (pts, t)
    }

    #[test]
    fn leaves_partition_points() {
        let (pts, t) = build(50);
        let total: usize = t.payloads().iter().sum();
        assert_eq!(total, pts.len());
        assert!(t.payloads().iter().all(|&n| n <= 50));
        for p in &pts {
            let l = t.leaf_at(p).unwrap();
            assert!(t.leaf_cubes()[l].contains(p));
        }
    }

    #[test]
    fn support_query_matches_scan() {
        let (_, t) = build(30);
        let probes = [
            Point3::new(0.1, 0.2, 0.3),
            Point3::new(-0.5, 0.4, 0.9),
            Point3::new(0.7, -0.7, 0.5),
            Point3::new(5.0, 5.0, 5.0),
        ];
        for x in probes {
            let mut got = Vec::new();
            t.for_each_support(&x, |l| got.push(l));
            got.sort_unstable();
            let want: Vec<usize> = (0..t.supports().len())
                .filter(|&l| box_contains(&t.supports()[l], &x))
                .collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn deterministic_across_thread_counts() {
        let (_, a) = build(20);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let (_, b) = pool.install(|| build(20));
        assert_eq!(a.payloads(), b.payloads());
        assert_eq!(a.leaf_cubes(), b.leaf_cubes());
    }
}
