//! Contour clean-up and analysis (seed 001 section 3): resampling of each stroke to an even
//! spacing, light Laplacian filtering, intersections between and within contours, nesting (a
//! contour inside another without crossing it is a hole), and the panels ("parts") with their
//! pairwise depth order.
//!
//! Simplification of the paper's section 3.2-3.3 (stated in the module report): a contour that
//! crosses another is its own panel, and where two panels overlap the depth order comes from
//! the drawing (document order or the explicit `over` pairs). A contour that crosses itself
//! is split into the layers of the folded sheet it outlines ([`super::paneling`]), each layer
//! a panel, the higher layer in front by default.

use crate::error::{Error, Result};
use nalgebra::Point2;

/// Signed area (positive for counter-clockwise).
pub fn signed_area(c: &[Point2<f64>]) -> f64 {
    let n = c.len();
    (0..n)
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        / 2.0
}

/// Perimeter of a closed polyline.
pub fn perimeter(c: &[Point2<f64>]) -> f64 {
    let n = c.len();
    (0..n).map(|i| (c[(i + 1) % n] - c[i]).norm()).sum()
}

/// Even-odd point-in-polygon test.
pub fn inside(c: &[Point2<f64>], p: &Point2<f64>) -> bool {
    let n = c.len();
    let mut odd = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (c[i], c[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            odd = !odd;
        }
        j = i;
    }
    odd
}

/// Resamples a closed polyline to `n` points evenly spaced along its length.
pub fn resample(c: &[Point2<f64>], n: usize) -> Vec<Point2<f64>> {
    let m = c.len();
    let total = perimeter(c);
    let step = total / n as f64;
    let mut out = Vec::with_capacity(n);
    let mut seg = 0;
    let mut acc = 0.0; // arc length at the start of segment `seg`
    for k in 0..n {
        let s = k as f64 * step;
        loop {
            let len = (c[(seg + 1) % m] - c[seg]).norm();
            if acc + len >= s || seg + 1 >= m {
                let t = if len > 0.0 {
                    ((s - acc) / len).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                out.push(c[seg] + (c[(seg + 1) % m] - c[seg]) * t);
                break;
            }
            acc += len;
            seg += 1;
        }
    }
    out
}

/// Light filtering: `rounds` of Laplacian smoothing with factor 0.3 (a stroke's jitter goes,
/// its shape stays).
pub fn smooth(c: &mut [Point2<f64>], rounds: usize) {
    let n = c.len();
    for _ in 0..rounds {
        let old = c.to_vec();
        for i in 0..n {
            let mid = (old[(i + n - 1) % n].coords + old[(i + 1) % n].coords) / 2.0;
            c[i] = Point2::from(old[i].coords * 0.7 + mid * 0.3);
        }
    }
}

/// Parameters (t, u) of the intersection a + t (b - a) = c + u (d - c) of segments ab and cd
/// (proper or touching: both in [0, 1]), if any.
pub fn segment_hit_params(
    a: Point2<f64>,
    b: Point2<f64>,
    c: Point2<f64>,
    d: Point2<f64>,
) -> Option<(f64, f64)> {
    let r = b - a;
    let s = d - c;
    let den = r.x * s.y - r.y * s.x;
    if den.abs() < 1e-300 {
        return None;
    }
    let q = c - a;
    let t = (q.x * s.y - q.y * s.x) / den;
    let u = (q.x * r.y - q.y * r.x) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then_some((t, u))
}

/// Intersection point of segments ab and cd (proper or touching), if any.
pub fn segment_hit(
    a: Point2<f64>,
    b: Point2<f64>,
    c: Point2<f64>,
    d: Point2<f64>,
) -> Option<Point2<f64>> {
    segment_hit_params(a, b, c, d).map(|(t, _)| a + (b - a) * t)
}

/// Crossings between two closed polylines as (segment i of a, t on it, segment j of b, u on
/// it), in order of i then j (`same` = a contour with itself: adjacent segments are skipped,
/// and each pair is visited once, j > i + 1). Segments whose bounding boxes are disjoint are
/// skipped before the exact test.
pub fn segment_crossings(
    a: &[Point2<f64>],
    b: &[Point2<f64>],
    same: bool,
) -> Vec<(usize, f64, usize, f64)> {
    let (na, nb) = (a.len(), b.len());
    let mut out = Vec::new();
    for i in 0..na {
        let (p0, p1) = (a[i], a[(i + 1) % na]);
        let (lo, hi) = (p0.coords.inf(&p1.coords), p0.coords.sup(&p1.coords));
        for j in 0..nb {
            if same && (j <= i + 1 || (i == 0 && j == nb - 1)) {
                continue;
            }
            let (q0, q1) = (b[j], b[(j + 1) % nb]);
            if q0.x.max(q1.x) < lo.x
                || q0.x.min(q1.x) > hi.x
                || q0.y.max(q1.y) < lo.y
                || q0.y.min(q1.y) > hi.y
            {
                continue;
            }
            if let Some((t, u)) = segment_hit_params(p0, p1, q0, q1) {
                out.push((i, t, j, u));
            }
        }
    }
    out
}

/// Crossing points between two closed polylines (`same` = a contour with itself: adjacent
/// segments are skipped).
pub fn crossings(a: &[Point2<f64>], b: &[Point2<f64>], same: bool) -> Vec<Point2<f64>> {
    segment_crossings(a, b, same)
        .into_iter()
        .map(|(i, t, _, _)| {
            let (p0, p1) = (a[i], a[(i + 1) % a.len()]);
            p0 + (p1 - p0) * t
        })
        .collect()
}

/// A panel: an outer contour (counter-clockwise) and its holes (clockwise), with the index of
/// the drawing contour it came from.
#[derive(Debug, Clone)]
pub struct Part {
    pub contour: usize,
    /// Layer of a self-overlapping contour (1 for an ordinary one; [`super::paneling`]).
    pub level: i32,
    pub outer: Vec<Point2<f64>>,
    pub holes: Vec<Vec<Point2<f64>>>,
}

impl Part {
    /// All boundary loops, outer first.
    pub fn loops(&self) -> impl Iterator<Item = &Vec<Point2<f64>>> {
        std::iter::once(&self.outer).chain(self.holes.iter())
    }
    /// Inside the region (inside the outer loop, outside every hole).
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        inside(&self.outer, p) && !self.holes.iter().any(|h| inside(h, p))
    }
}

