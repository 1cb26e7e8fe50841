//! Headless software rendering (no GPU, no window) of meshes, point clouds and tessellated
//! patch networks to PNG pictures, with deviation colours and patch-boundary lines.
//!
//! The pipeline of [`render_mesh`]:
//! 1. fit an orthographic [`Camera`] for the view so the object fills `fill` of the frame
//!    (left of the legend, when there is one);
//! 2. project the vertices at `supersample` times the output size;
//! 3. rasterize triangles (or splat points as discs) into a z-buffered visibility buffer
//!    ([`raster`]), in parallel horizontal bands;
//! 4. shade each visible pixel once ([`shade`]): interpolated normals, two-sided Lambert
//!    lighting with a key light, a headlight and ambient, deviation colours from a
//!    [`ColorScale`], outlines at silhouettes;
//! 5. draw the polylines (patch boundaries) with a depth test ([`lines`]);
//! 6. average each `supersample` x `supersample` block in linear light (anti-aliasing);
//! 7. draw the legend ([`legend`]) when there are scalars.
//!
//! Every stage is deterministic: the same input gives the same picture on any thread count.

pub mod camera;
pub mod cloud;
pub mod colormap;
pub mod focus;
pub mod font;
pub mod image;
pub mod legend;
pub mod lines;
pub mod patches;
pub mod raster;
pub mod shade;

pub use camera::{Camera, UpAxis, View};
pub use colormap::{ColorMap, ColorScale};
pub use image::{Image, ImageStats};

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use lines::LineStyle;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use shade::{Primitives, Shading};

/// How to render.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Picture size in pixels.
    pub width: u32,
    pub height: u32,
    pub view: View,
    /// Which model axis is up in the picture.
    pub up: UpAxis,
    /// sRGB colours: background, surface, back faces (seen through holes), lines.
    pub background: [u8; 3],
    pub base_color: [u8; 3],
    pub back_color: [u8; 3],
    pub line_color: [u8; 3],
    /// Line width in output pixels.
    pub line_width: f32,
    /// Splat radius in output pixels for point clouds; `None` picks it from the point spacing.
    pub point_radius: Option<f32>,
    /// Samples per pixel along each axis (1 = no anti-aliasing; 2 is the default).
    pub supersample: u32,
    /// Fraction of the frame the object's projection fills along its limiting side.
    pub fill: f64,
    /// Darken silhouettes and occluding contours.
    pub outline: bool,
    /// Title over the colour legend.
    pub legend_title: String,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1600,
            height: 1200,
            view: View::Iso,
            up: UpAxis::Y,
            background: [255, 255, 255],
            base_color: [200, 204, 212],
            back_color: [214, 150, 96],
            line_color: [20, 24, 40],
            line_width: 1.6,
            point_radius: None,
            supersample: 2,
            fill: 0.9,
            outline: true,
            legend_title: "deviation".into(),
        }
    }
}

/// Parses a picture size `WxH` (e.g. `1600x1200`).
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = || Error::InvalidOption(format!("size '{s}' is not WIDTHxHEIGHT, e.g. 1600x1200"));
    let (w, h) = s.split_once(['x', 'X', '*']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    check_size(w, h)?;
    Ok((w, h))
}

fn check_size(w: u32, h: u32) -> Result<()> {
    if !(16..=16384).contains(&w) || !(16..=16384).contains(&h) {
        return Err(Error::InvalidOption(format!(
            "picture size {w}x{h} is outside 16..16384 pixels per side"
        )));
    }
    Ok(())
}

impl RenderOptions {
    fn validate(&self) -> Result<()> {
        check_size(self.width, self.height)?;
        if !(1..=4).contains(&self.supersample) {
            return Err(Error::InvalidOption(format!(
                "supersample must be 1 to 4, got {}",
                self.supersample
            )));
        }
        if !(self.fill > 0.0 && self.fill <= 1.0) {
            return Err(Error::InvalidOption(format!(
                "fill must be in (0, 1], got {}",
                self.fill
            )));
        }
        if !(self.line_width.is_finite() && self.line_width > 0.0) {
            return Err(Error::InvalidOption("line width must be positive".into()));
        }
        let samples = (self.width as u64 * self.supersample as u64)
            * (self.height as u64 * self.supersample as u64);
        if samples > 1 << 27 {
            return Err(Error::InvalidOption(format!(
                "{}x{} pixels with {}x{} supersampling needs too much memory; \
                 lower the size or the supersampling",
                self.width, self.height, self.supersample, self.supersample
            )));
        }
        if let Some(r) = self.point_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::InvalidOption("point radius must be positive".into()));
            }
        }
        Ok(())
    }
}

