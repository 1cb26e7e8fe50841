//! The quad net's nodes put on the creases and corners of a sharp implicit (`fit --sharp`;
//! issue 36 item 1), so that the net has a connected path of edges along every crease and a
//! node on every corner.
//!
//! The voxel net's nodes are voxel corners projected onto f = 0 and relaxed there
//! ([`super::net_smooth`]); nothing puts them on a part's edges, so a crease runs through the
//! middle of quads and the patches round it off. On the sharp implicit
//! ([`crate::implicit::sharp`], one function per side in the cells a crease crosses):
//!
//! 1. **Quad regions** ([`super::crease_labels`]). Each quad takes the region of its
//!    centroid: of the regions near it, the one whose surface passes nearest
//!    ([`LocalSides::region`], the surfaces fitted to the data, else [`SideField::region`]);
//!    lone labels take their neighbours'. Then (by default, [`CreaseNodeOptions::least_moves`])
//!    the quads beside a crease take the labels for which the nodes move least onto their
//!    creases, corners and faces and the fewest quads have three corners on one crease
//!    ([`refine_by_moves`]): the strip of quads the voxel net cuts across a crease, and the
//!    quad that cuts across a corner, join one side consistently. Then the steps left at the
//!    corners are collapsed ([`CreaseNodeOptions::collapse_staircases`],
//!    [`super::crease_collapse`]): at a corner whose node has four quads, the corner-cutting
//!    quad is a step of one crease whichever side it joins. Corners count only where their
//!    three regions' surfaces meet near the node (not a chamfer narrower than a quad between
//!    two faces, whose three planes share a direction), and the collapse is undone when it
//!    leaves fewer such corners than there were.
//! 2. **Node roles** ([`super::crease_labels::node_role`]). A node whose quads carry one
//!    region is a face node, two a crease node, three or more a corner node: the rank (1, 2,
//!    3) of dual contouring's quadric error function at the node (Ju, Losasso, Schaefer and
//!    Warren 2002), read off the labels rather than off the singular values of the crossings'
//!    normals, which beside a crease rounded by noise are not clearly rank 2.
//! 3. **Placement.** A crease node between regions A and B goes to the nearest point of the
//!    crease f_A = f_B = 0, a corner node to the point where its three regions' surfaces meet
//!    ([`meet_point`]). The sides f_A, f_B, f_C are the regions' surfaces fitted to the data
//!    around the node ([`LocalSides`], e.g. [`crate::features::data_sides`]) when the caller
//!    has them and they can be fitted there, else the sharp implicit's own
//!    ([`SideField::side`], which differ only in its sharp cells). The iteration is Gauss-Newton with the minimum-norm step x <- x - J^+ r, r = (f_A(x),
//!    f_B(x)[, f_C(x)]), J the rows grad f_A, grad f_B[, grad f_C]. Each step minimizes the QEF
//!    sum_k (n_k . (y - x) + f_k(x))^2 of the sides' tangent planes at x (with |grad f_k| = 1
//!    its terms are the squared distances to those planes) with the least move, so the
//!    iteration ends on the crease point or corner nearest to the node. A corner of more than
//!    three regions takes the three with the most quads at the node. The node keeps its place
//!    when the iteration fails (the sides meet at under 6 degrees: a smooth join, not a
//!    crease) or moves it more than [`CreaseNodeOptions::max_move`] voxels.
//! 4. **Constrained relaxation** ([`relax_constrained`]): crease nodes slide along their
//!    crease (the relaxed position snapped back onto it), corners stay, and a face node next to
//!    a crease may not cross it (a move to where another region's surface passes nearer is
//!    undone). The relaxation moves the neighbours of a node placed far (a corner node most
//!    of a voxel from its corner) so that their quads unfold.
//! 5. **No folds.** Of a quad still flipped or degenerate after the relaxation (and fine
//!    before), the placed corner that moved most goes back, and steps 4-5 start again from the
//!    first positions ([`RELAX_ROUNDS`] at most; then each placement that folds a quad before
//!    any relaxation goes back, round after round, and the net is relaxed once).

use super::crease_collapse::{collapse_staircases, CollapseScope, CornerOk, LabelledQuads};
pub use super::crease_labels::NodeRole;
use super::crease_labels::{node_roles, quad_regions, refine_by_moves, MoveCost};
use super::crease_split::{meet_point, CreaseSplitOptions, SideField};
use super::net_quality::folded_quads;
use super::net_smooth::{relax_constrained, NodeConstraint, SmoothOptions, SmoothReport};
use super::newton::{project, NewtonOptions};
use super::quad_net::QuadNet;
use crate::implicit::Implicit;
use crate::Result;
use nalgebra::Point3;
use rayon::prelude::*;

