//! How far to extend each face's surface in the STEP file ([`crate::nurbs::extend`]), so that
//! OpenCASCADE's default point projection works on it.
//!
//! `GeomAPI_ProjectPointOnSurf` samples the surface domain with a uniform 44 x 44 grid (for
//! B-splines with at most 14 knot spans per direction; more spans give 3 grid lines per span)
//! and merges neighbouring grid points whose squared distance is under 2e-7 mm^2
//! ([`crate::nurbs::extend`] explains what that breaks). A patch direction whose extent, at
//! its slowest parameter speed, is L millimetres has grid cells of L / 43; extending the domain
//! of width W by r W on both sides makes them L (1 + 2 r) / 43. [`apron_widths`] picks the
//! smallest r that gives cells of at least [`GRID_SPACING_MM`], at most [`MAX_RELATIVE`] (a
//! patch of under 0.004 mm gets the largest apron and remains the most fragile), and none
//! when the patch is large enough already: models of ordinary size in millimetres get plain,
//! untrimmed faces.

use super::LengthUnit;
use crate::nurbs::BSplineSurface;

/// Smallest grid cell wanted, in millimetres (the square is 2.5 times OpenCASCADE's merge
/// threshold of 2e-7 mm^2).
pub const GRID_SPACING_MM: f64 = 7e-4;

/// Grid intervals of the projection's uniform sampling (44 grid lines).
const GRID_INTERVALS: f64 = 43.0;

/// Largest apron, as a fraction of the domain width on each side.
pub const MAX_RELATIVE: f64 = 3.0;

/// Aprons narrower than this fraction of the domain are not written.
const MIN_RELATIVE: f64 = 0.05;

/// Extent of the surface along u and along v at its slowest parameter speed: the smallest
/// |S_u| (|S_v|) over a 9 x 9 parameter grid times the domain width.
fn slow_extents(s: &BSplineSurface) -> (f64, f64) {
    let (u0, u1) = s.domain_u();
    let (v0, v1) = s.domain_v();
    let mut lu = f64::INFINITY;
    let mut lv = f64::INFINITY;
    for i in 0..=8 {
        for j in 0..=8 {
            let u = u0 + (u1 - u0) * i as f64 / 8.0;
            let v = v0 + (v1 - v0) * j as f64 / 8.0;
            let d = s.derivatives(u, v);
            lu = lu.min(d.du.norm() * (u1 - u0));
            lv = lv.min(d.dv.norm() * (v1 - v0));
        }
    }
    (lu, lv)
}

/// Millimetres per unit of the file.
pub fn millimetres_per_unit(unit: LengthUnit) -> f64 {
    match unit {
        LengthUnit::Millimetre => 1.0,
        LengthUnit::Centimetre => 10.0,
        LengthUnit::Metre => 1000.0,
        LengthUnit::Micrometre => 1e-3,
    }
}

/// Whether patches of edge length `size` (in `unit`) are small enough to get aprons: under
/// twice the extent whose uniform grid cells are [`GRID_SPACING_MM`] (about 0.06 mm), so
/// that the slower directions of such patches are covered too.
pub fn patch_needs_apron(size: f64, unit: LengthUnit) -> bool {
    size * millimetres_per_unit(unit) < 2.0 * GRID_INTERVALS * GRID_SPACING_MM
}

/// The apron widths (e_u, e_v), in parameter units, for a face on `s` in a file of `unit`
/// (module documentation); (0, 0) when the face needs none.
pub fn apron_widths(s: &BSplineSurface, unit: LengthUnit) -> (f64, f64) {
    let mm = millimetres_per_unit(unit);
    let (lu, lv) = slow_extents(s);
    let relative = |l: f64| {
        let r = if l > 0.0 {
            ((GRID_INTERVALS * GRID_SPACING_MM / (l * mm)) - 1.0) / 2.0
        } else {
            MAX_RELATIVE
        };
        if r < MIN_RELATIVE {
            0.0
        } else {
            r.min(MAX_RELATIVE)
        }
    };
    let (u0, u1) = s.domain_u();
    let (v0, v1) = s.domain_v();
    (relative(lu) * (u1 - u0), relative(lv) * (v1 - v0))
}

/// What the STEP writer did with a network's surfaces (the fit report's `step` block).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ApronSummary {
    /// Faces written on an extended surface (trimmed by their edges), of `faces`.
    pub extended_faces: usize,
    pub faces: usize,
    /// Widest apron written, as a fraction of the face's parameter width (0 for none).
    pub largest_apron: f64,
}

/// Counts the faces of `net` the STEP writer extends with `opts`.
pub fn summary(net: &crate::nurbs::PatchNetwork, opts: &super::ExportOptions) -> ApronSummary {
    let mut out = ApronSummary {
        extended_faces: 0,
        faces: net.faces.len(),
        largest_apron: 0.0,
    };
    for f in &net.faces {
        let (eu, ev) = opts.apron_widths(&f.surface);
        if eu > 0.0 || ev > 0.0 {
            out.extended_faces += 1;
            let (u0, u1) = f.surface.domain_u();
            let (v0, v1) = f.surface.domain_v();
            out.largest_apron = out.largest_apron.max(eu / (u1 - u0)).max(ev / (v1 - v0));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn square(size: f64) -> BSplineSurface {
        let k = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let ctrl = (0..4)
            .map(|i| {
                (0..4)
                    .map(|j| Point3::new(size * i as f64 / 3.0, size * j as f64 / 3.0, 0.0))
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, k.clone(), k, ctrl).unwrap()
    }

    #[test]
    fn only_small_patches_get_aprons() {
        // 0.0076 mm: the bunny's patches read as millimetres.
        let (eu, ev) = apron_widths(&square(0.0076), LengthUnit::Millimetre);
        assert!((eu - ev).abs() < 1e-12);
        assert!(
            (eu - (43.0 * 7e-4 / 0.0076 - 1.0) / 2.0).abs() < 1e-9,
            "{eu}"
        );
        // The same patch in metres is 7.6 mm: no apron.
        assert_eq!(apron_widths(&square(0.0076), LengthUnit::Metre), (0.0, 0.0));
        assert_eq!(
            apron_widths(&square(5.0), LengthUnit::Millimetre),
            (0.0, 0.0)
        );
        // Tiny patches get the largest apron.
        let (eu, _) = apron_widths(&square(1e-6), LengthUnit::Millimetre);
        assert_eq!(eu, MAX_RELATIVE);
    }
}
