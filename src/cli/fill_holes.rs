//! `scansurf fill-holes INPUT -o OUT [--method rbf|planar] [--max-size L] [--rings K] ...`.

use crate::error::{Error, Result};
use crate::holes::{fill_holes, FillMethod, FillOptions};
use nalgebra::Vector3;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Triangle mesh with holes (.ply .obj .stl).
    pub input: PathBuf,
    /// Output mesh: every original vertex and face unchanged and first, the fill after.
    #[arg(short, long)]
    pub output: PathBuf,
    /// rbf: local thin-plate RBF surface through the hole's ring (seed 000);
    /// planar: Delaunay fill of the projected loop with circular-arc subdivision (seed 002);
    /// flat: the planar fill without the arcs (a baseline).
    #[arg(long, default_value = "rbf")]
    pub method: String,
    /// Leave holes larger than this (bounding-box diagonal of the ring, model units) open.
    #[arg(long, value_name = "L")]
    pub max_size: Option<f64>,
    /// Fill the outer border of an open sheet too (by default it is kept open).
    #[arg(long)]
    pub fill_border: bool,
    /// Rings of triangles around a hole whose vertices the RBF interpolates.
    #[arg(long, value_name = "K")]
    pub rings: Option<usize>,
    /// Projection direction x,y,z to try first for the planar method.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub direction: Option<String>,
    /// Do not fall back to the other method when one fails on a hole.
    #[arg(long)]
    pub no_fallback: bool,
    /// Write the per-hole report (size, method, triangles added, deviation, time) as JSON here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write PLY/STL as text.
    #[arg(long)]
    pub ascii: bool,
}

fn parse_direction(s: &str) -> Result<Vector3<f64>> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::InvalidOption(format!("--direction {s}: expected x,y,z")))?;
    if v.len() != 3 || !v.iter().all(|c| c.is_finite()) {
        return Err(Error::InvalidOption(format!(
            "--direction {s}: expected x,y,z"
        )));
    }
    let d = Vector3::new(v[0], v[1], v[2]);
    d.try_normalize(1e-300)
        .ok_or_else(|| Error::InvalidOption("--direction must not be zero".into()))
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    let method: FillMethod = a.method.parse()?;
    let mesh = crate::io::read_mesh(&a.input)?;
    if mesh.faces.is_empty() {
        return Err(Error::content(
            &a.input,
            "is a point cloud; fill-holes needs a triangle mesh (use reconstruct for clouds)",
        ));
    }
    let mut opts = FillOptions {
        method,
        max_size: a.max_size,
        keep_border: !a.fill_border,
        fallback: !a.no_fallback,
        ..FillOptions::default()
    };
    if let Some(k) = a.rings {
        opts.rbf.rings = k;
    }
    if let Some(d) = &a.direction {
        opts.direction = Some(parse_direction(d)?);
    }
    let spinner = super::progress::spinner("filling holes", quiet);
    let (out, report) = fill_holes(&mesh, &opts).map_err(|e| super::with_input(e, &a.input))?;
    spinner.finish_and_clear();
    crate::io::write_mesh(&a.output, &out, crate::io::WriteOptions { ascii: a.ascii })?;
    if let Some(r) = &a.report {
        super::write_json(r, &report)?;
    }
    if !quiet {
        eprintln!(
            "filled {} of {} holes in {} ({} left open, {} failed; {} triangles added, fill faces from index {}) in {:.2} s -> {}",
            report.holes_filled,
            report.loops,
            a.input.display(),
            report.holes_left_open,
            report.holes_failed,
            report.triangles_added,
            mesh.faces.len(),
            report.time_s,
            a.output.display()
        );
    }
    Ok(())
}
