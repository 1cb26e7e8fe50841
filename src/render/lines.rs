//! Depth-tested 3D polylines (patch boundaries, feature lines) drawn over a shaded picture.
//!
//! Each segment `a b` is projected; a pixel centre `p` at distance `d` from the projected
//! segment gets the line colour with coverage `clamp(w/2 + 1/2 - d, 0, 1)` (a one-pixel
//! linear ramp: anti-aliased edges). The line's depth at `p` is interpolated along the
//! segment, `z = z_a + t (z_b - z_a)`, with `t` the projection parameter; the pixel is drawn
//! when `z <= depth(p) + tolerance` (or nothing was rasterized there), so lines on the
//! surface show and lines behind it are hidden. The tolerance absorbs the gap between a curve
//! and the tessellation of the surface it lies on.

use super::camera::Camera;
use super::raster::Visibility;
use nalgebra::Point3;

/// How a polyline is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineStyle {
    /// sRGB colour.
    pub color: [u8; 3],
    /// Width in pixels (of the buffer drawn into).
    pub width: f32,
    /// How far (model units) a line may lie behind the surface and still show.
    pub depth_tolerance: f32,
}

/// Draws a polyline into `color` (the shaded picture at the visibility buffer's size).
pub fn draw_polyline_3d(
    color: &mut [[u8; 3]],
    vis: &Visibility,
    camera: &Camera,
    points: &[Point3<f64>],
    style: &LineStyle,
) {
    let proj: Vec<[f32; 3]> = points
        .iter()
        .map(|p| camera.project(p).map(|c| c as f32))
        .collect();
    for seg in proj.windows(2) {
        segment(color, vis, seg[0], seg[1], style);
    }
}

fn segment(color: &mut [[u8; 3]], vis: &Visibility, a: [f32; 3], b: [f32; 3], s: &LineStyle) {
    let (w, h) = (vis.width as i64, vis.height as i64);
    if !(a.iter().chain(b.iter()).all(|c| c.is_finite())) {
        return;
    }
    let hw = 0.5 * s.width.max(0.5);
    let reach = hw + 1.0;
    let x0 = ((a[0].min(b[0]) - reach).floor() as i64).max(0);
    let x1 = ((a[0].max(b[0]) + reach).ceil() as i64).min(w - 1);
    let y0 = ((a[1].min(b[1]) - reach).floor() as i64).max(0);
    let y1 = ((a[1].max(b[1]) + reach).ceil() as i64).min(h - 1);
    if x0 > x1 || y0 > y1 {
        return;
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let lc = s.color.map(|c| c as f32);
    for py in y0..=y1 {
        for px in x0..=x1 {
            let (qx, qy) = (px as f32 + 0.5 - a[0], py as f32 + 0.5 - a[1]);
            let t = if len2 > 0.0 {
                ((qx * dx + qy * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (ex, ey) = (qx - t * dx, qy - t * dy);
            let d = (ex * ex + ey * ey).sqrt();
            let cov = (hw + 0.5 - d).clamp(0.0, 1.0);
            if cov <= 0.0 {
                continue;
            }
            let k = (py * w + px) as usize;
            let z = a[2] + t * (b[2] - a[2]);
            if z > vis.depth[k] + s.depth_tolerance {
                continue;
            }
            let c = &mut color[k];
            for ch in 0..3 {
                c[ch] = (c[ch] as f32 + cov * (lc[ch] - c[ch] as f32)).round() as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::{UpAxis, View};

    #[test]
    fn lines_in_front_show_and_behind_hide() {
        // Front view, 1 px per unit, centre at the origin: screen x = 50 + x, y = 50 - y.
        let pts = [Point3::new(-50.0, -50.0, 0.0), Point3::new(50.0, 50.0, 0.0)];
        let cam = Camera::fit(View::Front, UpAxis::Y, pts.iter(), 0.0, 100.0, 100.0, 1.0).unwrap();
        let mut vis = Visibility::new(100, 100);
        // A "surface" at depth 0 over the left half.
        for y in 0..100 {
            for x in 0..50 {
                vis.depth[y * 100 + x] = 0.0;
                vis.id[y * 100 + x] = 0;
            }
        }
        let mut color = vec![[255u8; 3]; 100 * 100];
        let style = LineStyle {
            color: [0, 0, 0],
            width: 2.0,
            depth_tolerance: 0.1,
        };
        // Behind the surface (z = -5 is depth +5): hidden on the left, shown on the right.
        let line = [
            Point3::new(-40.0, 10.0, -5.0),
            Point3::new(40.0, 10.0, -5.0),
        ];
        draw_polyline_3d(&mut color, &vis, &cam, &line, &style);
        assert_eq!(color[40 * 100 + 20], [255; 3]);
        assert_eq!(color[40 * 100 + 80], [0; 3]);
        // On the surface: shown everywhere.
        let line = [
            Point3::new(-40.0, -10.0, 0.0),
            Point3::new(40.0, -10.0, 0.0),
        ];
        draw_polyline_3d(&mut color, &vis, &cam, &line, &style);
        assert_eq!(color[60 * 100 + 20], [0; 3]);
        assert_eq!(color[60 * 100 + 80], [0; 3]);
        // About two pixels thick, anti-aliased at the edge.
        let col: Vec<u8> = (55..65).map(|y| color[y * 100 + 30][0]).collect();
        assert_eq!(col.iter().filter(|&&c| c == 0).count(), 2, "{col:?}");
    }
}
