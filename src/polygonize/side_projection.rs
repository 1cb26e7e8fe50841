//! A labelled quad net's nodes put onto the sharp implicit's sides (`fit --sharp`, the remesh
//! route of [`super::remesh_net`]).
//!
//! The net comes from a mesh of the implicit split into quads: its edge midpoints and triangle
//! centroids lie on chords, up to the sagitta L^2 / (8 R) off a surface of radius R, and its
//! labels are those of the mesh's own segmentation. Each net region is first given the sharp
//! implicit's region most of its quads' centres lie on ([`SideField::region`]); then every
//! node moves onto the surfaces of the regions of its quads:
//! - one region r (a face node): Newton steps x <- x - f_r(x) grad f_r / |grad f_r|^2 on that
//!   side's function (continued past its creases, so a node beside a crease stays on its own
//!   face);
//! - two or three regions (a crease node, a corner): the meeting point of their surfaces
//!   nearest to the node, f_a = f_b (= f_c) = 0 ([`meet_point`], Gauss-Newton);
//!
//! With the regions' surfaces fitted to the data around each node given as well, a crease or
//! corner node goes between those instead where they follow their points about as well as the
//! implicit's sides, unless that folds a quad ([`project_onto_sides`]).
//!
//! A move longer than `max_move` (or a solve that fails) is not made: the node stays where the
//! remesh put it. Nodes of an open boundary are left alone.

use super::crease_nodes::LocalSides;
use super::crease_split::{meet_point, CreaseSplitOptions, SideField};
use super::quad_net::{QuadNet, NO_QUAD};
use nalgebra::Point3;
use rayon::prelude::*;
use std::collections::BTreeSet;

/// What [`project_onto_sides`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SideProjectionReport {
    /// Nodes moved onto one side, onto a crease, onto a corner.
    pub face_nodes: usize,
    pub crease_nodes: usize,
    pub corner_nodes: usize,
    /// Nodes left where they were (no converged solve within the reach, or two net regions
    /// on one side of the implicit beside a node of three).
    pub kept: usize,
    /// Crease and corner nodes put between the regions' surfaces fitted to the data around
    /// them (when given) rather than the implicit's sides, and those moves undone because
    /// they folded a quad.
    pub data_fitted: usize,
    pub data_undone: usize,
    /// Largest move made, model units.
    pub max_move: f64,
}

/// Newton steps at most for a face node.
const FACE_STEPS: usize = 20;

/// The implicit region of each of the net's `regions` regions: the one most quad centres lie
/// on.
pub fn region_map(
    net: &QuadNet,
    quad_region: &[u32],
    regions: usize,
    field: &dyn SideField,
) -> Vec<u32> {
    let votes: Vec<(u32, u32)> = net
        .quads
        .par_iter()
        .zip(quad_region.par_iter())
        .map(|(q, &r)| {
            let c = Point3::from(
                q.iter()
                    .map(|&i| net.nodes[i as usize].coords)
                    .sum::<nalgebra::Vector3<f64>>()
                    / 4.0,
            );
            (r, field.region(&c))
        })
        .collect();
    let mut counts: Vec<std::collections::BTreeMap<u32, usize>> = vec![Default::default(); regions];
    for (r, s) in votes {
        if let Some(m) = counts.get_mut(r as usize) {
            *m.entry(s).or_default() += 1;
        }
    }
    counts
        .iter()
        .enumerate()
        .map(|(r, m)| {
            m.iter()
                .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
                .map_or(r as u32, |(&s, _)| s)
        })
        .collect()
}

/// Where one node goes: onto the implicit's sides, and onto the surfaces fitted to the data.
#[derive(Clone, Copy)]
struct Target {
    implicit: Option<Point3<f64>>,
    data: Option<Point3<f64>>,
    /// Regions of the node's quads (1 face, 2 crease, 3 corner).
    sides: usize,
}

impl Target {
    /// The position taken: the data's when `data` is set, else the implicit's.
    fn chosen(&self, data: bool) -> Option<Point3<f64>> {
        if data {
            self.data
        } else {
            self.implicit
        }
    }
}

/// The folded quads of a net (one flag per quad).
pub type FoldCheck<'a> = dyn Fn(&QuadNet) -> Vec<bool> + 'a;

/// Rounds of undoing the data-fitted moves that fold quads ([`project_onto_sides`]).
const UNFOLD_ROUNDS: usize = 4;

