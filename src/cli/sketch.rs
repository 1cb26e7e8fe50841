//! `scansurf sketch DRAWING.(svg|json) -o OUT.(ply|obj|stl|step) [--weights c,o,d] [--report R]`.

use crate::error::{Error, Result};
use crate::sketch::{read_drawing, sketch, SketchOptions, Weights};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Drawing of closed contours: SVG paths/polygons or JSON {"contours": [[[x, y], ...]]}.
    pub input: PathBuf,
    /// Closed triangle mesh (.ply .obj .stl), or STEP (.step .stp) through the `fit` pipeline.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Skeleton energy weights curvature,orientation,distance (seed 001 eq. 10-12); all
    /// positive, largest / smallest under 1e3.
    #[arg(long, default_value = "1,0.3,0.3")]
    pub weights: String,
    /// Smallest gap between overlapping parts, as a fraction of the drawing's diagonal.
    #[arg(long, default_value_t = 0.02)]
    pub min_gap: f64,
    /// Marching-cubes cube edge as a fraction of the drawing's diagonal.
    #[arg(long, default_value_t = 1.0 / 90.0)]
    pub cell: f64,
    /// STEP output only: about this many B-spline patches (as `scansurf fit --patches`).
    #[arg(long, default_value_t = crate::fit::net::DEFAULT_PATCHES)]
    pub patches: usize,
    /// Write the report (parts, depths, constraints, topology, silhouette match) as JSON here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// A contour that crosses itself (a fold, e.g. a tail curled over the body drawn as one
    /// curve): put the doubly covered layer behind the rest instead of in front.
    #[arg(long)]
    pub fold_behind: bool,
    /// Write PLY/STL as text.
    #[arg(long)]
    pub ascii: bool,
}

fn parse_weights(s: &str) -> Result<Weights> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::InvalidOption(format!("--weights '{s}': expected three numbers")))?;
    if v.len() != 3 {
        return Err(Error::InvalidOption(format!(
            "--weights '{s}': expected curvature,orientation,distance"
        )));
    }
    let w = Weights {
        curvature: v[0],
        orientation: v[1],
        distance: v[2],
    };
    w.check()?;
    Ok(w)
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let step = ext == "step" || ext == "stp";
    if !step {
        crate::io::Format::from_path(&a.output).and_then(|f| match f {
            crate::io::Format::Ply | crate::io::Format::Obj | crate::io::Format::Stl => Ok(()),
            _ => Err(Error::unsupported(
                &a.output,
                "sketch writes a triangle mesh (.ply, .obj, .stl) or STEP (.step, .stp)",
            )),
        })?;
    }
    let opts = SketchOptions {
        weights: parse_weights(&a.weights)?,
        min_gap: a.min_gap,
        cell: a.cell,
        fold_behind: a.fold_behind,
        ..SketchOptions::default()
    };
    let drawing = read_drawing(&a.input)?;
    let (mesh, report) = sketch(&drawing, &opts).map_err(|e| super::with_input(e, &a.input))?;
    if step {
        // STEP through the `fit` pipeline, on the sketched mesh.
        let bar = super::progress::bar("fit", 100, quiet);
        let mut progress = |stage: &str, frac: f64| {
            bar.set_prefix(stage.to_string());
            bar.set_position((frac.clamp(0.0, 1.0) * 100.0) as u64);
        };
        let fopts = crate::fit::pipeline::FitOptions {
            size: crate::fit::net::PatchSize::Count(a.patches),
            ..Default::default()
        };
        let (network, fr) = crate::fit::pipeline::fit(&mesh, &fopts, &mut progress)
            .map_err(|e| super::with_input(e, &a.input))?;
        bar.finish_and_clear();
        let opts = crate::export::ExportOptions {
            name: a
                .output
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scansurf".into()),
            tolerance: fr.tolerance.max(fr.bbox_diagonal * 1e-7),
            ..crate::export::ExportOptions::default()
        };
        let text = crate::export::step_string(&network, &opts)?;
        crate::io::write_atomic(&a.output, |w| w.write_all(text.as_bytes()))?;
    } else {
        crate::io::write_mesh(&a.output, &mesh, crate::io::WriteOptions { ascii: a.ascii })?;
    }
    if let Some(r) = &a.report {
        super::write_json(r, &report)?;
    }
    if !quiet {
        eprintln!(
            "sketched {} -> {}: {} parts, {} vertices, {} faces, {}, genus {}, silhouette IoU {:.3} in {:.2} s",
            a.input.display(),
            a.output.display(),
            report.parts.len(),
            report.vertices,
            report.faces,
            if report.closed_manifold {
                "closed manifold"
            } else {
                "NOT closed manifold"
            },
            report.genus,
            report.silhouette_iou,
            report.seconds
        );
    }
    Ok(())
}
