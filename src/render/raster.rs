//! Z-buffered rasterization of triangles and point splats into a visibility buffer: per pixel
//! the nearest depth (f32) and the index of the primitive seen there. Shading happens later,
//! once per visible pixel (see `shade.rs`), so overdraw costs only a depth test.
//!
//! Triangles use the half-space (edge function) test on vertices snapped to 1/256 pixel, in
//! exact i64 arithmetic: for the edge a->b, `E(p) = (b-a) x (p-a)`, positive inside a
//! triangle of positive area. A pixel centre exactly on an edge belongs to the triangle for
//! which the edge is a "top-left" edge (here: `dy > 0`, or `dy == 0` and `dx < 0`), so two
//! triangles sharing an edge never both cover, nor both miss, a pixel on it: no cracks, no
//! double hits. Depth is the plane through the three vertices, `z = z0 + zx (x-x0) + zy (y-y0)`.
//!
//! Parallelism: the picture is cut into horizontal bands; each primitive is binned into the
//! bands its bounding box touches (binned in parallel chunks, concatenated in primitive
//! order), and the bands are rasterized in parallel, each visiting its primitives in order.
//! A depth tie keeps the earlier primitive. The buffer therefore does not depend on the
//! number of threads.

use rayon::prelude::*;

/// "No primitive" in the id buffer.
pub const EMPTY: u32 = u32::MAX;

/// Sub-pixel precision of snapped vertices: 2^8 steps per pixel.
const SUB: f64 = 256.0;

/// Rows per band.
const BAND: usize = 16;

/// A visibility buffer.
#[derive(Debug, Clone)]
pub struct Visibility {
    pub width: usize,
    pub height: usize,
    /// Depth per pixel (model units, growing away from the viewer); `f32::INFINITY` when empty.
    pub depth: Vec<f32>,
    /// Primitive index per pixel, or [`EMPTY`].
    pub id: Vec<u32>,
}

impl Visibility {
    pub fn new(width: usize, height: usize) -> Visibility {
        Visibility {
            width,
            height,
            depth: vec![f32::INFINITY; width * height],
            id: vec![EMPTY; width * height],
        }
    }
}

/// A primitive's row range `[y0, y1]` (inclusive, clipped), or `None` when off screen.
type RowSpan = Option<(usize, usize)>;

/// Bins primitives into bands: for each band the primitives touching it, in index order.
fn bin(n: usize, height: usize, rows: impl Fn(usize) -> RowSpan + Sync) -> Vec<Vec<u32>> {
    let nbands = height.div_ceil(BAND);
    const CHUNK: usize = 1 << 16;
    let partial: Vec<Vec<Vec<u32>>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut bands = vec![Vec::new(); nbands];
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                if let Some((y0, y1)) = rows(i) {
                    for b in bands.iter_mut().take(y1 / BAND + 1).skip(y0 / BAND) {
                        b.push(i as u32);
                    }
                }
            }
            bands
        })
        .collect();
    (0..nbands)
        .into_par_iter()
        .map(|b| {
            let mut v = Vec::with_capacity(partial.iter().map(|p| p[b].len()).sum());
            for p in &partial {
                v.extend_from_slice(&p[b]);
            }
            v
        })
        .collect()
}

/// Rows a primitive spanning `[ymin, ymax]` (pixel units) can cover: pixel centres `y + 0.5`
/// inside the span.
#[inline]
fn row_span(ymin: f32, ymax: f32, height: usize) -> RowSpan {
    if !(ymin.is_finite() && ymax.is_finite()) || ymax < 0.0 || ymin > height as f32 {
        return None;
    }
    let y0 = (ymin - 0.5).ceil().max(0.0) as usize;
    let y1 = ((ymax - 0.5).floor().min(height as f32 - 1.0)).max(-1.0);
    if y1 < 0.0 || (y1 as usize) < y0 {
        return None;
    }
    Some((y0, y1 as usize))
}

