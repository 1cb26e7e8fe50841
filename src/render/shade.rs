//! Shading of a visibility buffer, once per visible pixel.
//!
//! Lighting, in the camera frame (x right, y up, z toward the viewer), on linear-light
//! colours, encoded to sRGB at the end:
//!
//! `c = albedo (a (0.8 + 0.2 n_y) + k max(0, n.l) + e max(0, n_z)) + s max(0, n.h)^40`
//!
//! with a key light `l` from the upper left front, a headlight along z (so nothing facing the
//! viewer is black), a small ambient `a` brighter from above, and a Blinn highlight (`h` the
//! half vector of `l` and the view direction). Surfaces are lit two-sided: a triangle seen
//! from behind (the inside of an open mesh) uses its flipped normal and a warm "back face"
//! albedo so holes read as holes; point normals (sign unknown) are turned toward the viewer.
//!
//! A triangle pixel interpolates the vertex normals (and the scalar, for deviation colours)
//! with the screen-space barycentric coordinates, exact for an orthographic camera. A pixel
//! on the near side of a depth jump (beyond `OUTLINE_SLOPE` pixels of depth per pixel more
//! than the surface's own slope) or next to the background is darkened: silhouettes and
//! occluding contours get an outline.

use super::colormap::ColorScale;
use super::raster::{Visibility, EMPTY};
use nalgebra::Vector3;
use rayon::prelude::*;

const AMBIENT: f32 = 0.16;
const KEY: f32 = 0.62;
const HEAD: f32 = 0.30;
const SPECULAR: f32 = 0.12;
const SHININESS: i32 = 40;
/// Depth change (in pixel widths) per pixel beyond which a neighbour counts as "behind", for
/// triangles (points pass their own, see `Shading::outline_slope`).
pub const OUTLINE_SLOPE: f32 = 4.0;
/// Outline pixels keep this fraction of their light.
const OUTLINE_KEEP: f32 = 0.25;

/// What is being shaded.
pub enum Primitives<'a> {
    /// Triangles: faces, their vertices on screen, and which faces face the viewer.
    Triangles {
        faces: &'a [[u32; 3]],
        screen: &'a [[f32; 3]],
        front: &'a [bool],
    },
    /// Points (one pixel id per point).
    Points,
}

/// Everything the shading pass reads.
pub struct Shading<'a> {
    pub prims: Primitives<'a>,
    /// Unit normals per vertex (or point) in the camera frame; zero when unknown.
    pub normals: &'a [Vector3<f32>],
    /// Per-vertex scalar with its scale (NaN: no value, drawn in the base colour).
    pub scalars: Option<(&'a [f64], ColorScale)>,
    /// sRGB albedos of front and back faces, and the background.
    pub base: [u8; 3],
    pub back: [u8; 3],
    pub background: [u8; 3],
    /// Pixels per model unit (of the buffer), for the outline's depth threshold.
    pub scale: f32,
    /// Outline width in pixels (0: no outline).
    pub outline: usize,
    /// Depth jump (pixels per pixel, beyond the surface's slope) that draws an outline.
    pub outline_slope: f32,
}

/// sRGB 8-bit to linear.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear to sRGB 8-bit through a 4096-entry table (a `powf` per channel per pixel is the
/// slowest part of shading otherwise).
pub struct SrgbEncoder {
    table: Vec<u8>,
}

impl Default for SrgbEncoder {
    fn default() -> Self {
        SrgbEncoder::new()
    }
}

impl SrgbEncoder {
    const N: usize = 4096;
    pub fn new() -> SrgbEncoder {
        let table = (0..Self::N)
            .map(|i| {
                let l = i as f32 / (Self::N - 1) as f32;
                let s = if l <= 0.003_130_8 {
                    12.92 * l
                } else {
                    1.055 * l.powf(1.0 / 2.4) - 0.055
                };
                (s * 255.0).round().clamp(0.0, 255.0) as u8
            })
            .collect();
        SrgbEncoder { table }
    }
    #[inline]
    pub fn encode(&self, l: f32) -> u8 {
        let i = (l.clamp(0.0, 1.0) * (Self::N - 1) as f32 + 0.5) as usize;
        self.table[i.min(Self::N - 1)]
    }
}

/// Light reaching the eye from a surface of albedo `albedo` (linear) with normal `n`.
#[inline]
fn light(n: Vector3<f32>, albedo: [f32; 3]) -> [f32; 3] {
    let key = Vector3::new(-0.45f32, 0.65, 0.62).normalize();
    let half = (key + Vector3::z()).normalize();
    let diffuse = AMBIENT * (0.8 + 0.2 * n.y) + KEY * n.dot(&key).max(0.0) + HEAD * n.z.max(0.0);
    let spec = SPECULAR * n.dot(&half).max(0.0).powi(SHININESS);
    albedo.map(|a| a * diffuse + spec)
}