/// Moves the nodes of `net` (quads labelled `quad_region`, mapped to the field's regions by
/// `map`) onto the sides of `field` (module doc); `scale` sets the solves' tolerance (the
/// net's edge length), `max_move` the longest move made. With `data`, crease and corner nodes
/// go between the regions' surfaces fitted to the data around them where those follow their
/// points about as well as the implicit's sides ([`LocalSides::near_checked`]): beside a crease
/// the implicit's smooth cells round the last few tenths of a millimetre, where few points
/// are, and its crease line runs inside the part. `folded`, when given, flags the net's
/// folded quads: a data-fitted move that folds a quad not folded before the projection goes
/// to the implicit's position instead (round after round, [`UNFOLD_ROUNDS`] at most). That
/// keeps a patch net free of new folds, at a price: all four nodes of the quad go back, and
/// the implicit's crease runs up to a tenth of a millimetre inside the part there (hexnut.stl,
/// `reconstruct --remesh`: 36 nodes, the crease 1.6e-3 of the diagonal off), so a mesh whose
/// slivers are cleaned afterwards does better without it ([`super::crease_mesh`]).
pub fn project_onto_sides(
    net: &mut QuadNet,
    quad_region: &[u32],
    map: &[u32],
    sides: Sides,
    scale: f64,
    max_move: f64,
    folded: Option<&FoldCheck>,
) -> SideProjectionReport {
    let Sides { field, data } = sides;
    let opts = CreaseSplitOptions::default();
    let mut on_boundary = vec![false; net.nodes.len()];
    for (e, qs) in net.edges.iter().zip(&net.edge_quads) {
        if qs.contains(&NO_QUAD) {
            on_boundary[e[0] as usize] = true;
            on_boundary[e[1] as usize] = true;
        }
    }
    let targets: Vec<Option<Target>> = (0..net.nodes.len())
        .into_par_iter()
        .map(|i| {
            if on_boundary[i] {
                return None;
            }
            let quads = net.node_quads(i);
            let sides: BTreeSet<u32> = quads
                .iter()
                .filter_map(|&q| map.get(quad_region[q as usize] as usize).copied())
                .collect();
            let sides: Vec<u32> = sides.into_iter().collect();
            let x = net.nodes[i];
            let near = |y: &Point3<f64>| (y - x).norm() <= max_move;
            let fitted = if (2..=3).contains(&sides.len()) {
                data.and_then(|d| d.near_checked(&x, &sides, field, scale))
                    .and_then(|local| meet_point(local.as_ref(), &sides, x, scale, &opts))
                    .filter(near)
            } else {
                None
            };
            let implicit = match sides.len() {
                1 => onto_side(field, sides[0], x, scale, opts.tolerance),
                2 | 3 => meet_point(field, &sides, x, scale, &opts),
                _ => None,
            }
            .filter(near);
            Some(Target {
                implicit,
                data: fitted,
                sides: sides.len(),
            })
        })
        .collect();
    let start = net.nodes.clone();
    let mut use_data: Vec<bool> = targets
        .iter()
        .map(|t| t.is_some_and(|t| t.data.is_some()))
        .collect();
    // The folds before the projection, needed only when some node takes the data's position.
    let before = folded
        .filter(|_| use_data.contains(&true))
        .map(|f| (f, f(net)));
    let place = |net: &mut QuadNet, use_data: &[bool]| {
        for (i, t) in targets.iter().enumerate() {
            net.nodes[i] = t.and_then(|t| t.chosen(use_data[i])).unwrap_or(start[i]);
        }
    };
    place(net, &use_data);
    let mut report = SideProjectionReport::default();
    if let Some((folded, before)) = before {
        for _ in 0..UNFOLD_ROUNDS {
            let after = folded(net);
            let mut undone = 0;
            for (q, quad) in net.quads.iter().enumerate() {
                if after[q] && !before[q] {
                    for &i in quad {
                        undone += usize::from(std::mem::take(&mut use_data[i as usize]));
                    }
                }
            }
            if undone == 0 {
                break;
            }
            report.data_undone += undone;
            place(net, &use_data);
        }
    }
    for (i, t) in targets.iter().enumerate() {
        match (t, t.and_then(|t| t.chosen(use_data[i]))) {
            (Some(t), Some(y)) => {
                report.max_move = report.max_move.max((y - start[i]).norm());
                report.data_fitted += usize::from(use_data[i]);
                match t.sides {
                    1 => report.face_nodes += 1,
                    2 => report.crease_nodes += 1,
                    _ => report.corner_nodes += 1,
                }
            }
            _ => report.kept += 1,
        }
    }
    report
}

/// The surfaces [`project_onto_sides`] puts nodes on: the implicit's sides, and optionally
/// the regions' surfaces fitted to the data around a node.
#[derive(Clone, Copy)]
pub struct Sides<'a> {
    pub field: &'a dyn SideField,
    pub data: Option<&'a dyn LocalSides>,
}

