//! Paneling of a self-overlapping contour (seed 001 sections 3 and 4.2, Williams' paneling
//! [19]; the paper cuts the closed curves at their crossings into segments labelled with the
//! number of surfaces hiding them, and stacks panels with depth index = number of panels
//! between the viewer and the panel, which drives the no-collision pairs of eq. 2-3):
//! a closed stroke that crosses itself, such as a tail curled over its own body drawn as one
//! curve, is the outline of a folded (immersed) sheet. Its planar arrangement splits the
//! stroke at the self-crossings into arcs; the region to the left of an arc (the stroke is
//! counter-clockwise overall) is covered w times, w the winding number of the stroke there.
//! The w-th layer of the sheet is the region covered at least w times; its boundary is exactly
//! the set of arcs whose left side has winding number w (their right side has w - 1), so the
//! layer outlines are found by chaining those arcs at the crossings.
//!
//! Layer 1 is the whole silhouette; layer 2 the doubly covered region (where the fold lies over
//! the body), and so on. Each layer loop becomes a panel of its own; a higher layer overlaps
//! the lower ones and by default lies in front (the fold over the body, as in the paper's
//! figure 1 tail; the fold gets depth index 0, the body under it 1); `fold_behind` puts it
//! behind. The depth label of every crossing follows:
//! the branch that bounds the higher layer is over. Clockwise loops of a level are holes of
//! that layer (the uncovered region a curled tail encloses with the body); a clockwise loop
//! with no layer around it (a sheet turned over, negative winding) is rejected.

use super::contour::{segment_crossings, signed_area};
use crate::error::{Error, Result};
use nalgebra::Point2;

/// A self-crossing of a closed polyline: segment `i` at parameter `ti` meets segment `j` at
/// `tj` (i < j), at point `p`.
#[derive(Debug, Clone, Copy)]
pub struct Crossing {
    pub i: usize,
    pub ti: f64,
    pub j: usize,
    pub tj: f64,
    pub p: Point2<f64>,
}

/// All self-crossings of the closed polyline `c` (adjacent segments skipped; a crossing found
/// twice at a shared vertex is kept once).
pub fn self_crossings(c: &[Point2<f64>]) -> Vec<Crossing> {
    let n = c.len();
    let mut out: Vec<Crossing> = Vec::new();
    for (i, ti, j, tj) in segment_crossings(c, c, true) {
        let (p0, p1) = (c[i], c[(i + 1) % n]);
        let (q0, q1) = (c[j], c[(j + 1) % n]);
        let p = p0 + (p1 - p0) * ti;
        let scale = (p1 - p0).norm().max((q1 - q0).norm());
        if out
            .iter()
            .any(|x| (x.p - p).norm() <= 1e-9 * scale.max(1e-300))
        {
            continue;
        }
        out.push(Crossing { i, ti, j, tj, p });
    }
    out
}

/// Winding number of the closed polyline `c` around `p` (counter-clockwise positive).
pub fn winding(c: &[Point2<f64>], p: &Point2<f64>) -> i32 {
    let n = c.len();
    let mut w = 0;
    for k in 0..n {
        let (a, b) = (c[k], c[(k + 1) % n]);
        let side = (b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y);
        if a.y <= p.y {
            if b.y > p.y && side > 0.0 {
                w += 1;
            }
        } else if b.y <= p.y && side < 0.0 {
            w -= 1;
        }
    }
    w
}

/// One layer panel: a counter-clockwise simple outline covered `level` times inside, with
/// its holes (clockwise; regions the fold encloses without covering them, e.g. inside a
/// tail that curls back onto the body).
#[derive(Debug, Clone)]
pub struct Layer {
    pub level: i32,
    pub outline: Vec<Point2<f64>>,
    pub holes: Vec<Vec<Point2<f64>>>,
}

/// An arc of the stroke between two consecutive crossing visits.
struct Arc {
    from: usize,
    to: usize,
    points: Vec<Point2<f64>>,
    /// Winding number just left of the arc.
    left: i32,
}