/// Shades the buffer into sRGB pixels of the same size.
pub fn shade(vis: &Visibility, s: &Shading) -> Vec<[u8; 3]> {
    let (w, h) = (vis.width, vis.height);
    let enc = SrgbEncoder::new();
    let lin = |c: [u8; 3]| c.map(srgb_to_linear);
    let (base, back) = (lin(s.base), lin(s.back));
    // Per-vertex positions on the colour map, as f32 (NaN where there is no value).
    let tmap: Option<(Vec<f32>, ColorScale)> = s
        .scalars
        .map(|(v, sc)| (v.iter().map(|&x| sc.t(x) as f32).collect(), sc));
    let slope = s.outline_slope / s.scale.max(f32::MIN_POSITIVE);
    let mut out = vec![s.background; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            let k = y * w + x;
            let id = vis.id[k];
            if id == EMPTY {
                continue;
            }
            let (n, t, facing) = match &s.prims {
                Primitives::Triangles {
                    faces,
                    screen,
                    front,
                } => {
                    let f = faces[id as usize];
                    let l = barycentric(screen, f, x as f32 + 0.5, y as f32 + 0.5);
                    let n = l[0] * s.normals[f[0] as usize]
                        + l[1] * s.normals[f[1] as usize]
                        + l[2] * s.normals[f[2] as usize];
                    let t = tmap.as_ref().map(|(tv, _)| {
                        l[0] * tv[f[0] as usize]
                            + l[1] * tv[f[1] as usize]
                            + l[2] * tv[f[2] as usize]
                    });
                    let facing = front[id as usize];
                    (if facing { n } else { -n }, t, facing)
                }
                Primitives::Points => {
                    let n = s.normals[id as usize];
                    let t = tmap.as_ref().map(|(tv, _)| tv[id as usize]);
                    (if n.z < 0.0 { -n } else { n }, t, true)
                }
            };
            let len = n.norm();
            let n = if len > 1e-12 && len.is_finite() {
                n / len
            } else {
                Vector3::z()
            };
            let albedo = match (t, &tmap) {
                (Some(t), Some((_, sc))) if t.is_finite() => sc
                    .map
                    .srgb(t as f64)
                    .map(|c| srgb_to_linear((c * 255.0).round() as u8)),
                _ if facing => base,
                _ => back,
            };
            let mut c = light(n, albedo);
            if s.outline > 0 && is_edge(vis, x, y, s.outline, slope) {
                c = c.map(|v| v * OUTLINE_KEEP);
            }
            *px = c.map(|v| enc.encode(v));
        }
    });
    out
}

/// Screen-space barycentric coordinates of (`px`, `py`) in face `f`, clamped to the triangle.
#[inline]
fn barycentric(screen: &[[f32; 3]], f: [u32; 3], px: f32, py: f32) -> [f32; 3] {
    let [a, b, c] = f.map(|i| screen[i as usize]);
    let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
    let (acx, acy) = (c[0] - a[0], c[1] - a[1]);
    let (apx, apy) = (px - a[0], py - a[1]);
    let d = abx * acy - aby * acx;
    if d.abs() < 1e-12 {
        return [1.0 / 3.0; 3];
    }
    let l1 = ((apx * acy - apy * acx) / d).clamp(0.0, 1.0);
    let l2 = ((abx * apy - aby * apx) / d).clamp(0.0, 1.0);
    let s = l1 + l2;
    let (l1, l2) = if s > 1.0 { (l1 / s, l2 / s) } else { (l1, l2) };
    [1.0 - l1 - l2, l1, l2]
}

/// True when a neighbour within `reach` pixels (4-connected directions) is background, or
/// lies behind this pixel by more than `slope` model units per pixel of distance beyond the
/// depth extrapolated linearly from the opposite neighbour. Extrapolating (a second
/// difference) keeps smooth surfaces seen at grazing angles, whose depth changes fast but
/// steadily, free of outline; only real jumps (occluding contours) and silhouettes are marked.
#[inline]
fn is_edge(vis: &Visibility, x: usize, y: usize, reach: usize, slope: f32) -> bool {
    let (w, h) = (vis.width as i64, vis.height as i64);
    let z = vis.depth[y * vis.width + x];
    let at = |dx: i64, dy: i64| -> Option<usize> {
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        (nx >= 0 && ny >= 0 && nx < w && ny < h).then_some((ny * w + nx) as usize)
    };
    for d in 1..=reach as i64 {
        for (dx, dy) in [(d, 0), (-d, 0), (0, d), (0, -d)] {
            let Some(q) = at(dx, dy) else { continue };
            if vis.id[q] == EMPTY {
                return true;
            }
            let expect = match at(-dx, -dy) {
                Some(r) if vis.id[r] != EMPTY => 2.0 * z - vis.depth[r],
                _ => z,
            };
            if vis.depth[q] - expect > slope * d as f32 {
                return true;
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lighting_varies_with_the_normal() {
        let a = [0.5f32; 3];
        let facing = light(Vector3::z(), a)[0];
        let grazing = light(Vector3::new(1.0, 0.0, 0.05).normalize(), a)[0];
        let toward_key = light(Vector3::new(-0.45, 0.65, 0.62).normalize(), a)[0];
        assert!(toward_key > facing && facing > grazing && grazing > 0.0);
    }

    #[test]
    fn srgb_round_trips() {
        let e = SrgbEncoder::new();
        for c in 0..=255u8 {
            assert_eq!(e.encode(srgb_to_linear(c)), c);
        }
    }

    #[test]
    fn barycentrics_reproduce_the_point() {
        let s = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]];
        let l = barycentric(&s, [0, 1, 2], 2.0, 3.0);
        assert!(
            (l[0] - 0.5).abs() < 1e-6 && (l[1] - 0.2).abs() < 1e-6 && (l[2] - 0.3).abs() < 1e-6
        );
        let l = barycentric(&s, [0, 1, 2], 20.0, 20.0);
        assert!(l.iter().all(|v| (0.0..=1.0).contains(v)));
    }
}