/// Most rounds of placement and relaxation (steps 4 and 5).
pub const RELAX_ROUNDS: usize = 4;
/// Most sweeps of each constrained relaxation (step 4).
pub const RELAX_SWEEPS: usize = 40;

/// Options of [`place_on_creases`].
#[derive(Debug, Clone, Copy)]
pub struct CreaseNodeOptions {
    /// Largest move of a node onto its crease or corner, in voxels (default 1).
    pub max_move: f64,
    /// The crease point iteration ([`meet_point`]).
    pub meet: CreaseSplitOptions,
    /// Collapse the quads of the staircase a crease at an angle to the grid makes
    /// ([`super::crease_collapse`]): `None` none, else those of the scope. Default: the steps
    /// at corners whose three surfaces meet near the node (on 12 machined parts after the
    /// least-move labels, crease p95 bracket.stl 1.4e-4 -> 1e-15, vblock 4.4e-3 -> 1.3e-3,
    /// lplate, wedge and hexnut lower, the rest the same; a collapse that leaves fewer corners
    /// within reach is undone); every step worsens block, tilted, wedge, slotplate and stepped
    /// 3-7x.
    pub collapse_staircases: Option<CollapseScope>,
    /// Choose the labels of the quads beside a crease for the least node moves and steps
    /// ([`super::crease_labels::refine_by_moves`]; default true: on 12 machined parts the
    /// net's crease p95 lower on 9 (bracket.stl 6.0e-3 -> 1.4e-4 of the diagonal), higher on
    /// bracket.xyz (8.6e-4 -> 1.0e-3) and lplate.xyz, every corner of an exact box with a
    /// pocket placed).
    pub least_moves: bool,
}

impl Default for CreaseNodeOptions {
    fn default() -> Self {
        CreaseNodeOptions {
            max_move: 1.0,
            meet: CreaseSplitOptions::default(),
            collapse_staircases: Some(CollapseScope::AtCorners),
            least_moves: true,
        }
    }
}

/// The regions' surfaces fitted to the data around a point (the sides [`meet_point`] puts a
/// node between; module doc, step 3).
pub trait LocalSides: Sync {
    /// The surfaces of `regions` around `x`, or `None` when one of them cannot be fitted there.
    fn near(&self, x: &Point3<f64>, regions: &[u32]) -> Option<Box<dyn SideField + Send + Sync>>;
    /// [`LocalSides::near`], but only when each region's surface fitted to the data follows its
    /// points about as well as `reference`'s side of that region does (`scale`: the net's edge
    /// length; the implementation says how close).
    fn near_checked(
        &self,
        x: &Point3<f64>,
        regions: &[u32],
        reference: &dyn SideField,
        scale: f64,
    ) -> Option<Box<dyn SideField + Send + Sync>>;
    /// The region whose surface passes nearest to `x`, or `None` when none can be fitted.
    fn region(&self, x: &Point3<f64>) -> Option<u32>;
}

/// What [`place_on_creases`] did (the report's `crease_nodes`).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct CreaseNodesReport {
    /// Quads and nodes of the net.
    pub quads: usize,
    pub nodes: usize,
    /// Quads whose centroid's region was replaced: by their neighbours', or for the least
    /// node moves (step 1).
    pub relabelled_quads: usize,
    /// Quads of the staircases collapsed (step 1b).
    pub collapsed_quads: usize,
    /// Nodes between two regions, and of them those put on the crease.
    pub crease_nodes: usize,
    pub placed_crease_nodes: usize,
    /// Nodes where three or more regions meet, and of them those put on the corner.
    pub corner_nodes: usize,
    pub placed_corner_nodes: usize,
    /// Placed nodes whose sides were fitted to the data around them ([`LocalSides`]); the
    /// others were put between the sharp implicit's sides.
    pub placed_on_data: usize,
    /// Placements undone because they folded a quad.
    pub undone_for_folds: usize,
    /// Largest move of a kept placement, in voxels.
    pub max_move: f64,
    /// Net quality before and after the constrained relaxation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smoothing: Option<SmoothReport>,
}

/// The net's regions and nodes' roles after [`place_on_creases`].
#[derive(Debug, Clone, PartialEq)]
pub struct CreaseNet {
    /// Region of each quad.
    pub quad_region: Vec<u32>,
    /// Role of each node.
    pub roles: Vec<NodeRole>,
    /// Whether each node was put on its crease or corner (face nodes: false).
    pub placed: Vec<bool>,
    pub report: CreaseNodesReport,
}