/// Rasterizes triangles given screen vertices `[x, y, depth]` (pixels, y down). The id of a
/// pixel is the index of the triangle in `faces`.
pub fn triangles(buf: &mut Visibility, verts: &[[f32; 3]], faces: &[[u32; 3]]) {
    let (w, h) = (buf.width, buf.height);
    let bins = bin(faces.len(), h, |i| {
        let [a, b, c] = faces[i].map(|k| verts[k as usize]);
        if !a.iter().chain(&b).chain(&c).all(|v| v.is_finite()) {
            return None;
        }
        let ymin = a[1].min(b[1]).min(c[1]);
        let ymax = a[1].max(b[1]).max(c[1]);
        let xmin = a[0].min(b[0]).min(c[0]);
        let xmax = a[0].max(b[0]).max(c[0]);
        if xmax < 0.0 || xmin > w as f32 {
            return None;
        }
        row_span(ymin, ymax, h)
    });
    buf.depth
        .par_chunks_mut(BAND * w)
        .zip(buf.id.par_chunks_mut(BAND * w))
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(band, ((depth, id), tris))| {
            let y_lo = band * BAND;
            let y_hi = (y_lo + BAND).min(h) - 1;
            for &t in tris {
                let [a, b, c] = faces[t as usize].map(|k| verts[k as usize]);
                triangle(depth, id, w, h, y_lo, y_hi, t, a, b, c);
            }
        });
}

/// Rasterizes one triangle into the rows `y_lo..=y_hi` held by `depth`/`id`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn triangle(
    depth: &mut [f32],
    id: &mut [u32],
    w: usize,
    h: usize,
    y_lo: usize,
    y_hi: usize,
    t: u32,
    a: [f32; 3],
    b: [f32; 3],
    c: [f32; 3],
) {
    let snap = |v: f32| (v as f64 * SUB).round() as i64;
    let (x0, y0) = (snap(a[0]), snap(a[1]));
    let (mut x1, mut y1, mut z1) = (snap(b[0]), snap(b[1]), b[2]);
    let (mut x2, mut y2, mut z2) = (snap(c[0]), snap(c[1]), c[2]);
    let z0 = a[2];
    let mut area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    if area == 0 {
        return;
    }
    if area < 0 {
        std::mem::swap(&mut x1, &mut x2);
        std::mem::swap(&mut y1, &mut y2);
        std::mem::swap(&mut z1, &mut z2);
        area = -area;
    }
    // Pixel range: centres (x + 0.5) within the bounding box.
    let s = SUB as i64;
    let half = s / 2;
    let lo = |v: i64| (v - half + s - 1).div_euclid(s); // ceil((v - half) / s)
    let hi = |v: i64| (v - half).div_euclid(s); // floor((v - half) / s)
    let px0 = lo(x0.min(x1).min(x2)).max(0);
    let px1 = hi(x0.max(x1).max(x2)).min(w as i64 - 1);
    let py0 = lo(y0.min(y1).min(y2)).max(y_lo as i64);
    let py1 = hi(y0.max(y1).max(y2)).min(y_hi as i64).min(h as i64 - 1);
    if px0 > px1 || py0 > py1 {
        return;
    }
    // Edge functions at the first pixel centre, their steps, and the top-left bias.
    let edge = |ax: i64, ay: i64, bx: i64, by: i64| {
        let (dx, dy) = (bx - ax, by - ay);
        let owned = dy > 0 || (dy == 0 && dx < 0);
        let bias = if owned { 0 } else { -1 };
        let px = px0 * s + half;
        let py = py0 * s + half;
        let e = dx * (py - ay) - dy * (px - ax) + bias;
        (e, -dy * s, dx * s)
    };
    let (e0, e0x, e0y) = edge(x1, y1, x2, y2); // opposite vertex 0
    let (e1, e1x, e1y) = edge(x2, y2, x0, y0); // opposite vertex 1
    let (e2, e2x, e2y) = edge(x0, y0, x1, y1); // opposite vertex 2
                                               // Depth plane from the snapped vertices (pixel units).
    let inv = 1.0 / area as f64;
    let (fx0, fy0) = (x0 as f64 / SUB, y0 as f64 / SUB);
    let (fx1, fy1) = (x1 as f64 / SUB - fx0, y1 as f64 / SUB - fy0);
    let (fx2, fy2) = (x2 as f64 / SUB - fx0, y2 as f64 / SUB - fy0);
    let (dz1, dz2) = ((z1 - z0) as f64, (z2 - z0) as f64);
    let sub2 = SUB * SUB;
    let zx = ((dz1 * fy2 - dz2 * fy1) * inv * sub2) as f32;
    let zy = ((dz2 * fx1 - dz1 * fx2) * inv * sub2) as f32;
    let zrow0 = (z0 as f64
        + (px0 as f64 + 0.5 - fx0) * zx as f64
        + (py0 as f64 + 0.5 - fy0) * zy as f64) as f32;
    let (mut r0, mut r1, mut r2, mut zrow) = (e0, e1, e2, zrow0);
    for py in py0..=py1 {
        let (mut q0, mut q1, mut q2, mut z) = (r0, r1, r2, zrow);
        let row = (py as usize - y_lo) * w;
        for px in px0..=px1 {
            if (q0 | q1 | q2) >= 0 {
                let k = row + px as usize;
                if z < depth[k] {
                    depth[k] = z;
                    id[k] = t;
                }
            }
            q0 += e0x;
            q1 += e1x;
            q2 += e2x;
            z += zx;
        }
        r0 += e0y;
        r1 += e1y;
        r2 += e2y;
        zrow += zy;
    }
}

