//! Completion of occluded contours at T-junctions (seed 001 section 3, "contour completion",
//! after Williams [19]; the section has no numbered equations):
//! an open stroke whose ends touch a closed contour is the visible part of an object that goes
//! on behind that contour. Each stroke end is a T-junction with an outward tangent t (the
//! direction the stroke leaves the picture in); the hidden contour joins two ends a, b by the
//! cubic Hermite curve
//!
//!   H(u) = h00(u) p_a + h10(u) L t_a + h01(u) p_b - h11(u) L t_b,  u in [0, 1],
//!
//! (h00 = 2u^3 - 3u^2 + 1, h10 = u^3 - 2u^2 + u, h01 = -2u^3 + 3u^2, h11 = u^3 - u^2), which
//! matches position and tangent direction at both junctions (G1); it is the paper's cubic
//! Bezier segment with control points p_a + L t_a / 3 and p_b + L t_b / 3. Its cost is the paper's
//! length-and-curvature energy E = int (1 + alpha kappa^2) ds (alpha = [`CURVATURE_LENGTH`]^2
//! in units of the drawing's diagonal), sampled at 64 points; the tangent magnitude L is the
//! one of L = k |p_b - p_a|, k in 0.5..3, with the least E (short curves for small k, tight
//! turns at the ends for large k).
//!
//! Which ends join is a perfect matching of the junctions (a stroke may close on itself, or
//! two strokes may be the visible pieces of one object); it is chosen by a branch-and-bound
//! over matchings in order of increasing pair energy, pruned by the best total so far, that
//! rejects topologically invalid labelings. The paper checks a candidate set with Williams'
//! integer linear program on the crossing counts and depth labels; here, with closed drawn
//! occluders only, the same constraints reduce to explicit tests: a completion must be hidden (every sample inside some closed
//! contour, which then lies in front of the completed one: depth changes only at the
//! T-junctions), completions may not cross each other or the visible strokes, and every
//! completed contour must be a simple closed curve. The depth labels follow: each closed
//! contour that hides part of a completion is over the completed contour.

use super::contour::{inside, segment_hit};
use crate::error::{Error, Result};
use nalgebra::{Point2, Vector2};

/// Curvature weight length (fraction of the diagonal): alpha = this^2 in E.
pub const CURVATURE_LENGTH: f64 = 0.1;

/// Tangent magnitudes tried, as multiples of the chord |p_b - p_a|.
const TANGENT_SCALES: [f64; 11] = [0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0];

/// Samples of a completion curve.
const SAMPLES: usize = 64;

/// At most this many T-junctions (the matching search is (2k - 1)!! in the worst case).
pub const MAX_JUNCTIONS: usize = 16;

/// A completed contour: the strokes it is made of (in order, with direction) and its
/// completions' energy and hidden length.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Completed {
    /// Stroke indices with `true` where traversed backwards.
    pub strokes: Vec<(usize, bool)>,
    pub energy: f64,
    pub hidden_length: f64,
    /// Largest angle (radians) between the stroke tangent and the completion's tangent at its
    /// junctions (0 for G1 joins up to the polyline sampling).
    pub max_turn: f64,
}

/// The result: closed contours to append to the drawing, and (front, back) depth pairs in the
/// indexing of `closed` followed by the new contours.
#[derive(Debug, Clone, Default)]
pub struct Completion {
    pub contours: Vec<Vec<Point2<f64>>>,
    pub over: Vec<(usize, usize)>,
    pub completed: Vec<Completed>,
    /// Matchings looked at by the branch-and-bound (leaves and pruned nodes).
    pub searched: usize,
}

/// Per junction pair: the completion's energy and samples (None: invalid pair).
type PairTable = Vec<Vec<Option<(f64, Vec<Point2<f64>>)>>>;

/// An assembled contour: points, strokes (index, backwards), energy, hidden length, largest
/// turn at a junction.
type Assembled = (Vec<Point2<f64>>, Vec<(usize, bool)>, f64, f64, f64);

/// A T-junction: a stroke end, its position and outward unit tangent.
#[derive(Debug, Clone, Copy)]
struct Junction {
    stroke: usize,
    end: bool,
    p: Point2<f64>,
    t: Vector2<f64>,
}