/// Labels the quads of `net` by region, puts its crease and corner nodes on the creases and
/// corners of `field`, and relaxes it under those constraints (module doc). `f` is the
/// implicit the net lies on (the sharp one), `smooth` the relaxation's options (its `h` the
/// voxel edge).
pub fn place_on_creases<I: Implicit + ?Sized>(
    net: &mut QuadNet,
    f: &I,
    field: &dyn SideField,
    data: Option<&dyn LocalSides>,
    smooth: &SmoothOptions,
    opts: &CreaseNodeOptions,
) -> Result<CreaseNet> {
    let h = smooth.h;
    let region = |x: &Point3<f64>| {
        data.and_then(|d| d.region(x))
            .unwrap_or_else(|| field.region(x))
    };
    // Where crease and corner nodes go: the labels' costs, the corners' test and step 3.
    let placement = Placement {
        data,
        field,
        h,
        opts,
    };
    let (mut quad_region, mut relabelled_quads) = quad_regions(net, &region);
    if opts.least_moves {
        relabelled_quads += refine_by_moves(net, &mut quad_region, &placement, h);
    }
    let mut collapsed_quads = 0;
    if let Some(scope) = opts.collapse_staircases {
        let corner_ok = |p: &Point3<f64>, regions: &[u32]| placement.target(p, regions).is_some();
        // A collapse that leaves fewer corners within reach of their node (a chain of merges
        // that carried a corner's label away from the corner) is not taken.
        if let Some((collapsed, labels, n)) =
            collapse(net, f, &quad_region, smooth, scope, &corner_ok)
        {
            if reachable_corners(&collapsed, &labels, &placement)
                >= reachable_corners(net, &quad_region, &placement)
            {
                (*net, quad_region, collapsed_quads) = (collapsed, labels, n);
            }
        }
    }
    let roles = node_roles(net, &quad_region);
    let mut report = CreaseNodesReport {
        relabelled_quads,
        collapsed_quads,
        crease_nodes: count(&roles, |r| matches!(r, NodeRole::Crease(_))),
        corner_nodes: count(&roles, |r| matches!(r, NodeRole::Corner(_))),
        ..Default::default()
    };

    // Step 3: placement, on the data's sides when they can be fitted, else the implicit's.
    let placements: Vec<Option<(Point3<f64>, Sides)>> = (0..net.nodes.len())
        .into_par_iter()
        .map(|i| match &roles[i] {
            NodeRole::Face(_) => None,
            r => placement.target(&net.nodes[i], r.regions()),
        })
        .collect();
    let targets: Vec<Option<Point3<f64>>> =
        placements.iter().map(|t| t.as_ref().map(|x| x.0)).collect();
    let sides: Vec<Option<Sides>> = placements.into_iter().map(|t| t.map(|x| x.1)).collect();
    // The relaxation here unfolds the quads around the placed nodes; past a few dozen sweeps
    // it only creeps (block.xyz: 196 sweeps for a min angle up by 1e-3 degree each).
    let smooth = &SmoothOptions {
        max_iterations: smooth.max_iterations.min(RELAX_SWEEPS),
        ..*smooth
    };
    let old = net.nodes.clone();
    let was_folded = folded_quads(net, f, smooth.scale, h);
    let mut placed: Vec<bool> = targets.iter().map(Option::is_some).collect();
    // Steps 4 and 5: the placements made and the net relaxed around them; of each quad still
    // folded after the relaxation the placed corner that moved most goes back, and the net is
    // placed and relaxed again from the first positions ([`RELAX_ROUNDS`] at most).
    let mut smoothing = None;
    let mut settled = false;
    for _ in 0..RELAX_ROUNDS {
        apply_placements(net, &old, &targets, &placed);
        let constraint = OnCreases::new(net, &region, field, &sides, &roles, &placed, h, opts);
        smoothing = Some(relax_constrained(net, f, smooth, &constraint)?);
        let undone = undo_folding(net, f, smooth, &was_folded, &old, &mut placed);
        if undone == 0 {
            settled = true;
            break;
        }
        report.undone_for_folds += undone;
    }
    if !settled {
        // Last resort: each placement that folds a quad before any relaxation goes back, round
        // after round, which ends with no quad folded that was fine.
        apply_placements(net, &old, &targets, &placed);
        loop {
            let undone = undo_folding(net, f, smooth, &was_folded, &old, &mut placed);
            if undone == 0 {
                break;
            }
            report.undone_for_folds += undone;
            apply_placements(net, &old, &targets, &placed);
        }
        let constraint = OnCreases::new(net, &region, field, &sides, &roles, &placed, h, opts);
        smoothing = Some(relax_constrained(net, f, smooth, &constraint)?);
    }
    for (i, r) in roles.iter().enumerate() {
        if placed[i] {
            match r {
                NodeRole::Crease(_) => report.placed_crease_nodes += 1,
                NodeRole::Corner(_) => report.placed_corner_nodes += 1,
                NodeRole::Face(_) => {}
            }
            if let Some(q) = targets[i] {
                report.max_move = report.max_move.max((q - old[i]).norm() / h);
            }
            if matches!(sides[i], Some(Sides::Data(_))) {
                report.placed_on_data += 1;
            }
        }
    }
    report.smoothing = smoothing;
    (report.quads, report.nodes) = (net.quads.len(), net.nodes.len());
    Ok(CreaseNet {
        quad_region,
        roles,
        placed,
        report,
    })
}