/// Polylines drawn in one colour and width over the surface, where visible (a polyline of
/// one repeated point draws a dot: a corner).
#[derive(Debug, Clone, Copy)]
pub struct LineLayer<'a> {
    pub lines: &'a [Vec<Point3<f64>>],
    /// sRGB colour.
    pub color: [u8; 3],
    /// Width in output pixels.
    pub width: f32,
}

/// Renders a mesh (or, when it has no faces, a point cloud) with optional per-vertex scalars
/// (deviation) coloured by `scale` with a legend, and polylines (patch boundaries) drawn in
/// `opts.line_color` over the surface where visible.
pub fn render_mesh(
    mesh: &Mesh,
    scalars: Option<(&[f64], ColorScale)>,
    lines: &[Vec<Point3<f64>>],
    opts: &RenderOptions,
) -> Result<Image> {
    let layer = LineLayer {
        lines,
        color: opts.line_color,
        width: opts.line_width,
    };
    render_mesh_layers(mesh, scalars, &[layer], opts)
}

/// [`render_mesh`] with several layers of lines (patch boundaries, then creases and corners
/// over them), each in its own colour and width; later layers are drawn over earlier ones.
pub fn render_mesh_layers(
    mesh: &Mesh,
    scalars: Option<(&[f64], ColorScale)>,
    layers: &[LineLayer],
    opts: &RenderOptions,
) -> Result<Image> {
    opts.validate()?;
    let n = mesh.positions.len();
    if n == 0 {
        return Err(Error::Degenerate("nothing to render: no vertices".into()));
    }
    if let Some((s, _)) = scalars {
        if s.len() != n {
            return Err(Error::InvalidOption(format!(
                "{} scalar values for {} vertices",
                s.len(),
                n
            )));
        }
    }
    if let Some(f) = mesh
        .faces
        .iter()
        .find(|f| f.iter().any(|&v| v as usize >= n))
    {
        return Err(Error::Degenerate(format!(
            "face {f:?} indexes past the {n} vertices"
        )));
    }
    let (w, h) = (opts.width, opts.height);
    let legend = scalars.map(|(_, sc)| legend::LegendLayout::new(w, h, &sc, &opts.legend_title));
    let avail = w - legend.as_ref().map_or(0, |l| l.reserved_width);

    // 1. Camera, fitted to the points that are drawn (a mesh's unused vertices are debris).
    let used = if mesh.faces.is_empty() {
        vec![true; n]
    } else {
        mesh.referenced()
    };
    let fit_points = mesh
        .positions
        .iter()
        .zip(&used)
        .filter(|(_, &u)| u)
        .map(|(p, _)| p)
        .chain(layers.iter().flat_map(|l| l.lines.iter().flatten()));
    let cam_out = Camera::fit(
        opts.view,
        opts.up,
        fit_points,
        0.0,
        avail as f64,
        h as f64,
        opts.fill,
    )?;
    let ss = opts.supersample as usize;
    let cam = cam_out.scaled(ss as f64);
    let (sw, sh) = (w as usize * ss, h as usize * ss);

    // 2. Projection.
    let screen: Vec<[f32; 3]> = mesh
        .positions
        .par_iter()
        .map(|p| cam.project(p).map(|c| c as f32))
        .collect();
    let depth_range = {
        let (lo, hi) = screen
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .fold((f32::MAX, f32::MIN), |(lo, hi), (s, _)| {
                (lo.min(s[2]), hi.max(s[2]))
            });
        (hi - lo).max(0.0)
    };

    // 3. Visibility, and 4. shading inputs.
    let mut vis = raster::Visibility::new(sw, sh);
    let to_cam = |v: &Vector3<f64>| cam.to_camera(v).map(|c| c as f32);
    let shaded = if mesh.faces.is_empty() {
        let need_normals = !valid_normals(mesh);
        let (est, spacing) = if need_normals || opts.point_radius.is_none() {
            cloud::normals_and_spacing(&mesh.positions, need_normals)?
        } else {
            (Vec::new(), 0.0)
        };
        let normals: Vec<Vector3<f32>> = match (&mesh.normals, need_normals) {
            (Some(nm), false) => nm.par_iter().map(to_cam).collect(),
            _ => est.par_iter().map(to_cam).collect(),
        };
        let radius = match opts.point_radius {
            Some(r) => r * ss as f32,
            None => auto_radius(spacing, cam.scale, sw.max(sh), ss),
        };
        // Surfels: the tangent plane of normal n (camera frame, turned toward the viewer)
        // rises d(depth) = (n_x dx - n_y dy) / n_z pixels for a screen offset (dx, dy)
        // (y down); n_z >= 0.2 caps the tilt.
        let gradients: Vec<[f32; 2]> = normals
            .par_iter()
            .map(|n| {
                let n = if n.z < 0.0 { -n } else { *n };
                if n.norm_squared() == 0.0 {
                    return [0.0, 0.0];
                }
                let nz = n.z.max(0.2);
                [n.x / nz, -n.y / nz]
            })
            .collect();
        raster::splats(
            &mut vis,
            &screen,
            Some((&gradients, 1.0 / cam.scale as f32)),
            radius,
        );
        shade::shade(
            &vis,
            &Shading {
                prims: Primitives::Points,
                normals: &normals,
                scalars,
                base: opts.base_color,
                back: opts.back_color,
                background: opts.background,
                scale: cam.scale as f32,
                outline: if opts.outline { ss } else { 0 },
                // A disc's rim leaves a curved surface by its sagitta; only jumps well beyond
                // half a radius are contours.
                outline_slope: shade::OUTLINE_SLOPE.max(0.5 * radius),
            },
        )
    } else {
        raster::triangles(&mut vis, &screen, &mesh.faces);
        let normals: Vec<Vector3<f32>> = if valid_normals(mesh) {
            mesh.normals.iter().flatten().map(to_cam).collect()
        } else {
            crate::mesh::normals::vertex_normals(mesh)
                .par_iter()
                .map(to_cam)
                .collect()
        };
        // A face faces the viewer when its (counter-clockwise) normal has a positive z in
        // the camera frame.
        let front: Vec<bool> = (0..mesh.faces.len())
            .into_par_iter()
            .map(|f| cam.to_camera(&mesh.face_cross(f)).z >= 0.0)
            .collect();
        shade::shade(
            &vis,
            &Shading {
                prims: Primitives::Triangles {
                    faces: &mesh.faces,
                    screen: &screen,
                    front: &front,
                },
                normals: &normals,
                scalars,
                base: opts.base_color,
                back: opts.back_color,
                background: opts.background,
                scale: cam.scale as f32,
                outline: if opts.outline { ss } else { 0 },
                outline_slope: shade::OUTLINE_SLOPE,
            },
        )
    };
    let mut color = shaded;

    // 5. Lines.
    for layer in layers {
        let style = LineStyle {
            color: layer.color,
            width: layer.width * ss as f32,
            depth_tolerance: 0.004 * depth_range + 2.0 / cam.scale as f32,
        };
        for l in layer.lines {
            if l.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(Error::Degenerate(
                    "a line to draw has a non-finite point".into(),
                ));
            }
            lines::draw_polyline_3d(&mut color, &vis, &cam, l, &style);
        }
    }

    // 6. Downsampling, 7. legend.
    let mut img = downsample(&color, sw, sh, ss);
    if let (Some(l), Some((_, sc))) = (legend, scalars) {
        l.draw(&mut img, &sc);
    }
    Ok(img)
}