/// Splits a counter-clockwise closed polyline (evenly resampled at `spacing`) into its layer
/// outlines. A simple polyline gives itself as the one layer. Returns the layers, lowest
/// first, and the number of self-crossings.
pub fn layers(c: &[Point2<f64>], spacing: f64) -> Result<(Vec<Layer>, usize)> {
    let xs = self_crossings(c);
    if xs.is_empty() {
        return Ok((
            vec![Layer {
                level: 1,
                outline: c.to_vec(),
                holes: Vec::new(),
            }],
            0,
        ));
    }
    let n = c.len();
    // Visits of the crossings in stroke order: (position along the stroke, crossing id).
    let mut visits: Vec<(f64, usize)> = Vec::with_capacity(2 * xs.len());
    for (k, x) in xs.iter().enumerate() {
        visits.push((x.i as f64 + x.ti, k));
        visits.push((x.j as f64 + x.tj, k));
    }
    visits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let m = visits.len();
    let mut arcs: Vec<Arc> = Vec::with_capacity(m);
    for v in 0..m {
        let (s0, k0) = visits[v];
        let (mut s1, k1) = visits[(v + 1) % m];
        if v + 1 == m {
            s1 += n as f64;
        }
        let mut points = vec![xs[k0].p];
        // Stroke vertices strictly between the two visits.
        let first = s0.floor() as usize + 1;
        let mut idx = first;
        while (idx as f64) < s1 {
            let p = c[idx % n];
            if (p - *points.last().unwrap_or(&p)).norm() > 1e-12 {
                points.push(p);
            }
            idx += 1;
        }
        points.push(xs[k1].p);
        // Winding just left of the arc, at its middle (by length) away from the crossings.
        let len: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        let mut acc = 0.0;
        let mut left = 0;
        for w in points.windows(2) {
            let l = (w[1] - w[0]).norm();
            if acc + l >= len / 2.0 && l > 0.0 {
                let t = ((len / 2.0 - acc) / l).clamp(0.0, 1.0);
                let mid = w[0] + (w[1] - w[0]) * t;
                let d = (w[1] - w[0]) / l;
                let eps = (0.25 * spacing).min(0.1 * len.max(1e-12));
                let q = mid + nalgebra::Vector2::new(-d.y, d.x) * eps;
                left = winding(c, &q);
                break;
            }
            acc += l;
        }
        arcs.push(Arc {
            from: k0,
            to: k1,
            points,
            left,
        });
    }
    // Chain the arcs of each level into loops at the crossings.
    let top = arcs.iter().map(|a| a.left).max().unwrap_or(1);
    let mut used = vec![false; arcs.len()];
    let mut out: Vec<Layer> = Vec::new();
    let mut holes: Vec<(i32, Vec<Point2<f64>>)> = Vec::new();
    for level in 1..=top {
        for start in 0..arcs.len() {
            if used[start] || arcs[start].left != level {
                continue;
            }
            let mut outline: Vec<Point2<f64>> = Vec::new();
            let mut a = start;
            loop {
                used[a] = true;
                let pts = &arcs[a].points;
                outline.extend_from_slice(&pts[..pts.len() - 1]);
                let at = arcs[a].to;
                // Where the layer touches itself at a crossing, two arcs of this level leave
                // it: take the tightest left turn (the first outgoing direction clockwise
                // from the reversed incoming one), which keeps every loop simple.
                let back = -direction(pts, false);
                let next = (0..arcs.len())
                    .filter(|&b| arcs[b].left == level && arcs[b].from == at)
                    .min_by(|&x, &y| {
                        clockwise(&back, &direction(&arcs[x].points, true))
                            .total_cmp(&clockwise(&back, &direction(&arcs[y].points, true)))
                    });
                match next {
                    Some(b) if !used[b] => a = b,
                    _ => break,
                }
            }
            if outline.len() < 3 {
                continue;
            }
            let area = signed_area(&outline);
            // Loops of jitter (tiny kinks of the stroke) are dropped.
            if area.abs() <= 4.0 * spacing * spacing {
                continue;
            }
            if area > 0.0 {
                out.push(Layer {
                    level,
                    outline,
                    holes: Vec::new(),
                });
            } else {
                holes.push((level, outline));
            }
        }
    }
    // Every hole goes to the smallest outline of its level around it.
    for (level, h) in holes {
        let probe = h[h.len() / 2];
        let owner = out
            .iter()
            .enumerate()
            .filter(|(_, l)| l.level == level && super::contour::inside(&l.outline, &probe))
            .min_by(|a, b| signed_area(&a.1.outline).total_cmp(&signed_area(&b.1.outline)))
            .map(|(k, _)| k);
        match owner {
            Some(k) => out[k].holes.push(h),
            None => {
                return Err(Error::Degenerate(format!(
                    "the self-overlapping contour has a loop near ({:.3}, {:.3}) that bounds no covered region (a fold turned over?); draw the parts as separate closed curves",
                    probe.x, probe.y
                )))
            }
        }
    }
    if level_one_missing(&out) {
        return Err(Error::Degenerate(
            "the self-crossing contour does not bound a folded sheet (no region is covered once)"
                .into(),
        ));
    }
    Ok((out, xs.len()))
}

