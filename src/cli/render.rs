//! `scansurf render INPUT -o OUT.png [--against CLOUD | --deviation D.ply] [--view iso|front|top|side] [--size WxH]`.
//!
//! INPUT is a mesh or point cloud, or a STEP model of B-spline faces (`.step`/`.stp`, read by
//! [`crate::io::step`]): its faces are tessellated and shaded and each face's parameter-domain
//! boundary is drawn as a dark line, showing the patch network.

use crate::error::{Error, Result};
use crate::render::{self, ColorScale, RenderOptions, UpAxis, View};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh, point cloud (.ply .obj .stl .xyz .e57 .las .laz ...) or STEP model of B-spline
    /// faces (.step .stp) to draw; STEP faces get their patch boundaries as dark lines.
    pub input: PathBuf,
    /// PNG to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Colour the input's vertices by their distance to the nearest point of this cloud, with a
    /// legend in model units.
    #[arg(long, value_name = "CLOUD")]
    pub against: Option<PathBuf>,
    /// Colour the input by the deviation of the scan points stored in this `fit
    /// --deviation-ply` file (each surface point takes the inverse-distance weighted
    /// value of its 8 nearest scan points; scale 0 to the 99th percentile), with a legend.
    #[arg(long, value_name = "D.ply", conflicts_with = "against")]
    pub deviation: Option<PathBuf>,
    /// iso, front, top, side, bottom or back.
    #[arg(long, default_value = "iso")]
    pub view: String,
    /// Model axis pointing up in the picture: y (scans, default) or z (CAD).
    #[arg(long, default_value = "y")]
    pub up: String,
    /// Picture size WxH in pixels.
    #[arg(long, default_value = "1600x1200")]
    pub size: String,
    /// Draw only what lies within R of (X, Y, Z), framed to fill the picture: e.g. a spot the
    /// `fit` report lists among its largest normal jumps.
    #[arg(long, value_name = "X,Y,Z,R", allow_hyphen_values = true)]
    pub focus: Option<String>,
    /// Draw the creases (red) and corners (blue) of this `scansurf features` file over the
    /// model.
    #[arg(long, value_name = "FEATURES.json")]
    pub features: Option<PathBuf>,
    /// Subsample point clouds above this many points (voxel grid) before drawing.
    #[arg(long)]
    pub max_points: Option<usize>,
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if ext.as_deref() != Some("png") {
        return Err(Error::unsupported(
            &a.output,
            "render writes PNG: name the output .png",
        ));
    }
    let (width, height) = render::parse_size(&a.size)?;
    let view: View = a.view.parse()?;
    let up: UpAxis = a.up.parse()?;
    let focus = match &a.focus {
        Some(f) => Some(f.parse::<render::focus::Focus>()?),
        None => None,
    };
    let (mut mesh, lines) = if is_step(&a.input) {
        let model = crate::io::step::read_step(&a.input)?;
        let faces: Vec<render::patches::FaceRef> = model
            .faces
            .iter()
            .map(|f| render::patches::FaceRef {
                surface: &f.surface,
                same_sense: f.same_sense,
            })
            .collect();
        render::patches::tessellate_faces(&faces, render::patches::resolution(faces.len()))
    } else {
        (crate::io::read_mesh(&a.input)?, Vec::new())
    };
    if let Some(max) = a.max_points {
        mesh = crate::mesh::subsample::limit_points(mesh, max)?;
    }
    // Creases as polylines, corners as dots (a polyline of one repeated point).
    let (creases, corners) = match &a.features {
        Some(p) => {
            let (c, k) = crate::features::export::read_lines_json(p)?;
            (c, k.into_iter().map(|p| vec![p, p]).collect())
        }
        None => (Vec::new(), Vec::new()),
    };
    // A STEP model's open boundary (sides no other face shares), over its patch boundaries.
    let open = render::patches::open_sides(&lines);
    let (mesh, lines, creases, corners, open) = match &focus {
        Some(f) => {
            let (mesh, lines) = f.crop(mesh, &lines)?;
            let (cr, co) = (f.crop_lines(&creases), f.crop_lines(&corners));
            (mesh, lines, cr, co, f.crop_lines(&open))
        }
        None => (mesh, lines, creases, corners, open),
    };
    let opts = RenderOptions {
        width,
        height,
        view,
        up,
        ..RenderOptions::default()
    };
    let spinner = super::progress::spinner("rendering", quiet);
    let scalars = match (&a.against, &a.deviation) {
        (Some(c), _) => {
            let cloud = crate::io::read_mesh(c)?;
            let d = nearest_distances(&mesh, &cloud.positions)
                .map_err(|e| Error::content(c, e.to_string()))?;
            let scale = ColorScale::auto(&d)?;
            Some((d, scale))
        }
        (None, Some(dp)) => {
            let (points, dev) = crate::io::ply::read_scalar_cloud(dp, "quality")?;
            let coloured = render::patches::point_deviation_colours(&mesh.positions, &points, &dev)
                .map_err(|e| Error::content(dp, e.to_string()))?;
            let Some(c) = coloured else {
                return Err(Error::content(dp, "no finite deviation value"));
            };
            Some(c)
        }
        (None, None) => None,
    };
    let mut opts = opts;
    if a.deviation.is_some() {
        opts.legend_title = "point deviation".into();
    }
    let mut layers = render::patches::outline_layers(&lines, &open, &opts).to_vec();
    layers.extend([
        render::LineLayer {
            lines: &creases,
            color: crate::features::export::CREASE_COLOUR,
            width: 2.5 * opts.line_width,
        },
        render::LineLayer {
            lines: &corners,
            color: crate::features::export::CORNER_COLOUR,
            width: 6.0 * opts.line_width,
        },
    ]);
    let img = match scalars {
        Some((d, scale)) => render::render_mesh_layers(&mesh, Some((&d, scale)), &layers, &opts)?,
        None => render::render_mesh_layers(&mesh, None, &layers, &opts)?,
    };
    img.save_png(&a.output)?;
    spinner.finish_and_clear();
    if !quiet {
        eprintln!(
            "rendered {} ({} view, {}x{}) -> {}",
            a.input.display(),
            a.view,
            width,
            height,
            a.output.display()
        );
    }
    Ok(())
}

/// Whether the path names a STEP file (.step, .stp).
fn is_step(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("step") || e.eq_ignore_ascii_case("stp"))
}

/// Distance from every vertex of `mesh` to the nearest point of `cloud`.
fn nearest_distances(mesh: &crate::Mesh, cloud: &[nalgebra::Point3<f64>]) -> Result<Vec<f64>> {
    use rayon::prelude::*;
    let tree = crate::spatial::KdTree::build(cloud)?;
    Ok(mesh
        .positions
        .par_iter()
        .map(|p| tree.nearest(p).1)
        .collect())
}