/// The contour analysis result.
#[derive(Debug, Clone)]
pub struct Analysis {
    pub parts: Vec<Part>,
    /// (front, back) part pairs whose regions overlap.
    pub overlaps: Vec<(usize, usize)>,
    /// The resampling spacing used.
    pub spacing: f64,
    /// Crossing points found between contours.
    pub crossings: usize,
    /// Self-crossings of folded contours (each one splits the stroke into layers).
    pub self_crossings: usize,
}

/// Cleans the contours and builds panels. `spacing` is the resampling step (absolute).
/// A contour that crosses itself is split into its layers ([`super::paneling`]); a higher
/// layer lies in front of the lower ones unless `fold_behind`.
pub fn analyse(
    contours: &[Vec<Point2<f64>>],
    over: &[(usize, usize)],
    spacing: f64,
    fold_behind: bool,
) -> Result<Analysis> {
    // Cleaned loops with the drawing contour they came from and their layer.
    let mut clean: Vec<Vec<Point2<f64>>> = Vec::with_capacity(contours.len());
    let mut origin: Vec<usize> = Vec::with_capacity(contours.len());
    let mut level: Vec<i32> = Vec::with_capacity(contours.len());
    let mut layer_holes: Vec<Vec<Vec<Point2<f64>>>> = Vec::with_capacity(contours.len());
    let mut self_crossings = 0;
    for (k, c) in contours.iter().enumerate() {
        let len = perimeter(c);
        let area = signed_area(c).abs();
        if area.partial_cmp(&(1e-6 * len * len)) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Degenerate(format!(
                "contour {k} encloses no area (a line or a point)"
            )));
        }
        let n = ((len / spacing).round() as usize).max(12);
        let mut r = resample(c, n);
        smooth(&mut r, 2);
        if signed_area(&r) < 0.0 {
            r.reverse();
        }
        let (layers, nx) = super::paneling::layers(&r, spacing)
            .map_err(|e| Error::Degenerate(format!("contour {k}: {e}")))?;
        self_crossings += nx;
        for l in layers {
            clean.push(l.outline);
            layer_holes.push(l.holes);
            origin.push(k);
            level.push(l.level);
        }
    }
    let n = clean.len();
    // Pairwise relations: crossing, or nesting.
    let mut cross = vec![vec![false; n]; n];
    let mut ncross = 0;
    for i in 0..n {
        for j in i + 1..n {
            if origin[i] == origin[j] {
                // Layers of one folded contour overlap (they touch at the crossings).
                cross[i][j] = true;
                cross[j][i] = true;
                continue;
            }
            let c = crossings(&clean[i], &clean[j], false).len();
            ncross += c;
            cross[i][j] = c > 0;
            cross[j][i] = c > 0;
        }
    }
    let contains = |i: usize, j: usize| !cross[i][j] && inside(&clean[i], &clean[j][0]);
    // Nesting depth among non-crossing contours: even = outer, odd = hole.
    let depth: Vec<usize> = (0..n)
        .map(|j| (0..n).filter(|&i| i != j && contains(i, j)).count())
        .collect();
    let mut part_of = vec![usize::MAX; n];
    let mut parts: Vec<Part> = Vec::new();
    for k in 0..n {
        if depth[k].is_multiple_of(2) {
            part_of[k] = parts.len();
            parts.push(Part {
                contour: origin[k],
                level: level[k],
                outer: clean[k].clone(),
                holes: layer_holes[k].clone(),
            });
        }
    }
    for k in 0..n {
        if !depth[k].is_multiple_of(2) {
            // The hole belongs to the innermost outer contour holding it.
            let owner = (0..n)
                .filter(|&i| depth[i] + 1 == depth[k] && contains(i, k))
                .min_by(|&a, &b| {
                    signed_area(&clean[a])
                        .abs()
                        .total_cmp(&signed_area(&clean[b]).abs())
                });
            let Some(o) = owner else {
                return Err(Error::Degenerate(format!(
                    "contour {k} is nested in contours that cross each other; draw holes inside a single outline"
                )));
            };
            let mut h = clean[k].clone();
            h.reverse();
            part_of[k] = part_of[o];
            parts[part_of[o]].holes.push(h);
        }
    }
    // Overlaps between parts: crossing outlines, or a part lying inside another's hole region
    // is not an overlap; a part inside another part's filled region is (it sits in front).
    let mut overlaps = Vec::new();
    for a in 0..parts.len() {
        for b in a + 1..parts.len() {
            let (ka, kb) = (parts[a].contour, parts[b].contour);
            let same = ka == kb;
            let touching = same
                || parts[a].loops().any(|la| {
                    parts[b]
                        .loops()
                        .any(|lb| !crossings(la, lb, false).is_empty())
                });
            let nested =
                parts[a].contains(&parts[b].outer[0]) || parts[b].contains(&parts[a].outer[0]);
            if !(touching || nested) {
                continue;
            }
            if same {
                // Layers of one folded contour: the higher layer (the fold) in front, unless
                // `fold_behind`.
                let a_front = (parts[a].level > parts[b].level) != fold_behind;
                overlaps.push(if a_front { (a, b) } else { (b, a) });
                continue;
            }
            // Explicit pairs first (by drawing contour index, its lowest layer), else later in
            // front.
            let part_of_contour = |c: usize| (0..n).find(|&l| origin[l] == c).map(|l| part_of[l]);
            let explicit = over.iter().rev().find_map(|&(f, k)| {
                let f = part_of_contour(f)?;
                let k = part_of_contour(k)?;
                if (f, k) == (a, b) {
                    Some((a, b))
                } else if (f, k) == (b, a) {
                    Some((b, a))
                } else {
                    None
                }
            });
            overlaps.push(explicit.unwrap_or(if kb > ka { (b, a) } else { (a, b) }));
        }
    }
    Ok(Analysis {
        parts,
        overlaps,
        spacing,
        crossings: ncross,
        self_crossings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn circle(cx: f64, cy: f64, r: f64, n: usize) -> Vec<Point2<f64>> {
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                Point2::new(cx + r * t.cos(), cy + r * t.sin())
            })
            .collect()
    }

    #[test]
    fn resampling_is_even_and_keeps_the_area() {
        let c = circle(0.0, 0.0, 1.0, 7);
        let r = resample(&c, 70);
        let d: Vec<f64> = (0..70).map(|i| (r[(i + 1) % 70] - r[i]).norm()).collect();
        let (lo, hi) = d
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), x| (a.min(*x), b.max(*x)));
        assert!(hi - lo < 0.2 * hi, "{lo} {hi}");
        assert!((signed_area(&r) - signed_area(&c)).abs() < 0.05 * signed_area(&c));
    }

    #[test]
    fn ring_nests_and_ellipses_overlap_in_order() {
        let a = analyse(
            &[circle(0.0, 0.0, 2.0, 50), circle(0.0, 0.0, 1.0, 50)],
            &[],
            0.1,
            false,
        )
        .unwrap();
        assert_eq!(a.parts.len(), 1);
        assert_eq!(a.parts[0].holes.len(), 1);
        assert!(a.parts[0].contains(&Point2::new(1.5, 0.0)));
        assert!(!a.parts[0].contains(&Point2::new(0.0, 0.0)));
        let b = analyse(
            &[circle(0.0, 0.0, 1.0, 50), circle(1.0, 0.0, 1.0, 50)],
            &[],
            0.1,
            false,
        )
        .unwrap();
        assert_eq!(b.parts.len(), 2);
        assert_eq!(b.overlaps, vec![(1, 0)]);
        let c = analyse(
            &[circle(0.0, 0.0, 1.0, 50), circle(1.0, 0.0, 1.0, 50)],
            &[(0, 1)],
            0.1,
            false,
        )
        .unwrap();
        assert_eq!(c.overlaps, vec![(0, 1)]);
    }

    #[test]
    fn self_crossing_contour_gives_layers_in_front() {
        let c: Vec<Point2<f64>> = (0..40)
            .map(|i| {
                let t = i as f64 / 40.0 * std::f64::consts::TAU;
                // Limacon r = 0.5 + cos t: a loop inside a loop, crossing itself once.
                let r = 0.5 + t.cos();
                Point2::new(r * t.cos(), r * t.sin())
            })
            .collect();
        let a = analyse(std::slice::from_ref(&c), &[], 0.05, false).unwrap();
        assert_eq!(a.self_crossings, 1);
        assert_eq!(a.parts.len(), 2);
        assert_eq!((a.parts[0].level, a.parts[1].level), (1, 2));
        assert!(a.parts.iter().all(|p| p.contour == 0 && p.holes.is_empty()));
        assert_eq!(a.overlaps, vec![(1, 0)]);
        let b = analyse(&[c], &[], 0.05, true).unwrap();
        assert_eq!(b.overlaps, vec![(0, 1)]);
    }
}
