//! `scansurf fit INPUT -o OUT.step [--iges OUT.igs] [--report R.json] [--patches N | --patch-size L]
//! [--tolerance T] [--smooth N] [--deviation-ply D.ply] [--net NET.obj] [--preview P.png]`.

use crate::error::{Error, Result};
use crate::export::{ExportOptions, ExtendSurfaces, LengthUnit, Timestamp};
use crate::fit::net::PatchSize;
use crate::fit::pipeline::{fit_measured, FitOptions};
use crate::holes::{fill_holes, FillMethod, FillOptions};
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Point cloud or triangle mesh (.ply .obj .stl .xyz .txt .pts .csv .e57 .las .laz).
    pub input: PathBuf,
    /// STEP file to write (AP214; a closed shell as a solid, else an open shell).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write IGES 5.3 (entity 128 per patch) here.
    #[arg(long, value_name = "OUT.igs")]
    pub iges: Option<PathBuf>,
    /// Write the quality report (deviation, continuity, patch counts, timings) as JSON here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// About this many patches (within 15%).
    #[arg(long, value_name = "N", conflicts_with = "patch_size")]
    pub patches: Option<usize>,
    /// Patch edge length in model units (the voxel size of the quad net).
    #[arg(long, value_name = "L")]
    pub patch_size: Option<f64>,
    /// Largest distance of the patches from the fitted surface, as a fraction of the bounding-box
    /// diagonal.
    #[arg(long, default_value_t = 1e-4, value_name = "T")]
    pub tolerance: f64,
    /// Fitting tolerance of the implicit surface at the input points (fraction of the diagonal).
    #[arg(long, default_value_t = 2e-4)]
    pub fit_tolerance: f64,
    /// How holes in a mesh input are closed: first by the local fills of `fill-holes`, `rbf`
    /// (local thin-plate RBF, seed 000), `planar` (Delaunay with circular arcs, seed 002) or
    /// `flat`; or `implicit` (the fitted implicit surface closes them, seed 003; `none` is the
    /// same, for scripts that want to say so). `auto`: `rbf` for a mesh, `implicit` for a
    /// point cloud. Deviation is still measured at the input's own points.
    #[arg(long, default_value = "auto")]
    pub fill_holes: String,
    /// Anisotropic smoothing iterations on a mesh input before fitting (0 = none).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub smooth: usize,
    /// Write the input points coloured by their distance from the patches (PLY, scalar
    /// `quality` + RGB), for MeshLab or CloudCompare.
    #[arg(long, value_name = "D.ply")]
    pub deviation_ply: Option<PathBuf>,
    /// Write the quad net the patches were built on (OBJ: the patch corners as `v`, one quad
    /// `f` per patch in the STEP's face order), to inspect the layout in any mesh viewer.
    #[arg(long, value_name = "NET.obj")]
    pub net: Option<PathBuf>,
    /// Write a rendered picture of the patch network with its patch boundaries.
    #[arg(long, value_name = "P.png")]
    pub preview: Option<PathBuf>,
    /// Size WxH of the preview picture in pixels.
    #[arg(long, value_name = "WxH", default_value = "1600x1200")]
    pub preview_size: String,
    /// Subsample point clouds above this many points (voxel grid) on read.
    #[arg(long)]
    pub max_points: Option<usize>,
    /// Unit of the input coordinates, declared in STEP/IGES: mm, cm, m or um.
    #[arg(long, default_value = "mm")]
    pub unit: String,
    /// STEP faces on surfaces extended beyond them: `auto` extends the surfaces of patches
    /// too small (under about 0.03 mm in the declared unit) for OpenCASCADE's point projection
    /// to work on them, so the face is a trimmed region of a larger surface; `never` writes
    /// every face as its whole surface.
    #[arg(long, default_value = "auto", value_name = "auto|never")]
    pub extend_surfaces: String,
    /// Also find the input's sharp features (creases, corners, smooth regions, noise; as
    /// `scansurf features`) and summarize them in the report under `features`. The surfaces
    /// do not follow them yet.
    #[arg(long)]
    pub features: bool,
    /// Also build the crease-aligned quad net (work in progress, issue 36): find the smooth
    /// regions and creases first (as `scansurf features`), fit a second implicit with one
    /// function per region in the cells a crease crosses, and build a net whose edges follow
    /// the creases (`--crease-net`; the report's `crease_remesh` or `crease_nodes`, `--net`
    /// writes this net, by region). The STEP is unchanged for now: its patches are built on
    /// the smooth net. `on` whenever the input has creases (`--sharp` alone means `on`),
    /// `auto` when it looks machined (as `reconstruct`), `off` (default).
    #[arg(long, value_enum, default_value_t = crate::features::SharpMode::Off, num_args = 0..=1,
          default_missing_value = "on", value_name = "on|off|auto")]
    pub sharp: crate::features::SharpMode,
    /// How `--sharp` builds its crease-aligned net: `remesh` (default) meshes the sharp
    /// implicit as `reconstruct` does, remeshes it with its creases kept as edge paths and its
    /// corners pinned, and splits every triangle into three quads; `voxel` puts the voxel
    /// net's nodes on the creases and corners (a staircase where a crease runs at an angle to
    /// the grid).
    #[arg(long, value_enum, default_value_t = crate::fit::crease_net::CreaseNetRoute::Remesh,
          value_name = "remesh|voxel")]
    pub crease_net: crate::fit::crease_net::CreaseNetRoute,
    /// What to do where the data stop (a part scanned on a table has no underside): `open`
    /// fits only the scanned surface (an open shell); `smooth` closes every opening with the
    /// implicit's smooth extension (a solid); `auto` closes when the data enclose a volume (at
    /// most 4 % of the rays cast inward from the points leave the part) and fits open
    /// otherwise. The report's `close` says what was chosen and why.
    #[arg(long, default_value = "auto", value_name = "auto|smooth|open")]
    pub close: String,
    /// Header time stamp (ISO 8601, e.g. 2026-11-22T10:00:00). Default: SOURCE_DATE_EPOCH if
    /// set, else 1970-01-01T00:00:00, so the same input gives byte-identical files.
    #[arg(long)]
    pub timestamp: Option<String>,
}