/// Unit direction of an arc where it leaves its first point (`start`) or enters its last.
fn direction(pts: &[Point2<f64>], start: bool) -> nalgebra::Vector2<f64> {
    let n = pts.len();
    let d = if start {
        pts[1.min(n - 1)] - pts[0]
    } else {
        pts[n - 1] - pts[n.saturating_sub(2)]
    };
    let l = d.norm();
    if l > 0.0 {
        d / l
    } else {
        d
    }
}

/// Angle in [0, 2 pi) turning clockwise from `a` to `b`.
fn clockwise(a: &nalgebra::Vector2<f64>, b: &nalgebra::Vector2<f64>) -> f64 {
    let ccw = (a.x * b.y - a.y * b.x).atan2(a.dot(b));
    let cw = -ccw;
    if cw <= 0.0 {
        cw + std::f64::consts::TAU
    } else {
        cw
    }
}

fn level_one_missing(layers: &[Layer]) -> bool {
    !layers.iter().any(|l| l.level == 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limacon(n: usize) -> Vec<Point2<f64>> {
        // r = 0.5 + cos t: an inner loop inside the outer one, crossing once at the origin.
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = 0.5 + t.cos();
                Point2::new(r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn limacon_gives_an_outer_layer_and_a_fold() {
        let c = limacon(400);
        assert!(signed_area(&c) > 0.0);
        let (ls, nx) = layers(&c, 0.02).unwrap();
        assert_eq!(nx, 1);
        assert_eq!(
            ls.len(),
            2,
            "{:?}",
            ls.iter().map(|l| l.level).collect::<Vec<_>>()
        );
        assert_eq!(ls[0].level, 1);
        assert_eq!(ls[1].level, 2);
        // The outer layer is the whole silhouette (x from -0.5... 1.5), the fold the inner
        // loop (x between 0 and 0.5 on the axis: r = 0.5 + cos t < 0 mirrored).
        let w1 = winding(&c, &Point2::new(1.0, 0.0));
        let w2 = winding(&c, &Point2::new(0.25, 0.0));
        assert_eq!((w1, w2), (1, 2));
        assert!(self_crossings(&ls[0].outline).is_empty());
        assert!(self_crossings(&ls[1].outline).is_empty());
        assert!(super::super::contour::inside(
            &ls[1].outline,
            &Point2::new(0.25, 0.0)
        ));
        assert!(!super::super::contour::inside(
            &ls[1].outline,
            &Point2::new(1.0, 0.0)
        ));
        assert!(super::super::contour::inside(
            &ls[0].outline,
            &Point2::new(0.25, 0.0)
        ));
        // Areas: the layers add up to the signed area of the stroke (sum of w * area).
        let total: f64 = ls.iter().map(|l| signed_area(&l.outline)).sum();
        assert!(
            (total - signed_area(&c)).abs() < 1e-9 * total.abs().max(1.0),
            "{total}"
        );
    }

    #[test]
    fn random_scribbles_give_layers_or_an_error_never_a_panic() {
        // Deterministic pseudo-random closed polygons (star-like, often self-crossing).
        let mut seed = 0x2545f4914f6cdd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut ok = 0;
        for _ in 0..200 {
            let n = 5 + (rnd() * 20.0) as usize;
            let c: Vec<Point2<f64>> = (0..n)
                .map(|_| Point2::new(rnd() - 0.5, rnd() - 0.5))
                .collect();
            let mut r = super::super::contour::resample(&c, 60);
            if signed_area(&r) < 0.0 {
                r.reverse();
            }
            if let Ok((ls, _)) = layers(&r, 0.02) {
                ok += 1;
                for l in &ls {
                    assert!(l.level >= 1 && l.outline.len() >= 3);
                    assert!(signed_area(&l.outline) > 0.0);
                }
            }
        }
        assert!(ok > 0);
    }

    #[test]
    fn simple_contour_is_its_own_layer() {
        let c: Vec<Point2<f64>> = (0..50)
            .map(|i| {
                let t = i as f64 / 50.0 * std::f64::consts::TAU;
                Point2::new(t.cos(), t.sin())
            })
            .collect();
        let (ls, nx) = layers(&c, 0.1).unwrap();
        assert_eq!((ls.len(), nx), (1, 0));
    }
}