/// Newton's iteration onto f_region = 0 from `x`, or `None` when it does not converge to
/// |f| / |grad f| <= tolerance scale.
fn onto_side(
    field: &dyn SideField,
    region: u32,
    mut x: Point3<f64>,
    scale: f64,
    tolerance: f64,
) -> Option<Point3<f64>> {
    for _ in 0..FACE_STEPS {
        let (f, g) = field.side(region, &x);
        let g2 = g.norm_squared();
        if !(g2 > 0.0 && f.is_finite()) {
            return None;
        }
        if f.abs() <= tolerance * scale * g2.sqrt() {
            return Some(x);
        }
        x -= g * (f / g2);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// Two half-planes meeting at a right angle along the y axis: side 0 the plane z = 0,
    /// side 1 the plane x = `off`.
    struct Planes {
        off: f64,
    }

    impl SideField for Planes {
        fn region(&self, x: &Point3<f64>) -> u32 {
            u32::from(x.z < -0.5)
        }
        fn side(&self, region: u32, x: &Point3<f64>) -> (f64, Vector3<f64>) {
            match region {
                0 => (x.z, Vector3::z()),
                _ => (x.x - self.off, Vector3::x()),
            }
        }
    }

    /// Data whose surfaces put the edge 0.3 out along x, and always pass the check.
    struct Data;

    impl LocalSides for Data {
        fn near(&self, _: &Point3<f64>, _: &[u32]) -> Option<Box<dyn SideField + Send + Sync>> {
            Some(Box::new(Planes { off: 0.3 }))
        }
        fn near_checked(
            &self,
            x: &Point3<f64>,
            regions: &[u32],
            _: &dyn SideField,
            _: f64,
        ) -> Option<Box<dyn SideField + Send + Sync>> {
            self.near(x, regions)
        }
        fn region(&self, x: &Point3<f64>) -> Option<u32> {
            Some(Planes { off: 0.3 }.region(x))
        }
    }

    /// An L of unit quads: two rows on z = 0 (x from -2 to 0), two on x = 0 (z from 0 to
    /// -2), four along y; the crease nodes are (0, j, 0). Quad labels: 0 on z = 0, 1 on x = 0.
    fn l_net() -> (QuadNet, Vec<u32>) {
        let id = |i: usize, j: usize| (i * 5 + j) as u32;
        // Column i: x = i - 2 on the top (i <= 2), z = 2 - i on the side (i >= 2).
        let nodes = (0..5)
            .flat_map(|i| {
                (0..5).map(move |j| {
                    let (x, z) = if i <= 2 {
                        (i as f64 - 2.0, 0.0)
                    } else {
                        (0.0, 2.0 - i as f64)
                    };
                    Point3::new(x, j as f64, z)
                })
            })
            .collect();
        let mut quads = Vec::new();
        let mut labels = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                labels.push(u32::from(i >= 2));
            }
        }
        (QuadNet::new_open(nodes, quads).unwrap(), labels)
    }

    /// The crease nodes go between the data's surfaces (0.3 out); a fold check that flags
    /// every quad with a node past x = 0.2 sends them back to the implicit's edge (x = 0),
    /// and without the check they stay on the data's.
    #[test]
    fn data_moves_that_fold_are_undone_only_when_checked() {
        let field = Planes { off: 0.0 };
        let sides = Sides {
            field: &field,
            data: Some(&Data),
        };
        let folded = |net: &QuadNet| {
            net.quads
                .iter()
                .map(|q| q.iter().any(|&i| net.nodes[i as usize].x > 0.2))
                .collect::<Vec<bool>>()
        };
        let crease_x = |net: &QuadNet| (1..4).map(|j| net.nodes[2 * 5 + j].x).collect::<Vec<f64>>();
        let (mut checked, labels) = l_net();
        let r = project_onto_sides(
            &mut checked,
            &labels,
            &[0, 1],
            sides,
            1.0,
            1.0,
            Some(&folded),
        );
        assert_eq!(
            (r.crease_nodes, r.data_undone, r.data_fitted),
            (3, 3, 0),
            "{r:?}"
        );
        for x in crease_x(&checked) {
            assert!(x.abs() < 1e-9, "{x}");
        }
        let (mut free, labels) = l_net();
        let r = project_onto_sides(&mut free, &labels, &[0, 1], sides, 1.0, 1.0, None);
        assert_eq!(
            (r.crease_nodes, r.data_undone, r.data_fitted),
            (3, 0, 3),
            "{r:?}"
        );
        for x in crease_x(&free) {
            assert!((x - 0.3).abs() < 1e-6, "{x}");
        }
    }
}
