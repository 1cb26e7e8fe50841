//! `scansurf smooth IN -o OUT [--method anisotropic|arc|centroid] [--iterations N] ...`.

use super::progress;
use crate::error::{Error, Result};
use crate::smooth::{self, Adjacency, Control, Method};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Triangle mesh to smooth (.ply .obj .stl).
    pub input: PathBuf,
    /// Output mesh (.ply .obj .stl); same vertex order and faces as the input.
    #[arg(short, long)]
    pub output: PathBuf,
    /// anisotropic: feature preserving (seed 000, after Hildebrandt & Polthier);
    /// arc: circular-arc smoothing (seed 002), for organic shapes;
    /// centroid: area-weighted centroid relaxation (seed 003 eq. 9), triangle quality only.
    #[arg(long, default_value = "anisotropic")]
    pub method: String,
    /// Iterations (defaults: anisotropic 15, arc 10, centroid 5).
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Anisotropic time step s (an area; default 0.2 x mean edge length squared).
    #[arg(long)]
    pub step: Option<f64>,
    /// Anisotropic curvature threshold lambda (a length; default 0.2 x mean edge length).
    #[arg(long)]
    pub lambda: Option<f64>,
    /// Anisotropic fall-off r of the weight past lambda (default 100).
    #[arg(long)]
    pub r: Option<f64>,
    /// Smooth only the faces from this index on (a `fill-holes` result puts its fill after the
    /// original faces) and `--rings` rings of vertices around them.
    #[arg(long, value_name = "FIRST_FACE")]
    pub only_region: Option<usize>,
    /// Rings of vertices around `--only-region` that may move too.
    #[arg(long, default_value_t = 2)]
    pub rings: usize,
    /// Write the report (iterations, displacement, time) as JSON here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write PLY/STL as text.
    #[arg(long)]
    pub ascii: bool,
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    let mut mesh = crate::io::read_mesh(&a.input)?;
    if mesh.faces.is_empty() {
        return Err(Error::content(
            &a.input,
            "is a point cloud; smoothing needs a triangle mesh",
        ));
    }
    let mut method = Method::by_name(&a.method)?;
    if let Some(n) = a.iterations {
        method = method.with_iterations(n);
    }
    match &mut method {
        Method::Anisotropic(p) => {
            p.step = a.step.or(p.step);
            p.lambda = a.lambda.or(p.lambda);
            if let Some(r) = a.r {
                p.r = r;
            }
        }
        _ => {
            if a.step.is_some() || a.lambda.is_some() || a.r.is_some() {
                return Err(Error::InvalidOption(
                    "--step, --lambda and --r apply to --method anisotropic only".into(),
                ));
            }
        }
    }
    let adj = Adjacency::build(&mesh)?;
    let region = match a.only_region {
        None => None,
        Some(first) if first >= mesh.faces.len() => {
            return Err(Error::InvalidOption(format!(
                "--only-region {first}: the mesh has {} faces",
                mesh.faces.len()
            )))
        }
        Some(first) => {
            let faces: Vec<u32> = (first as u32..mesh.faces.len() as u32).collect();
            let seed = smooth::vertices_of_faces(&mesh, &faces);
            Some(adj.grow_rings(&seed, a.rings))
        }
    };
    let total = match &method {
        Method::Anisotropic(p) => p.iterations,
        Method::Arc(p) => p.iterations,
        Method::Centroid(p) => p.iterations,
    };
    let bar = progress::bar("smoothing", total as u64, quiet);
    let tick = |done: usize, _total: usize| bar.set_position(done as u64);
    let control = Control {
        region: region.as_deref(),
        progress: Some(&tick),
    };
    let report = smooth::run(&mut mesh, &adj, &method, None, &control)?;
    bar.finish_and_clear();
    crate::io::write_mesh(&a.output, &mesh, crate::io::WriteOptions { ascii: a.ascii })?;
    if let Some(r) = &a.report {
        super::write_json(r, &report)?;
    }
    if !quiet {
        eprintln!(
            "smoothed {} ({} iterations, mean displacement {:.3e}, {:.2} s) -> {}",
            a.input.display(),
            report.iterations,
            report.mean_displacement,
            report.seconds,
            a.output.display()
        );
    }
    Ok(())
}