/// Unsupported patch area (fraction) above which `fit` warns.
const UNSUPPORTED_WARNING: f64 = 0.05;

fn timestamp(a: &Args) -> Result<Option<Timestamp>> {
    if let Some(t) = &a.timestamp {
        return Timestamp::parse_iso8601(t).map(Some);
    }
    match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(s) => {
            let secs: u64 = s.trim().parse().map_err(|_| {
                Error::InvalidOption(format!("SOURCE_DATE_EPOCH={s} is not a number"))
            })?;
            Ok(Some(Timestamp::from_unix_seconds(secs)))
        }
        Err(_) => Ok(None),
    }
}

pub fn run(a: Args, quiet: bool) -> Result<()> {
    super::check_ext(&a.output, &["step", "stp"], "the STEP output")?;
    if let Some(i) = &a.iges {
        super::check_ext(i, &["igs", "iges"], "the IGES output")?;
    }
    if let Some(p) = &a.preview {
        super::check_ext(p, &["png"], "the preview")?;
    }
    // Checked before the fit, so a typo does not cost a whole run.
    let (preview_w, preview_h) = crate::render::parse_size(&a.preview_size)?;
    if let Some(p) = &a.deviation_ply {
        super::check_ext(p, &["ply"], "the deviation cloud")?;
    }
    if let Some(p) = &a.net {
        super::check_ext(p, &["obj"], "the quad net")?;
    }
    if let Some(p) = &a.report {
        crate::io::atomic::check_target(p)?;
    }
    // `auto` is decided once the input is read (a mesh or a cloud).
    let auto_fill = a.fill_holes == "auto";
    let mut local_fill: Option<FillMethod> = match a.fill_holes.as_str() {
        "implicit" | "none" | "auto" => None,
        m => Some(m.parse().map_err(|_| {
            Error::InvalidOption(format!(
                "--fill-holes {m}: expected auto, implicit, none, rbf, planar or flat"
            ))
        })?),
    };
    let unit: LengthUnit = a.unit.parse()?;
    let close: crate::openings::Close = a.close.parse()?;
    let extend_surfaces: ExtendSurfaces = a.extend_surfaces.parse()?;
    let stamp = timestamp(&a)?;
    let size = match (a.patches, a.patch_size) {
        (Some(0), _) => return Err(Error::InvalidOption("--patches must be at least 1".into())),
        (Some(n), _) => PatchSize::Count(n),
        (None, Some(l)) => PatchSize::Edge(l),
        (None, None) => PatchSize::Count(crate::fit::net::DEFAULT_PATCHES),
    };

    let mut input = crate::io::read_mesh(&a.input)?;
    if let Some(max) = a.max_points {
        input = crate::mesh::subsample::limit_points(input, max)?;
    }
    if a.smooth > 0 {
        if input.faces.is_empty() {
            return Err(Error::InvalidOption(
                "--smooth needs a mesh input; point clouds are smoothed by the implicit fit".into(),
            ));
        }
        let adj = crate::smooth::Adjacency::build(&input)?;
        let method = crate::smooth::Method::by_name("anisotropic")?.with_iterations(a.smooth);
        crate::smooth::run(&mut input, &adj, &method, None, &Default::default())?;
    }
    // `--close open` keeps every opening open, the small holes of a mesh too; so does `auto`
    // when it will choose open: decided here on the mesh as read, before a local fill could
    // close the opening it is about (a scan mesh whose bottom was cut away).
    let opens = match close {
        crate::openings::Close::Open => true,
        crate::openings::Close::Smooth => false,
        crate::openings::Close::Auto => {
            auto_fill && !input.faces.is_empty() && {
                let op =
                    crate::normals::oriented_points(&input, crate::normals::DEFAULT_NEIGHBOURS)
                        .map_err(|e| super::with_input(e, &a.input))?;
                let e = crate::openings::enclosure::escape_share(&op.points, &op.normals);
                crate::openings::choose(close, e).chosen == crate::openings::Close::Open
            }
        }
    };
    if auto_fill && !input.faces.is_empty() && !opens {
        local_fill = Some(FillMethod::Rbf);
    }
    if local_fill.is_some() && input.faces.is_empty() {
        return Err(Error::content(
            &a.input,
            format!(
                "is a point cloud; --fill-holes {} needs a triangle mesh (the implicit closes \
                 the holes of a cloud: use --fill-holes implicit)",
                a.fill_holes
            ),
        ));
    }
    // The scan's own points: what the deviation is measured at, whatever the fill adds.
    let (measured, _) = input.referenced_points();
    let hole_fill = match local_fill {
        Some(method) => {
            let spinner = super::progress::spinner("filling holes", quiet);
            let fill = FillOptions {
                method,
                ..FillOptions::default()
            };
            let (filled, report) =
                fill_holes(&input, &fill).map_err(|e| super::with_input(e, &a.input))?;
            spinner.finish_and_clear();
            input = filled;
            Some(report)
        }
        None => None,
    };
    let mut opts = FitOptions {
        size,
        tolerance: a.tolerance,
        apron_unit: (extend_surfaces == ExtendSurfaces::Auto).then_some(unit),
        features: a.features.then(crate::features::DetectOptions::default),
        close,
        sharp: a.sharp,
        crease_net: a.crease_net,
        size_given: a.patches.is_some() || a.patch_size.is_some(),
        ..FitOptions::default()
    };
    opts.implicit.tolerance = a.fit_tolerance;

    let bar = super::progress::bar("fit", 100, quiet);
    let mut progress = |stage: &str, frac: f64| {
        bar.set_prefix(stage.to_string());
        bar.set_position((frac.clamp(0.0, 1.0) * 100.0) as u64);
    };
    let (network, mut report) = fit_measured(&input, &measured, &opts, &mut progress)
        .map_err(|e| super::with_input(e, &a.input))?;
    bar.finish_and_clear();
    report.hole_fill = hole_fill;

    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scansurf".into())
    };
    let export = |p: &Path| ExportOptions {
        name: name(p),
        timestamp: stamp,
        unit,
        tolerance: (report.tolerance).max(report.bbox_diagonal * 1e-7),
        extend_surfaces,
        ..ExportOptions::default()
    };
    report.step = Some(crate::export::apron::summary(&network, &export(&a.output)));
    // Both texts are made before either file is written, so an export error leaves no file.
    let step = crate::export::step_string(&network, &export(&a.output))?;
    let iges = match &a.iges {
        Some(i) => Some(crate::export::iges_string(&network, &export(i))?),
        None => None,
    };
    crate::io::write_atomic(&a.output, |w| w.write_all(step.as_bytes()))?;
    if let (Some(i), Some(text)) = (&a.iges, &iges) {
        crate::io::write_atomic(i, |w| w.write_all(text.as_bytes()))?;
    }
    if let Some(r) = &a.report {
        super::write_json(r, &report)?;
    }
    if let Some(n) = &a.net {
        // `--sharp`: the crease-aligned net; otherwise the patches' own.
        let (nodes, quads, comment) = match &report.crease_net {
            Some(cnet) => (
                cnet.nodes.clone(),
                cnet.quads.clone(),
                format!(
                    "crease-aligned quad net of {} (--sharp): {} nodes, {} quads, {}; the \
                     patches are built on the voxel net for now",
                    name(&a.output),
                    cnet.nodes.len(),
                    cnet.quads.len(),
                    if cnet.is_open() { "open" } else { "closed" }
                ),
            ),
            None => {
                let quads = network.quads();
                let comment = format!(
                    "quad net of {}: {} nodes, {} quads (one per patch, in the STEP's face \
                     order), {}",
                    name(&a.output),
                    network.vertices.len(),
                    quads.len(),
                    if network.closed { "closed" } else { "open" }
                );
                (network.vertices.clone(), quads, comment)
            }
        };
        crate::io::write_atomic(n, |w| {
            let regions = report
                .net_regions
                .as_ref()
                .map(|r| crate::io::obj::QuadRegions {
                    quad_region: &r.quad_region,
                    crease_edges: &r.crease_edges,
                });
            crate::io::obj::write_quads(w, &nodes, &quads, &[comment], regions)
        })?;
    }
    let pts = measured;
    if let Some(d) = &a.deviation_ply {
        let dist = &report.deviation.distances;
        let scale = crate::render::ColorScale::auto(dist)?;
        let colors: Vec<[u8; 3]> = dist.iter().map(|&v| scale.map.srgb8(scale.t(v))).collect();
        crate::io::write_atomic(d, |w| {
            crate::io::ply::write_scalar_cloud(w, &pts, dist, &colors)
        })?;
    }
    if let Some(p) = &a.preview {
        let dist = Some(report.deviation.distances.as_slice());
        let opts = crate::render::RenderOptions {
            width: preview_w,
            height: preview_h,
            ..crate::render::RenderOptions::default()
        };
        crate::render::patches::network_preview(&network, &pts, dist, &opts)?.save_png(p)?;
    }
    let support = &report.support;
    if !quiet && report.close.requested == crate::openings::Close::Auto {
        eprintln!("close: {}", report.close.reason);
    }
    if let Some(c) = report
        .close
        .coverage
        .as_ref()
        .filter(|c| !c.note.is_empty())
    {
        // Parts left unfitted are a warning; a finer net made for them is said unless quiet
        // (the patch count then differs from the default).
        if !c.covered {
            eprintln!("warning: {}", c.note);
        } else if !quiet {
            eprintln!("close: {}", c.note);
        }
    }
    if support.unsupported_fraction > UNSUPPORTED_WARNING {
        eprintln!(
            "warning: {:.1}% of the patch area lies farther than {:.3e} (half a patch) from every \
             input point: the implicit closed openings there by extrapolation, not from data \
             (report: support); check those parts in a viewer",
            100.0 * support.unsupported_fraction,
            support.threshold
        );
    }
    if report.control_net.patches_outside > 0 {
        eprintln!(
            "warning: {} patches have control points farther than {:.0}% of the diagonal outside \
             the input's bounding box (up to {:.2e} of it): their interpolation went wrong \
             (report: control_net); check them in a viewer",
            report.control_net.patches_outside,
            100.0 * crate::quality::control_net::OUTSIDE_BAR,
            report.control_net.outside_max
        );
    }
    if !quiet {
        let dev = &report.deviation.stats.relative;
        eprintln!(
            "fitted {} -> {}: {} patches, {}, deviation mean {:.2e} p99 {:.2e} max {:.2e} of the diagonal, normal jump p95 {:.2} max {:.2} deg, {:.1} s",
            a.input.display(),
            a.output.display(),
            report.patches,
            if report.closed { "closed" } else { "open" },
            dev.mean,
            dev.p99,
            dev.max,
            report.continuity.all_deg.p95,
            report.continuity.all_deg.max,
            report.timings.total
        );
    }
    Ok(())
}
