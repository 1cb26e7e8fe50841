//! Folds: two regions of a cloud that meet at a crease along only part of their common
//! boundary are one smooth surface with a fold in it, not two faces.
//!
//! Region growing stops wherever a neighbourhood is not smooth at the noise, and on an organic
//! scan with little noise that happens at every rim sharper than a few point spacings (the thin
//! rims of the bunny's ears, a groove in its base, the folds around spot's eyes): the walk goes
//! round such a spot and leaves a small region behind it. Along part of its boundary the two
//! sides' planes do meet at an angle (a crease sample, [`super::crease_cloud`] step 1); along
//! the rest the two regions join where the surface turns gently, or so roundly that the band
//! between them belongs to neither (no sample there).
//!
//! Two faces of a machined part meet at their crease all along their common boundary, except
//! near its ends, where a third face comes in. So, per region pair, the boundary points are
//! gathered into cells of [`CreaseOptions::cell`] spacings, and a cell is *creased* when one of
//! its boundary points gave a crease sample:
//!
//!   uncreased cells > (1 - [`MIN_CREASED`]) cells + [`END_CELLS`]  =>  the pair is one region.
//!
//! Measured (share of creased cells of the least creased pair; `scansurf features`, session of
//! 2026-12-04): make_parts' and the extra parts (block, bracket, flange, wedge, tilted,
//! stepped, cornerblock, hexnut, slotplate; 200,000 points, 0.01 mm noise) 0.83-0.99, fandisk
//! sampled densely 0.86; organic clouds 0.57-0.75 (the bunny's vertices 0.57 and 0.65, spot
//! 0.64-0.70, the cow 0.59-0.75, the teapot 0.25-0.66).
//!
//! Creases that fade out inside one smooth surface (fandisk's, a draft angle running to zero)
//! are not representable by regions at all; the pair they separate is merged like a fold, and
//! what is lost is a crease whose ends the regions could not have bounded either.

use super::crease_cloud::{BoundaryPoint, CreaseOptions};
use super::details::remap_pairs;
use super::segment_cloud::{CloudLabels, NONE};
use super::union_find::DisjointSets;
use nalgebra::Point3;
use std::collections::{BTreeMap, BTreeSet};

/// Fewest creased cells, as a share of a pair's boundary cells, for two faces.
pub const MIN_CREASED: f64 = 0.8;

/// Uncreased cells allowed on top of the share: the ends of a crease, where a third face comes
/// near and the two sides' planes are not both fitted.
pub const END_CELLS: usize = 2;

/// Grid cells, by integer coordinates.
type Cells = BTreeSet<[i64; 3]>;

/// Boundary cells of one region pair.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PairBoundary {
    /// Cells holding a boundary point of the pair.
    pub cells: usize,
    /// Of those, cells where a crease sample was found.
    pub creased: usize,
}

impl PairBoundary {
    /// True when the pair meets at a crease along too little of its boundary (module doc).
    pub fn is_fold(&self) -> bool {
        // uncreased > (1 - MIN) cells + END, i.e. creased + END < MIN cells (a hair of
        // slack so that the exact limit does not hang on rounding).
        ((self.creased + END_CELLS) as f64) < MIN_CREASED * self.cells as f64 - 1e-9
    }
}

/// Boundary cells per region pair, from the boundary points of
/// [`super::crease_cloud::boundary_points`] (`found[i]` for `points[i]`).
pub fn pair_boundaries(
    points: &[Point3<f64>],
    found: &[BoundaryPoint],
    spacing: f64,
    opts: &CreaseOptions,
) -> BTreeMap<(u32, u32), PairBoundary> {
    let cell = opts.cell * spacing;
    // Per pair: its boundary cells, and those creased.
    let mut cells: BTreeMap<(u32, u32), [Cells; 2]> = BTreeMap::new();
    for (p, f) in points.iter().zip(found) {
        let Some(pair) = f.pair else { continue };
        let k = p.coords.map(|x| (x / cell).floor() as i64);
        let e = cells.entry(pair).or_default();
        e[0].insert([k.x, k.y, k.z]);
        if f.creased() {
            e[1].insert([k.x, k.y, k.z]);
        }
    }
    cells
        .into_iter()
        .map(|(pair, [all, creased])| {
            (
                pair,
                PairBoundary {
                    cells: all.len(),
                    creased: creased.len(),
                },
            )
        })
        .collect()
}

/// Merges the region pairs of `labels` that are folds (module doc), relabelling the points and
/// the pairs; returns how many pairs were merged.
pub fn merge_folds(
    points: &[Point3<f64>],
    labels: &mut CloudLabels,
    found: &[BoundaryPoint],
    spacing: f64,
    opts: &CreaseOptions,
) -> usize {
    let mut sets = DisjointSets::new(labels.regions);
    let mut merged = 0;
    for ((a, b), boundary) in pair_boundaries(points, found, spacing, opts) {
        if boundary.is_fold() && sets.union(a, b) {
            merged += 1;
        }
    }
    if merged == 0 {
        return 0;
    }
    let (map, count) = sets.labels();
    for l in labels.label.iter_mut() {
        if *l != NONE {
            *l = map[*l as usize];
        }
    }
    labels.regions = count;
    labels.pairs = remap_pairs(&labels.pairs, &map);
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_creased_all_along_but_its_ends_is_two_faces() {
        // 100 cells, 80 creased + 2 ends: the limit.
        assert!(!PairBoundary {
            cells: 100,
            creased: 78
        }
        .is_fold());
        assert!(PairBoundary {
            cells: 100,
            creased: 77
        }
        .is_fold());
        // A short crease between corners: both its end cells uncreased.
        assert!(!PairBoundary {
            cells: 6,
            creased: 4
        }
        .is_fold());
        // The bunny's ear tip: creased along 57 % of its rim.
        assert!(PairBoundary {
            cells: 98,
            creased: 56
        }
        .is_fold());
    }
}