/// True when the mesh carries one finite, non-zero normal per vertex.
fn valid_normals(mesh: &Mesh) -> bool {
    mesh.normals.as_ref().is_some_and(|nm| {
        nm.len() == mesh.positions.len()
            && nm
                .iter()
                .all(|v| v.iter().all(|c| c.is_finite()) && v.norm_squared() > 0.0)
    })
}

/// Splat radius (buffer pixels) for points `spacing` apart: large enough that neighbouring
/// discs overlap into a closed surface, bounded to stay between a pixel and 1.5% of the
/// picture.
fn auto_radius(spacing: f64, scale: f64, size: usize, ss: usize) -> f32 {
    let r = 1.1 * spacing * scale;
    let r = if r.is_finite() { r } else { 0.0 };
    r.clamp(0.75 * ss as f64, 0.015 * size as f64) as f32
}

/// Averages `ss` x `ss` blocks in linear light.
fn downsample(color: &[[u8; 3]], sw: usize, sh: usize, ss: usize) -> Image {
    let (w, h) = (sw / ss, sh / ss);
    if ss == 1 {
        return Image {
            width: w as u32,
            height: h as u32,
            pixels: color.to_vec(),
        };
    }
    let lut: Vec<f32> = (0..=255u8).map(shade::srgb_to_linear).collect();
    let enc = shade::SrgbEncoder::new();
    let inv = 1.0 / (ss * ss) as f32;
    let mut pixels = vec![[0u8; 3]; w * h];
    pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            let mut acc = [0f32; 3];
            for dy in 0..ss {
                let base = (y * ss + dy) * sw + x * ss;
                for c in &color[base..base + ss] {
                    for k in 0..3 {
                        acc[k] += lut[c[k] as usize];
                    }
                }
            }
            *px = acc.map(|a| enc.encode(a * inv));
        }
    });
    Image {
        width: w as u32,
        height: h as u32,
        pixels,
    }
}

#[cfg(test)]
mod tests;
