//! Segmentation of a triangle mesh into smooth regions: the faces joined across every edge
//! whose dihedral angle (between the unit normals of its two triangles) is under `crease_deg`.
//! A scan mesh of a machined part keeps its sharp edges as mesh edges, so there the creases
//! are exact; the mesh's own noise gives scattered sharp edges, which separate nothing unless
//! they close a loop, and what they do close is small and absorbed by its neighbour.
//!
//! Regions that meet smoothly after all are merged ([`super::merge`]): a coarse mesh of a curved
//! limb has rings of edges bent by more than `crease_deg`, but the local quadratics of the two
//! sides continue each other across them.
//!
//! Regions smaller than `min_faces` triangles, or narrower than `min_width` mean edge lengths
//! (area over half the perimeter), are merged into the neighbour with which they share the
//! longest boundary, smallest first: a ring of faces cut out by noise, or the one-triangle-wide
//! strips a fillet of radius about the edge length falls into. With a prior labelling of the
//! faces ([`segment_mesh_hinted`]: the regions the input data were segmented into, seen from a
//! mesh made later, e.g. the sharp implicit's), a narrow region that is not tiny is kept when
//! it and the neighbour it would be merged into (the one sharing its longest boundary) each
//! have a majority prior label (carried by at least half of their faces, a tie going to the
//! smaller label) and these differ: a true face narrower than 1.5 edges of a coarse mesh
//! (make_parts' stepped shaft: the 3 mm wall where a flat cuts a cylinder, on a mesh of 1 mm
//! edges), not a strip of noise. A kept region is judged again after every merge.

use super::merge::{merge_smooth, Boundaries, Labelled};
use super::union_find::DisjointSets;
use super::RegionPair;
use crate::mesh::adjacency::Adjacency;
use crate::mesh::normals::vertex_normals;
use crate::mesh::Mesh;
use crate::spatial::KdTree;
use crate::Result;
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Options of [`segment_mesh`], with documented defaults.
#[derive(Debug, Clone, Copy)]
pub struct MeshOptions {
    /// Edges whose dihedral angle is at least this separate regions, degrees (default 20).
    pub crease_deg: f64,
    /// Regions with fewer triangles are absorbed (default 12).
    pub min_faces: usize,
    /// Regions narrower than this many mean edge lengths are absorbed (default 1.5).
    pub min_width: f64,
    /// Vertices around a boundary sample for the merge test (default 32).
    pub neighbours: usize,
    /// Label the fit's points by the triangle they lie on, with their region's own normals
    /// ([`super::face_labels`]), instead of by the nearest labelled vertex or face centre with
    /// the mesh's vertex normals (default false: on eleven machined meshes it took the
    /// largest crease distance from 1.54e-3 to 1.05e-3 of the diagonal, but doubled it on the
    /// flange, whose rim got two notches; see docs/BENCHMARKS.md).
    pub face_labels: bool,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            crease_deg: 20.0,
            min_faces: 12,
            min_width: 1.5,
            neighbours: 32,
            face_labels: false,
        }
    }
}

/// A labelling of the faces into smooth regions.
#[derive(Debug, Clone)]
pub struct MeshLabels {
    /// Region per face (0..regions).
    pub face_label: Vec<u32>,
    pub regions: usize,
    /// Regions meeting at a crease, with the length-weighted mean dihedral of their common
    /// edges (`boundary_samples` = the number of those edges).
    pub pairs: Vec<RegionPair>,
}

/// Segments the faces of `mesh` into smooth regions.
pub fn segment_mesh(mesh: &Mesh, opt: &MeshOptions) -> Result<MeshLabels> {
    segment_mesh_hinted(mesh, opt, None)
}

/// Regions to absorb above which one round merges many of them ([`segment_mesh_hinted`]).
const BATCH_FROM: usize = 256;