/// Where crease and corner nodes go (step 3), and how far (the labels' [`MoveCost`]).
struct Placement<'a> {
    data: Option<&'a dyn LocalSides>,
    field: &'a dyn SideField,
    h: f64,
    opts: &'a CreaseNodeOptions,
}

impl Placement<'_> {
    /// The point where the surfaces of `regions` meet nearest to `p` within
    /// [`CreaseNodeOptions::max_move`] voxels: between the data's sides when they can be
    /// fitted there, else the implicit's.
    fn target(&self, p: &Point3<f64>, regions: &[u32]) -> Option<(Point3<f64>, Sides)> {
        let near = |q: &Point3<f64>| (q - p).norm() <= self.opts.max_move * self.h;
        if let Some(sides) = self.data.and_then(|d| d.near(p, regions)) {
            if let Some(q) = meet_point(&*sides, regions, *p, self.h, &self.opts.meet).filter(near)
            {
                return Some((q, Sides::Data(sides)));
            }
        }
        meet_point(self.field, regions, *p, self.h, &self.opts.meet)
            .filter(near)
            .map(|q| (q, Sides::Implicit))
    }
}

impl MoveCost for Placement<'_> {
    fn distance(&self, p: &Point3<f64>, role: &NodeRole) -> Option<f64> {
        match role {
            NodeRole::Face(r) => {
                let from_data = self
                    .data
                    .and_then(|d| d.near(p, &[*r]))
                    .map(|s| s.side(*r, p));
                let (v, g) = from_data
                    .filter(|(v, g)| v.is_finite() && g.norm() > 0.0)
                    .unwrap_or_else(|| self.field.side(*r, p));
                let d = v.abs() / g.norm();
                // A region with no surface here: the node cannot lie on it.
                Some(if d.is_finite() { d } else { self.h })
            }
            r => self.target(p, r.regions()).map(|(q, _)| (q - p).norm()),
        }
    }
}

/// How many corner nodes of `net` have their corner within reach.
fn reachable_corners(net: &QuadNet, quad_region: &[u32], placement: &Placement) -> usize {
    node_roles(net, quad_region)
        .iter()
        .enumerate()
        .filter(|(i, r)| {
            matches!(r, NodeRole::Corner(_))
                && placement.target(&net.nodes[*i], r.regions()).is_some()
        })
        .count()
}

/// Step 1b: the staircase quads collapsed ([`collapse_staircases`]), the merged nodes
/// projected onto f. Returns the collapsed net, the regions of its quads and how many quads
/// went, or `None` when none did or the collapsed net does not build.
fn collapse<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    quad_region: &[u32],
    smooth: &SmoothOptions,
    scope: CollapseScope,
    corner_ok: &CornerOk<'_>,
) -> Option<(QuadNet, Vec<u32>, usize)> {
    let pinned = net.boundary_nodes();
    let mut lq = LabelledQuads {
        nodes: net.nodes.clone(),
        quads: net.quads.clone(),
        quad_region: quad_region.to_vec(),
    };
    let (n, merged) = collapse_staircases(&mut lq, &pinned, scope, corner_ok);
    if n == 0 {
        return None;
    }
    let newton = NewtonOptions::new(smooth.scale, 0.5 * smooth.h);
    for &i in &merged {
        if let Ok((p, _)) = project(f, lq.nodes[i as usize], &newton) {
            lq.nodes[i as usize] = p;
        }
    }
    let rebuilt = if net.is_open() {
        QuadNet::new_open(lq.nodes, lq.quads)
    } else {
        QuadNet::new(lq.nodes, lq.quads)
    };
    rebuilt.ok().map(|new| (new, lq.quad_region, n))
}