/// The Hermite completion from junction a to junction b (samples, first = p_a, last = p_b).
pub fn hermite(
    pa: Point2<f64>,
    ta: Vector2<f64>,
    pb: Point2<f64>,
    tb: Vector2<f64>,
    scale: f64,
) -> Vec<Point2<f64>> {
    let l = (pb - pa).norm() * scale;
    (0..=SAMPLES)
        .map(|k| {
            let u = k as f64 / SAMPLES as f64;
            let (u2, u3) = (u * u, u * u * u);
            let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
            let h10 = u3 - 2.0 * u2 + u;
            let h01 = -2.0 * u3 + 3.0 * u2;
            let h11 = u3 - u2;
            Point2::from(pa.coords * h00 + ta * (l * h10) + pb.coords * h01 - tb * (l * h11))
        })
        .collect()
}

/// The least-energy Hermite completion over the tangent scales: (E, curve).
pub fn best_hermite(
    pa: Point2<f64>,
    ta: Vector2<f64>,
    pb: Point2<f64>,
    tb: Vector2<f64>,
) -> (f64, Vec<Point2<f64>>) {
    TANGENT_SCALES
        .iter()
        .map(|&k| {
            let c = hermite(pa, ta, pb, tb, k);
            (energy(&c).0, c)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or_else(|| (f64::INFINITY, vec![pa, pb]))
}

/// E = int (1 + alpha kappa^2) ds of a sampled open curve (discrete turning angles).
pub fn energy(c: &[Point2<f64>]) -> (f64, f64) {
    let alpha = CURVATURE_LENGTH * CURVATURE_LENGTH;
    let len: f64 = c.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let mut bend = 0.0;
    for w in c.windows(3) {
        let (a, b) = (w[1] - w[0], w[2] - w[1]);
        let (la, lb) = (a.norm(), b.norm());
        if la > 0.0 && lb > 0.0 {
            let turn = (a.x * b.y - a.y * b.x).atan2(a.dot(&b));
            let ds = (la + lb) / 2.0;
            bend += turn * turn / ds; // kappa^2 ds with kappa = turn / ds
        }
    }
    (len + alpha * bend, len)
}

/// Open polyline resampled at about `spacing` (ends kept), lightly smoothed with fixed ends.
fn clean_stroke(s: &[Point2<f64>], spacing: f64) -> Vec<Point2<f64>> {
    let len: f64 = s.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let n = ((len / spacing).round() as usize).max(4);
    let step = len / n as f64;
    let mut out = Vec::with_capacity(n + 1);
    let (mut seg, mut acc) = (0usize, 0.0);
    for k in 0..=n {
        let target = k as f64 * step;
        while seg + 1 < s.len() - 1 && acc + (s[seg + 1] - s[seg]).norm() < target {
            acc += (s[seg + 1] - s[seg]).norm();
            seg += 1;
        }
        let l = (s[seg + 1] - s[seg]).norm();
        let t = if l > 0.0 {
            ((target - acc) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(s[seg] + (s[seg + 1] - s[seg]) * t);
    }
    for _ in 0..2 {
        let old = out.clone();
        for i in 1..out.len() - 1 {
            let mid = (old[i - 1].coords + old[i + 1].coords) / 2.0;
            out[i] = Point2::from(old[i].coords * 0.7 + mid * 0.3);
        }
    }
    out
}

/// Outward unit tangent at an end of a stroke, from the chord over about 3 spacings.
fn end_tangent(s: &[Point2<f64>], end: bool, spacing: f64) -> Option<Vector2<f64>> {
    let n = s.len();
    let (p, pts): (Point2<f64>, Vec<Point2<f64>>) = if end {
        (s[n - 1], s.iter().rev().skip(1).copied().collect())
    } else {
        (s[0], s.iter().skip(1).copied().collect())
    };
    let q = pts
        .iter()
        .find(|q| (p - *q).norm() >= 3.0 * spacing)
        .or(pts.last())?;
    let d = p - q;
    let l = d.norm();
    (l > 0.0).then(|| d / l)
}

fn polylines_cross(a: &[Point2<f64>], b: &[Point2<f64>], skip_ends: bool) -> bool {
    let lo = usize::from(skip_ends);
    for i in lo..a.len().saturating_sub(1 + lo) {
        for j in lo..b.len().saturating_sub(1 + lo) {
            if segment_hit(a[i], a[i + 1], b[j], b[j + 1]).is_some() {
                return true;
            }
        }
    }
    false
}

/// Completes the strokes (coordinates as `closed`, in units of the drawing's diagonal),
/// `spacing` the resampling step.
pub fn complete(
    closed: &[Vec<Point2<f64>>],
    strokes: &[Vec<Point2<f64>>],
    spacing: f64,
) -> Result<Completion> {
    if strokes.is_empty() {
        return Ok(Completion::default());
    }
    if 2 * strokes.len() > MAX_JUNCTIONS {
        return Err(Error::InvalidOption(format!(
            "{} open strokes: at most {} T-junctions are completed",
            strokes.len(),
            MAX_JUNCTIONS
        )));
    }
    if let Some(k) = strokes.iter().position(|s| s.len() < 2) {
        return Err(Error::Degenerate(format!(
            "open stroke {k} has fewer than 2 points"
        )));
    }
    let clean: Vec<Vec<Point2<f64>>> = strokes.iter().map(|s| clean_stroke(s, spacing)).collect();
    let mut js = Vec::new();
    for (k, s) in clean.iter().enumerate() {
        for end in [false, true] {
            let t = end_tangent(s, end, spacing)
                .ok_or_else(|| Error::Degenerate(format!("open stroke {k} has no length")))?;
            js.push(Junction {
                stroke: k,
                end,
                p: if end { s[s.len() - 1] } else { s[0] },
                t,
            });
        }
    }
    let m = js.len();
    // Pair costs and curves; None = invalid (not hidden, or crossing a visible stroke).
    let hidden_by = |p: &Point2<f64>| -> Vec<usize> {
        (0..closed.len())
            .filter(|&c| {
                inside(&closed[c], p)
                    || crate::sketch::input::distance_to_loop(&closed[c], p) <= 1.5 * spacing
            })
            .collect()
    };
    let mut pair: PairTable = vec![vec![None; m]; m];
    for a in 0..m {
        for b in a + 1..m {
            let (ja, jb) = (js[a], js[b]);
            if (jb.p - ja.p).norm() < spacing {
                continue;
            }
            let (e, c) = best_hermite(ja.p, ja.t, jb.p, jb.t);
            if c.iter().any(|p| hidden_by(p).is_empty()) {
                continue;
            }
            if clean.iter().any(|s| polylines_cross(&c, s, true)) {
                continue;
            }
            pair[a][b] = Some((e, c.clone()));
            pair[b][a] = Some((e, c.into_iter().rev().collect()));
        }
    }
    // Branch-and-bound over perfect matchings.
    struct Search<'a> {
        pair: &'a PairTable,
        best: Option<(f64, Vec<usize>)>,
        searched: usize,
        valid: &'a dyn Fn(&[usize]) -> bool,
    }
    fn go(s: &mut Search, mate: &mut Vec<usize>, cost: f64) {
        s.searched += 1;
        if let Some((b, _)) = &s.best {
            if cost >= *b {
                return;
            }
        }
        let Some(a) = mate.iter().position(|&x| x == usize::MAX) else {
            if (s.valid)(mate) {
                s.best = Some((cost, mate.clone()));
            }
            return;
        };
        let mut cands: Vec<(f64, usize)> = (0..mate.len())
            .filter(|&b| b != a && mate[b] == usize::MAX)
            .filter_map(|b| s.pair[a][b].as_ref().map(|(e, _)| (*e, b)))
            .collect();
        cands.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (e, b) in cands {
            // Completions of this matching may not cross each other.
            let crosses = (0..mate.len()).any(|x| {
                mate[x] != usize::MAX && x < mate[x] && {
                    let (cx, cb) = (&s.pair[x][mate[x]], &s.pair[a][b]);
                    match (cx, cb) {
                        (Some((_, p)), Some((_, q))) => polylines_cross(p, q, true),
                        _ => true,
                    }
                }
            });
            if crosses {
                continue;
            }
            mate[a] = b;
            mate[b] = a;
            go(s, mate, cost + e);
            mate[a] = usize::MAX;
            mate[b] = usize::MAX;
        }
    }
    let assemble = |mate: &[usize]| -> Vec<Assembled> {
        let mut used = vec![false; clean.len()];
        let mut out = Vec::new();
        for s0 in 0..clean.len() {
            if used[s0] {
                continue;
            }
            let (mut pts, mut parts) = (Vec::new(), Vec::new());
            let (mut e_sum, mut hidden, mut turn) = (0.0, 0.0, 0.0f64);
            // Walk: traverse stroke s from its `from_end` junction to the other end.
            let (mut s, mut backwards) = (s0, false);
            loop {
                used[s] = true;
                parts.push((s, backwards));
                let st = &clean[s];
                if backwards {
                    pts.extend(st.iter().rev().copied());
                } else {
                    pts.extend(st.iter().copied());
                }
                let exit = 2 * s + usize::from(!backwards);
                let into = mate[exit];
                if let Some((e, c)) = &pair[exit][into] {
                    e_sum += e;
                    hidden += energy(c).1;
                    // G1 check: completion tangent vs stroke tangent at both ends.
                    let d0 = c[1] - c[0];
                    let d1 = c[c.len() - 1] - c[c.len() - 2];
                    let t_in = -js[into].t;
                    turn = turn.max(js[exit].t.angle(&d0)).max(t_in.angle(&d1));
                    pts.extend(c[1..c.len() - 1].iter().copied());
                }
                s = js[into].stroke;
                backwards = js[into].end;
                if used[s] {
                    break;
                }
            }
            out.push((pts, parts, e_sum, hidden, turn));
        }
        out
    };
    let valid = |mate: &[usize]| -> bool {
        assemble(mate)
            .iter()
            .all(|(c, ..)| super::paneling::self_crossings(c).is_empty())
    };
    let mut search = Search {
        pair: &pair,
        best: None,
        searched: 0,
        valid: &valid,
    };
    let mut mate = vec![usize::MAX; m];
    go(&mut search, &mut mate, 0.0);
    let Some((_, mate)) = search.best else {
        return Err(Error::Degenerate(
            "no valid completion of the open strokes: every way of joining their ends behind the closed contours is visible or crosses itself".into(),
        ));
    };
    let mut result = Completion {
        searched: search.searched,
        ..Completion::default()
    };
    for (pts, parts, energy, hidden_length, max_turn) in assemble(&mate) {
        let idx = closed.len() + result.contours.len();
        // Depth labels: every closed contour hiding part of a completion is over it.
        for (a, &b) in mate.iter().enumerate() {
            if a < b && parts.iter().any(|&(s, _)| s == js[a].stroke) {
                if let Some((_, c)) = &pair[a][b] {
                    for p in c.iter().skip(1).take(c.len().saturating_sub(2)) {
                        for o in hidden_by(p) {
                            if inside(&closed[o], p) && !result.over.contains(&(o, idx)) {
                                result.over.push((o, idx));
                            }
                        }
                    }
                }
            }
        }
        result.contours.push(pts);
        result.completed.push(Completed {
            strokes: parts,
            energy,
            hidden_length,
            max_turn,
        });
    }
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ellipse(cx: f64, cy: f64, a: f64, b: f64, t0: f64, t1: f64, n: usize) -> Vec<Point2<f64>> {
        (0..n)
            .map(|i| {
                let t = t0 + (t1 - t0) * i as f64 / (n - 1) as f64;
                Point2::new(cx + a * t.cos(), cy + b * t.sin())
            })
            .collect()
    }

    #[test]
    fn hermite_matches_ends_and_tangents() {
        let c = hermite(
            Point2::new(0.0, 0.0),
            Vector2::new(0.0, 1.0),
            Point2::new(1.0, 0.0),
            Vector2::new(0.0, 1.0),
            1.0,
        );
        assert!((c[0] - Point2::new(0.0, 0.0)).norm() < 1e-12);
        assert!((c[SAMPLES] - Point2::new(1.0, 0.0)).norm() < 1e-12);
        assert!((c[1] - c[0]).normalize().dot(&Vector2::new(0.0, 1.0)) > 0.99);
        assert!(
            (c[SAMPLES] - c[SAMPLES - 1])
                .normalize()
                .dot(&Vector2::new(0.0, -1.0))
                > 0.99
        );
        // A straight completion costs its length.
        let s = hermite(
            Point2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Point2::new(1.0, 0.0),
            Vector2::new(-1.0, 0.0),
            1.0,
        );
        let (e, l) = energy(&s);
        assert!((e - 1.0).abs() < 1e-9 && (l - 1.0).abs() < 1e-9, "{e} {l}");
    }

    #[test]
    fn hidden_arc_of_an_ellipse_is_completed_behind_the_front_one() {
        // Front ellipse at x = 0.25, back ellipse at x = -0.25; only the back ellipse's part
        // outside the front one is drawn (its ends on the front outline).
        let front = ellipse(0.25, 0.0, 0.3, 0.15, 0.0, std::f64::consts::TAU, 200);
        let front: Vec<Point2<f64>> = front[..199].to_vec();
        // Back ellipse x = -0.25 + 0.3 cos t meets the front one where x = 0 (by symmetry):
        // cos t = 5/6.
        let t0 = (5.0f64 / 6.0).acos();
        let stroke = ellipse(-0.25, 0.0, 0.3, 0.15, t0, std::f64::consts::TAU - t0, 150);
        let c = complete(&[front], &[stroke], 0.005).unwrap();
        assert_eq!(c.contours.len(), 1);
        assert_eq!(c.over, vec![(0, 1)]);
        let done = &c.contours[0];
        assert!(super::super::paneling::self_crossings(done).is_empty());
        // Tangent continuity at the junctions (up to the sampling of the stroke).
        assert!(c.completed[0].max_turn < 0.15, "{:?}", c.completed);
        // The completed region is close to the full back ellipse (area pi a b).
        let area = super::super::contour::signed_area(done).abs();
        let full = std::f64::consts::PI * 0.3 * 0.15;
        assert!((area / full - 1.0).abs() < 0.02, "{area} {full}");
    }

    #[test]
    fn two_pieces_behind_a_bar_join_into_one_rod() {
        // A vertical bar in front; a horizontal rod drawn as its two visible pieces, each an
        // open stroke from the bar's left (right) edge around the rod's end and back.
        let bar = vec![
            Point2::new(-0.1, -0.5),
            Point2::new(0.1, -0.5),
            Point2::new(0.1, 0.5),
            Point2::new(-0.1, 0.5),
        ];
        let cap = |cx: f64, sgn: f64| -> Vec<Point2<f64>> {
            // From (sgn 0.1, 0.05) out to the cap at x = cx and back to (sgn 0.1, -0.05).
            let mut s = Vec::new();
            for i in 0..=20 {
                let x = sgn * 0.1 + (cx - sgn * 0.1) * i as f64 / 20.0;
                s.push(Point2::new(x, 0.05));
            }
            for i in 1..20 {
                let a = std::f64::consts::FRAC_PI_2 - std::f64::consts::PI * i as f64 / 20.0;
                s.push(Point2::new(cx + sgn * 0.05 * a.cos(), 0.05 * a.sin()));
            }
            for i in 0..=20 {
                let x = cx + (sgn * 0.1 - cx) * i as f64 / 20.0;
                s.push(Point2::new(x, -0.05));
            }
            s
        };
        let c = complete(&[bar], &[cap(0.5, 1.0), cap(-0.5, -1.0)], 0.01).unwrap();
        // One rod through the bar, not two capsules closed on themselves.
        assert_eq!(c.contours.len(), 1, "{:?}", c.completed);
        assert_eq!(c.completed[0].strokes.len(), 2);
        assert_eq!(c.over, vec![(0, 1)]);
        assert!(c.searched >= 2);
    }
}