/// [`segment_mesh`], with `hint` a prior label per face (module doc): a narrow region whose
/// faces mostly carry another prior label than its neighbour's is not absorbed. Fails when
/// `hint` does not hold one label per face.
pub fn segment_mesh_hinted(
    mesh: &Mesh,
    opt: &MeshOptions,
    hint: Option<&[u32]>,
) -> Result<MeshLabels> {
    if let Some(h) = hint.filter(|h| h.len() != mesh.faces.len()) {
        return Err(crate::Error::InvalidOption(format!(
            "segment_mesh: {} prior labels for {} faces",
            h.len(),
            mesh.faces.len()
        )));
    }
    let adj = Adjacency::build(mesh)?;
    let nf = mesh.faces.len();
    let normals: Vec<Option<Vector3<f64>>> = (0..nf)
        .map(|f| mesh.face_cross(f).try_normalize(1e-300))
        .collect();
    let cos_crease = opt.crease_deg.to_radians().cos();
    // Per manifold edge: its two faces, length and dihedral cosine.
    let mut sets = DisjointSets::new(nf);
    let mut edges: Vec<(u32, u32, f64, f64)> = Vec::new();
    let mut edge_ends: Vec<[u32; 2]> = Vec::new();
    for (e, &[a, b]) in adj.edges.iter().enumerate() {
        let faces = adj.faces_of_edge(e);
        let &[f, g] = faces else { continue };
        let (Some(nf_), Some(ng)) = (normals[f as usize], normals[g as usize]) else {
            // A degenerate triangle takes its neighbours' region.
            sets.union(f, g);
            continue;
        };
        let c = nf_.dot(&ng).clamp(-1.0, 1.0);
        let len = (mesh.positions[a as usize] - mesh.positions[b as usize]).norm();
        edges.push((f, g, len, c));
        edge_ends.push([a, b]);
        if c > cos_crease {
            sets.union(f, g);
        }
    }
    let (mut label, mut count) = sets.labels();
    let mean_edge = mesh.mean_edge_length();

    // Absorb small and thin regions into their longest-bordering neighbour, smallest first.
    loop {
        let mut area = vec![0.0; count];
        let mut faces = vec![0usize; count];
        for f in 0..nf {
            area[label[f] as usize] += mesh.face_area(f);
            faces[label[f] as usize] += 1;
        }
        let mut perimeter = vec![0.0; count];
        let mut border: BTreeMap<(u32, u32), f64> = BTreeMap::new();
        for &(f, g, len, _) in &edges {
            let (a, b) = (label[f as usize], label[g as usize]);
            if a != b {
                perimeter[a as usize] += len;
                perimeter[b as usize] += len;
                *border.entry((a.min(b), a.max(b))).or_default() += len;
            }
        }
        let tiny = |r: usize| faces[r] < opt.min_faces;
        let narrow = |r: usize| {
            perimeter[r] > 0.0 && area[r] / (0.5 * perimeter[r]) < opt.min_width * mean_edge
        };
        // The neighbour sharing the longest boundary (ties: the first pair in key order).
        let mut best: Vec<Option<(f64, (u32, u32))>> = vec![None; count];
        for (&k, &len) in &border {
            for r in [k.0, k.1] {
                let b = &mut best[r as usize];
                if b.is_none_or(|(l, _)| len > l) {
                    *b = Some((len, k));
                }
            }
        }
        let into = |r: u32| best[r as usize].map(|(_, k)| if k.0 == r { k.1 } else { k.0 });
        let prior = hint.map(|h| prior_majorities(h, &label, count));
        let distinct = |r: usize| match (&prior, into(r as u32)) {
            (Some(m), Some(n)) => matches!((m[r], m[n as usize]), (Some(a), Some(b)) if a != b),
            _ => false,
        };
        let mut victims: Vec<usize> = (0..count)
            .filter(|&r| perimeter[r] > 0.0 && (tiny(r) || (narrow(r) && !distinct(r))))
            .collect();
        victims.sort_by(|&a, &b| area[a].total_cmp(&area[b]).then(a.cmp(&b)));
        match victims.first() {
            Some(&r) if into(r as u32).is_some() => {}
            _ => break,
        }
        // The smallest victim; with thousands of specks (a noisy mesh's), every victim whose
        // neighbour is untouched in this round, smallest first.
        let take = if victims.len() > BATCH_FROM {
            victims.len()
        } else {
            1
        };
        let mut sets = DisjointSets::new(count);
        let mut touched = vec![false; count];
        for &r in &victims[..take] {
            if let Some(n) = into(r as u32).filter(|&n| !touched[r] && !touched[n as usize]) {
                sets.union(r as u32, n);
                touched[r] = true;
                touched[n as usize] = true;
            }
        }
        let (map, c) = sets.labels();
        for l in label.iter_mut() {
            *l = map[*l as usize];
        }
        count = c;
    }

    // Regions cut apart on a smooth surface (a coarse mesh's rings of bent edges) merged back
    // by comparing local quadratics of each side's vertices (region-only vertex normals).
    if count > 1 {
        let mut points = Vec::new();
        let mut vnormals = Vec::new();
        let mut vlabel = Vec::new();
        for r in 0..count as u32 {
            let sub = Mesh {
                positions: mesh.positions.clone(),
                normals: None,
                faces: (0..nf)
                    .filter(|&f| label[f] == r)
                    .map(|f| mesh.faces[f])
                    .collect(),
            };
            let vn = vertex_normals(&sub);
            for (v, used) in sub.referenced().into_iter().enumerate() {
                if used && vn[v].norm_squared() > 0.0 {
                    points.push(mesh.positions[v]);
                    vnormals.push(vn[v]);
                    vlabel.push(r);
                }
            }
        }
        let kd = KdTree::build(&points)?;
        let mut boundaries: Boundaries = BTreeMap::new();
        for (e, &(f, g, _, _)) in edges.iter().enumerate() {
            let (a, b) = (label[f as usize], label[g as usize]);
            if a != b {
                let [p, q] = edge_ends[e];
                let x = nalgebra::center(&mesh.positions[p as usize], &mesh.positions[q as usize]);
                let entry = boundaries.entry((a.min(b), a.max(b))).or_default();
                entry.0.push(x);
                entry.1 += 1;
            }
        }
        let lab = Labelled {
            points: &points,
            normals: &vnormals,
            label: &vlabel,
            kd: &kd,
        };
        let merged = merge_smooth(&lab, &boundaries, count, opt.neighbours, 48, opt.crease_deg);
        for l in label.iter_mut() {
            *l = merged.map[*l as usize];
        }
        count = merged.regions;
    }

    // Pairs meeting at creases: length-weighted mean dihedral of their common edges.
    let mut acc: BTreeMap<(u32, u32), (f64, f64, usize)> = BTreeMap::new();
    for &(f, g, len, c) in &edges {
        let (a, b) = (label[f as usize], label[g as usize]);
        if a != b {
            let e = acc.entry((a.min(b), a.max(b))).or_default();
            e.0 += len * c.acos().to_degrees();
            e.1 += len;
            e.2 += 1;
        }
    }
    let pairs = acc
        .into_iter()
        .map(|((a, b), (sum, len, n))| RegionPair {
            a,
            b,
            dihedral_deg: sum / len.max(f64::MIN_POSITIVE),
            boundary_samples: n,
        })
        .collect();
    Ok(MeshLabels {
        face_label: label,
        regions: count,
        pairs,
    })
}

