//! `scansurf features INPUT -o FEATURES.json [--ply CREASES.ply] [--regions-ply REGIONS.ply]`.

use super::progress;
use crate::error::{Error, Result};
use crate::features::{detect, export, DetectOptions};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh or point cloud (.ply .obj .stl .xyz .txt .pts .csv .e57 .las .laz).
    pub input: PathBuf,
    /// The features as JSON: noise, regions, creases (polylines with their angle), corners.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the creases as polylines (PLY edges, red) and the corners (blue points).
    #[arg(long, value_name = "CREASES.ply")]
    pub ply: Option<PathBuf>,
    /// Also write the input points coloured by smooth region, with a `region` property.
    #[arg(long, value_name = "REGIONS.ply")]
    pub regions_ply: Option<PathBuf>,
    /// Faces meeting at a smaller angle are one smooth surface, degrees (default 20).
    #[arg(long, value_name = "DEG")]
    pub angle: Option<f64>,
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    super::check_ext(&a.output, &["json"], "the features output")?;
    if let Some(p) = &a.ply {
        super::check_ext(p, &["ply"], "the creases file (--ply)")?;
    }
    if let Some(p) = &a.regions_ply {
        super::check_ext(p, &["ply"], "the regions file (--regions-ply)")?;
    }
    let mut opts = DetectOptions::default();
    if let Some(angle) = a.angle {
        if !(angle > 0.0 && angle < 180.0) {
            return Err(Error::InvalidOption(format!(
                "--angle must be between 0 and 180 degrees, not {angle}"
            )));
        }
        opts.angle_deg = angle;
    }
    let input = crate::io::read_mesh(&a.input)?;
    let spinner = progress::spinner("finding creases", quiet);
    let f = detect(&input, &opts).map_err(|e| super::with_input(e, &a.input))?;
    spinner.finish_and_clear();
    super::write_json(&a.output, &f)?;
    if let Some(p) = &a.ply {
        export::write_lines_ply(p, &f)?;
    }
    if let Some(p) = &a.regions_ply {
        export::write_regions_ply(p, &f)?;
    }
    if !quiet {
        eprintln!(
            "{}: {} regions, {} creases ({:.4} long, {:.2} % of the diagonal), {} corners, noise {:.3e} ({}, {:.2} s) -> {}",
            a.input.display(),
            f.regions,
            f.creases.len(),
            f.crease_length,
            100.0 * f.crease_length / f.diagonal.max(f64::MIN_POSITIVE),
            f.corners.len(),
            f.noise,
            f.method,
            f.seconds,
            a.output.display()
        );
    }
    Ok(())
}