/// The net's nodes at their first positions `old`, the placed ones at their targets.
fn apply_placements(
    net: &mut QuadNet,
    old: &[Point3<f64>],
    targets: &[Option<Point3<f64>>],
    placed: &[bool],
) {
    net.nodes.clone_from_slice(old);
    for (i, t) in targets.iter().enumerate() {
        if let (true, Some(q)) = (placed[i], t) {
            net.nodes[i] = *q;
        }
    }
}

/// Of each quad folded now that was fine before, the placed corner farthest from its first
/// position stops being placed (at a step of the staircase a crease makes across the grid,
/// the step's corner: the quad keeps the others). Returns how many.
fn undo_folding<I: Implicit + ?Sized>(
    net: &QuadNet,
    f: &I,
    smooth: &SmoothOptions,
    was_folded: &[bool],
    old: &[Point3<f64>],
    placed: &mut [bool],
) -> usize {
    let folded = folded_quads(net, f, smooth.scale, smooth.h);
    let mut undone = 0;
    for (q, quad) in net.quads.iter().enumerate() {
        if !folded[q] || was_folded[q] {
            continue;
        }
        let worst = quad
            .iter()
            .map(|&i| i as usize)
            .filter(|&i| placed[i])
            .max_by(|&a, &b| {
                let (da, db) = (
                    (net.nodes[a] - old[a]).norm(),
                    (net.nodes[b] - old[b]).norm(),
                );
                da.total_cmp(&db).then(b.cmp(&a))
            });
        if let Some(i) = worst {
            placed[i] = false;
            undone += 1;
        }
    }
    undone
}

fn count(roles: &[NodeRole], pred: impl Fn(&NodeRole) -> bool) -> usize {
    roles.iter().filter(|r| pred(r)).count()
}

/// The sides a node was put between.
enum Sides {
    /// Fitted to the data around it.
    Data(Box<dyn SideField + Send + Sync>),
    /// The sharp implicit's.
    Implicit,
}

/// Step 5's constraint.
struct OnCreases<'a> {
    region: &'a (dyn Fn(&Point3<f64>) -> u32 + Sync),
    field: &'a dyn SideField,
    sides: &'a [Option<Sides>],
    roles: &'a [NodeRole],
    placed: &'a [bool],
    /// Face nodes with a crease or corner node among their quads' corners.
    beside_crease: Vec<bool>,
    h: f64,
    opts: CreaseNodeOptions,
}

impl<'a> OnCreases<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        net: &QuadNet,
        region: &'a (dyn Fn(&Point3<f64>) -> u32 + Sync),
        field: &'a dyn SideField,
        sides: &'a [Option<Sides>],
        roles: &'a [NodeRole],
        placed: &'a [bool],
        h: f64,
        opts: &CreaseNodeOptions,
    ) -> Self {
        let beside_crease = (0..net.nodes.len())
            .map(|i| {
                matches!(roles[i], NodeRole::Face(_))
                    && net.node_quads(i).iter().any(|&q| {
                        net.quads[q as usize]
                            .iter()
                            .any(|&k| !matches!(roles[k as usize], NodeRole::Face(_)))
                    })
            })
            .collect();
        OnCreases {
            region,
            field,
            sides,
            roles,
            placed,
            beside_crease,
            h,
            opts: *opts,
        }
    }
}

impl NodeConstraint for OnCreases<'_> {
    fn pinned(&self, i: usize) -> bool {
        matches!(self.roles[i], NodeRole::Corner(_)) && self.placed[i]
    }

    fn constrain(&self, i: usize, old: &Point3<f64>, new: &Point3<f64>) -> Point3<f64> {
        match self.roles[i] {
            NodeRole::Crease(s) if self.placed[i] => {
                let field: &dyn SideField = match &self.sides[i] {
                    Some(Sides::Data(d)) => &**d,
                    _ => self.field,
                };
                meet_point(field, &s, *new, self.h, &self.opts.meet)
                    .filter(|q| (q - new).norm() <= self.opts.max_move * self.h)
                    .unwrap_or(*old)
            }
            NodeRole::Face(r) if self.beside_crease[i] => {
                if (self.region)(new) == r {
                    *new
                } else {
                    *old
                }
            }
            _ => *new,
        }
    }
}

#[cfg(test)]
mod tests;