/// How much a tilted disc narrows on screen, between 0 (not at all) and 1 (the exact
/// projection). Below 1 the discs stay a little wider than their true ellipses, which closes
/// the gaps that the exact ellipses leave on strongly curved, sparsely sampled parts.
const SURFEL_SQUASH: f32 = 0.6;

/// Splats points as discs of radius `radius` pixels; the id of a pixel is the index of the
/// point. With `surfels` = (gradients, model units per pixel), each point's disc lies in its
/// tangent plane: a screen offset `(dx, dy)` from the centre is on the plane at the depth
/// offset `g.(dx, dy)` pixels (`g` the point's depth gradient), and inside the disc when
/// `dx^2 + dy^2 + (c g.(dx, dy))^2 <= r^2` — an ellipse, thin where the surface turns away
/// (`c` = `SURFEL_SQUASH`).
/// Tilted discs join into a continuous depth across a sloping surface, where flat ones would
/// make a staircase. Without gradients the discs face the viewer at their point's depth.
pub fn splats(
    buf: &mut Visibility,
    verts: &[[f32; 3]],
    surfels: Option<(&[[f32; 2]], f32)>,
    radius: f32,
) {
    let (w, h) = (buf.width, buf.height);
    let r = radius.max(0.5);
    let bins = bin(verts.len(), h, |i| {
        let [x, y, z] = verts[i];
        if x + r < 0.0 || x - r > w as f32 || !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return None;
        }
        row_span(y - r, y + r, h)
    });
    let r2 = r * r;
    buf.depth
        .par_chunks_mut(BAND * w)
        .zip(buf.id.par_chunks_mut(BAND * w))
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(band, ((depth, id), pts))| {
            let y_lo = band * BAND;
            let y_hi = (y_lo + BAND).min(h) - 1;
            for &i in pts {
                let [x, y, z] = verts[i as usize];
                let ([gx, gy], unit) =
                    surfels.map_or(([0.0, 0.0], 0.0), |(g, u)| (g[i as usize], u));
                let py0 = ((y - r - 0.5).ceil().max(y_lo as f32)) as usize;
                let py1 = ((y + r - 0.5).floor().min(y_hi as f32)).max(-1.0);
                let px0 = ((x - r - 0.5).ceil().max(0.0)) as usize;
                let px1 = ((x + r - 0.5).floor().min(w as f32 - 1.0)).max(-1.0);
                if py1 < 0.0 || px1 < 0.0 {
                    continue;
                }
                for py in py0..=py1 as usize {
                    let dy = py as f32 + 0.5 - y;
                    let row = (py - y_lo) * w;
                    for px in px0..=px1 as usize {
                        let dx = px as f32 + 0.5 - x;
                        let dz = gx * dx + gy * dy;
                        let e = SURFEL_SQUASH * dz;
                        if dx * dx + dy * dy + e * e <= r2 {
                            let k = row + px;
                            let zp = z + dz * unit;
                            if zp < depth[k] {
                                depth[k] = zp;
                                id[k] = i;
                            }
                        }
                    }
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(buf: &Visibility, t: u32) -> usize {
        buf.id.iter().filter(|&&i| i == t).count()
    }

    #[test]
    fn square_of_two_triangles_has_no_cracks_or_overlaps() {
        // A 10x10 square at a non-integer offset split along its diagonal: exactly 100 pixel
        // centres fall inside, each covered once.
        let v = [
            [3.3, 2.7, 1.0],
            [13.3, 2.7, 1.0],
            [13.3, 12.7, 1.0],
            [3.3, 12.7, 1.0],
        ];
        let faces = [[0, 1, 2], [0, 2, 3]];
        let mut buf = Visibility::new(20, 40);
        triangles(&mut buf, &v, &faces);
        assert_eq!(count(&buf, 0) + count(&buf, 1), 100);
        // Same with both faces wound the other way (the rasterizer is two-sided).
        let mut buf = Visibility::new(20, 40);
        triangles(&mut buf, &v, &[[0, 2, 1], [0, 3, 2]]);
        assert_eq!(count(&buf, 0) + count(&buf, 1), 100);
    }

    #[test]
    fn fan_covers_each_pixel_once() {
        // A fan of 64 thin triangles around a centre: covered pixels are counted once, i.e. the
        // covered count equals that of the enclosing polygon rasterized as one fan of 2.
        let n = 64;
        let c = [50.2f32, 47.9, 0.0];
        let mut v = vec![c];
        for k in 0..n {
            let a = k as f32 / n as f32 * std::f32::consts::TAU;
            v.push([c[0] + 40.0 * a.cos(), c[1] + 40.0 * a.sin(), 0.0]);
        }
        let faces: Vec<[u32; 3]> = (0..n)
            .map(|k| [0, 1 + k as u32, 1 + ((k + 1) % n) as u32])
            .collect();
        let mut buf = Visibility::new(100, 100);
        triangles(&mut buf, &v, &faces);
        let covered = buf.id.iter().filter(|&&i| i != EMPTY).count();
        // Polygon area pi r^2 * sin(2pi/n)/(2pi/n) ~ 5015.
        let area = 0.5 * n as f64 * 1600.0 * (std::f64::consts::TAU / n as f64).sin();
        assert!(
            (covered as f64 - area).abs() < 0.02 * area,
            "{covered} vs {area}"
        );
        // Deterministic and each triangle visible somewhere.
        for t in 0..n as u32 {
            assert!(count(&buf, t) > 0);
        }
    }

    #[test]
    fn depth_test_keeps_the_nearest_and_interpolates() {
        // Two overlapping triangles; the second is nearer on the left, farther on the right.
        let v = [
            [0.0, 0.0, 5.0],
            [64.0, 0.0, 5.0],
            [0.0, 64.0, 5.0],
            [0.0, 0.0, 0.0],
            [64.0, 0.0, 10.0],
            [0.0, 64.0, 0.0],
        ];
        let mut buf = Visibility::new(64, 64);
        triangles(&mut buf, &v, &[[0, 1, 2], [3, 4, 5]]);
        // Depth of the second along y=0.5: z = 10 x / 64, crosses 5 at x = 32.
        assert_eq!(buf.id[10], 1);
        assert_eq!(buf.id[40], 0);
        assert!((buf.depth[10] - 10.5 * 10.0 / 64.0).abs() < 1e-4);
        // Threads do not matter.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut b1 = Visibility::new(64, 64);
        one.install(|| triangles(&mut b1, &v, &[[0, 1, 2], [3, 4, 5]]));
        assert_eq!(b1.id, buf.id);
    }

    #[test]
    fn off_screen_and_degenerate_are_skipped() {
        let v = [
            [-50.0, -50.0, 0.0],
            [-40.0, -50.0, 0.0],
            [-45.0, -40.0, 0.0],
            [5.0, 5.0, 0.0],
            [6.0, 6.0, 0.0],
            [7.0, 7.0, 0.0],
            [f32::NAN, 1.0, 0.0],
        ];
        let mut buf = Visibility::new(16, 16);
        triangles(&mut buf, &v, &[[0, 1, 2], [3, 4, 5], [6, 3, 4]]);
        assert!(buf.id.iter().all(|&i| i == EMPTY));
    }

    #[test]
    fn splats_are_discs_depth_tested() {
        let v = [[10.0, 10.0, 1.0], [12.0, 10.0, 0.5], [100.0, 100.0, 0.0]];
        let mut buf = Visibility::new(32, 32);
        splats(&mut buf, &v, None, 3.0);
        let a = count(&buf, 0);
        let b = count(&buf, 1);
        assert_eq!(count(&buf, 2), 0);
        // Disc of radius 3: ~28 pixels; point 1 is nearer and wins the overlap.
        assert!((25..=32).contains(&b), "{b}");
        assert!(a > 5 && a < b, "{a}");
    }
}