/// Per region, the prior label (`hint`) that at least half of its faces carry, if any.
fn prior_majorities(hint: &[u32], label: &[u32], regions: usize) -> Vec<Option<u32>> {
    let mut counts: Vec<BTreeMap<u32, usize>> = vec![BTreeMap::new(); regions];
    for (&h, &l) in hint.iter().zip(label) {
        *counts[l as usize].entry(h).or_default() += 1;
    }
    counts
        .iter()
        .map(|c| {
            let total: usize = c.values().sum();
            c.iter()
                .max_by(|x, y| x.1.cmp(y.1).then(y.0.cmp(x.0)))
                .filter(|&(_, &n)| 2 * n >= total)
                .map(|(&h, _)| h)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    /// A unit cube split into 12 triangles per face side (2 x 2 grid per face).
    fn cube() -> Mesh {
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        let mut index = std::collections::HashMap::new();
        let mut vid = |p: [i32; 3], positions: &mut Vec<Point3<f64>>| -> u32 {
            *index.entry(p).or_insert_with(|| {
                positions.push(Point3::new(p[0] as f64, p[1] as f64, p[2] as f64) / 4.0);
                positions.len() as u32 - 1
            })
        };
        // Each face: axis a fixed at 0 or 4, grid over the other two (4 x 4 cells).
        for a in 0..3 {
            for side in [0, 4] {
                let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                for i in 0..4 {
                    for j in 0..4 {
                        let corner = |di: i32, dj: i32| {
                            let mut p = [0; 3];
                            p[a] = side;
                            p[b] = i + di;
                            p[c] = j + dj;
                            p
                        };
                        let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                            .map(|p| vid(p, &mut positions));
                        if side == 4 {
                            faces.push([q[0], q[1], q[2]]);
                            faces.push([q[0], q[2], q[3]]);
                        } else {
                            faces.push([q[0], q[2], q[1]]);
                            faces.push([q[0], q[3], q[2]]);
                        }
                    }
                }
            }
        }
        Mesh {
            positions,
            normals: None,
            faces,
        }
    }

    /// A step: the floor z = 0 for x < 0, a wall x = 0 one edge high, the top z = 1 for x > 0,
    /// all 10 long in y, in unit squares cut into two triangles each.
    fn step() -> Mesh {
        let profile: Vec<(f64, f64)> = (-5..=0)
            .map(|x| (x as f64, 0.0))
            .chain((0..=5).map(|x| (x as f64, 1.0)))
            .collect();
        let n = profile.len() as u32;
        let mut positions = Vec::new();
        for y in 0..=10 {
            for &(x, z) in &profile {
                positions.push(Point3::new(x, y as f64, z));
            }
        }
        let mut faces = Vec::new();
        for y in 0..10 {
            for i in 0..n - 1 {
                let (a, b) = (y * n + i, y * n + i + 1);
                let (c, d) = (a + n, b + n);
                faces.push([a, b, d]);
                faces.push([a, d, c]);
            }
        }
        Mesh {
            positions,
            normals: None,
            faces,
        }
    }

    #[test]
    fn a_narrow_face_is_absorbed_unless_the_prior_labels_tell_it_apart() {
        let m = step();
        // Without a prior labelling the one-edge-high wall (20 triangles) is too narrow.
        assert_eq!(
            segment_mesh(&m, &MeshOptions::default()).unwrap().regions,
            2
        );
        // The input data's regions: floor, wall, top.
        let hint: Vec<u32> = (0..m.faces.len())
            .map(|f| {
                let c = m.face_centroid(f);
                if c.x.abs() < 1e-9 {
                    1
                } else if c.x < 0.0 {
                    0
                } else {
                    2
                }
            })
            .collect();
        let l = segment_mesh_hinted(&m, &MeshOptions::default(), Some(&hint)).unwrap();
        assert_eq!(l.regions, 3);
        assert_eq!(l.pairs.len(), 2);
        // A prior labelling of another mesh is refused.
        assert!(segment_mesh_hinted(&m, &MeshOptions::default(), Some(&hint[1..])).is_err());
        // A prior labelling that does not tell the wall apart changes nothing.
        let same = vec![0; m.faces.len()];
        let l = segment_mesh_hinted(&m, &MeshOptions::default(), Some(&same)).unwrap();
        assert_eq!(l.regions, 2);
    }

    /// A plane of 60 x 60 unit cells with 400 spikes (a vertex every third row and column
    /// lifted by 2): 400 specks and more, absorbed many per round, leave the plane alone.
    #[test]
    fn hundreds_of_specks_are_absorbed() {
        let n = 61;
        let id = |i: usize, j: usize| (i * n + j) as u32;
        let positions = (0..n)
            .flat_map(|i| {
                (0..n).map(move |j| {
                    let spike = i % 3 == 1 && j % 3 == 1;
                    Point3::new(i as f64, j as f64, if spike { 2.0 } else { 0.0 })
                })
            })
            .collect();
        let mut faces = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let m = Mesh {
            positions,
            normals: None,
            faces,
        };
        let l = segment_mesh(&m, &MeshOptions::default()).unwrap();
        assert_eq!(l.regions, 1, "{:?}", l.pairs.len());
    }

    #[test]
    fn cube_has_six_faces_and_twelve_creases() {
        let m = cube();
        let l = segment_mesh(&m, &MeshOptions::default()).unwrap();
        assert_eq!(l.regions, 6);
        assert_eq!(l.pairs.len(), 12);
        for p in &l.pairs {
            assert!((p.dihedral_deg - 90.0).abs() < 1e-9, "{p:?}");
        }
    }
}
