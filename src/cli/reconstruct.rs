//! `scansurf reconstruct INPUT -o OUT.(ply|obj|stl) [--resolution N] [--tolerance T] [--report R]`.

use crate::error::{Error, Result};
use crate::features::SharpMode;
use crate::reconstruct::{reconstruct, ReconstructOptions};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Point cloud or mesh with holes (.ply .obj .stl .xyz .e57 .las .laz ...).
    pub input: PathBuf,
    /// Closed, manifold, outward-oriented triangle mesh (.ply .obj .stl).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Marching-cubes cube edge as a multiple of the mean point spacing (smaller = finer).
    #[arg(long, default_value_t = 1.0)]
    pub resolution: f64,
    /// Largest gap between mesh and implicit surface, as a fraction of the bounding-box
    /// diagonal (default: three times the fit tolerance).
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Fitting tolerance of the implicit at the input points, as a fraction of the diagonal.
    #[arg(long, default_value_t = 2e-4)]
    pub fit_tolerance: f64,
    /// Subsample point clouds above this many points (voxel grid) on read.
    #[arg(long)]
    pub max_points: Option<usize>,
    /// Write the report (counts, cells, deviation of the input points, timings) as JSON here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write PLY/STL as text.
    #[arg(long)]
    pub ascii: bool,
    /// Keep sharp edges: find the smooth regions and creases first (as `scansurf features`)
    /// and fit one function per region in the cells a crease crosses. `auto`: when the input
    /// looks machined (a quarter of its points outside its largest smooth region); `on`:
    /// whenever it has creases (`--sharp` alone means `on`); `off`: round every edge. Inputs
    /// with one smooth region (organic scans) come out the same in every mode.
    #[arg(long, value_enum, default_value_t = SharpMode::Auto, num_args = 0..=1,
          default_missing_value = "on", value_name = "on|off|auto")]
    pub sharp: SharpMode,
    /// With the sharp edges kept: remesh the result into a light mesh (tens of thousands of
    /// triangles instead of a million) whose edges run on the creases and whose vertices lie
    /// on the faces' surfaces, finer where a face or a crease curves. Off by default.
    #[arg(long)]
    pub remesh: bool,
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    crate::io::Format::from_path(&a.output).and_then(|f| match f {
        crate::io::Format::Ply | crate::io::Format::Obj | crate::io::Format::Stl => Ok(()),
        _ => Err(Error::unsupported(
            &a.output,
            "reconstruct writes a triangle mesh: .ply, .obj or .stl",
        )),
    })?;
    let mut input = crate::io::read_mesh(&a.input)?;
    if let Some(max) = a.max_points {
        input = crate::mesh::subsample::limit_points(input, max)?;
    }
    let mut opts = ReconstructOptions {
        resolution: a.resolution,
        tolerance: a.tolerance,
        sharp: a.sharp,
        remesh: a.remesh,
        ..ReconstructOptions::default()
    };
    opts.fit.tolerance = a.fit_tolerance;
    let bar = super::progress::bar("reconstruct", 100, quiet);
    let mut progress = |stage: &str, frac: f64| {
        bar.set_message(stage.to_string());
        bar.set_prefix(stage.to_string());
        bar.set_position((frac.clamp(0.0, 1.0) * 100.0) as u64);
    };
    let (mesh, report) =
        reconstruct(&input, &opts, &mut progress).map_err(|e| super::with_input(e, &a.input))?;
    bar.finish_and_clear();
    crate::io::write_mesh(&a.output, &mesh, crate::io::WriteOptions { ascii: a.ascii })?;
    if let Some(r) = &a.report {
        super::write_json(r, &report)?;
    }
    if !quiet {
        let dev = report
            .deviation
            .as_ref()
            .map(|d| {
                format!(
                    ", deviation mean {:.2e} max {:.2e} of the diagonal",
                    d.relative.mean, d.relative.max
                )
            })
            .unwrap_or_default();
        eprintln!(
            "reconstructed {} -> {}: {} vertices, {} faces, {}{} in {:.2} s",
            a.input.display(),
            a.output.display(),
            report.vertices,
            report.faces,
            if report.closed_manifold {
                "closed manifold"
            } else {
                "NOT closed manifold"
            },
            dev,
            report.timings.total
        );
        if let Some(c) = report.sharp.as_ref().filter(|c| c.regions > 1) {
            let kept = if c.sharp { "kept" } else { "rounded" };
            eprintln!("sharp edges {kept}: {}", c.reason);
        }
        if report.triangles.degenerate > 0 {
            eprintln!(
                "warning: {} degenerate triangles (smallest angle under {} degrees) in {}",
                report.triangles.degenerate,
                crate::mesh::shape::DEGENERATE_ANGLE_DEG,
                a.output.display()
            );
        }
        if a.remesh && report.remesh.is_none() {
            eprintln!("--remesh: no sharp edges kept, so the mesh was not remeshed");
        }
    }
    Ok(())
}
