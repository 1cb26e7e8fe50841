//! The `scansurf` command line: clap subcommands that parse, call the library and print.
//! No algorithms live here.

mod features;
mod fill_holes;
mod fit;
mod inspect;
pub mod interrupt;
pub mod progress;
mod reconstruct;
mod render;
mod sketch;
mod smooth;

use clap::{Parser, Subcommand};

/// scansurf: turn 3D scans (point clouds, meshes with holes) into CAD surfaces.
#[derive(Debug, Parser)]
#[command(name = "scansurf", version, about, long_about = None)]
pub struct Cli {
    /// No progress bars on stderr.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Memory budget, e.g. 8G or 500M: inputs and grids that would need more fail early with a
    /// suggestion (coarser --patch-size or --resolution, --max-points). Default: 3/4 of the
    /// physical memory.
    #[arg(long, global = true, value_name = "SIZE")]
    pub max_memory: Option<String>,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Fit a sewn network of bicubic B-spline patches to a point cloud or mesh and write STEP
    /// (and IGES), with a report of the deviation and continuity it reached.
    #[command(
        after_help = "Examples:\n  scansurf fit scan.ply -o part.step --iges part.igs --report part.json\n  scansurf fit bunny.obj -o bunny.step --patches 800 --preview bunny.png\n  scansurf fit cloud.xyz -o out.step --patch-size 5 --tolerance 5e-5"
    )]
    Fit(fit::Args),
    /// Close the holes of a mesh, keeping every original triangle: local RBF (seed 000) or
    /// planar Delaunay with circular arcs (seed 002).
    #[command(
        name = "fill-holes",
        after_help = "Examples:\n  scansurf fill-holes bunny.obj -o filled.ply\n  scansurf fill-holes scan.ply -o out.ply --method planar --max-size 20 --report holes.json"
    )]
    FillHoles(fill_holes::Args),
    /// Find the sharp features of a mesh or noisy point cloud: its noise, smooth regions, the
    /// crease polylines between them and the corners where three or more meet.
    #[command(
        after_help = "Examples:\n  scansurf features part.stl -o part-features.json --ply creases.ply\n  scansurf features scan.xyz -o f.json --regions-ply regions.ply --angle 30\n  scansurf render part.stl -o part.png --features part-features.json"
    )]
    Features(features::Args),
    /// Count points, faces, components, holes and defects of a mesh or point cloud.
    #[command(
        after_help = "Example:\n  scansurf inspect scan.ply\n  scansurf inspect bunny.obj --json > bunny.json"
    )]
    Inspect(inspect::Args),
    /// Smooth a noisy mesh: anisotropic (keeps sharp edges), circular-arc, or centroid.
    #[command(
        after_help = "Examples:\n  scansurf smooth noisy.ply -o smooth.ply\n  scansurf smooth scan.obj -o out.obj --method arc --iterations 20 --report smooth.json\n  scansurf smooth filled.ply -o out.ply --only-region 69451 --rings 3"
    )]
    Smooth(smooth::Args),
    /// Draw a mesh or point cloud to a PNG (software renderer, no GPU), optionally coloured by
    /// the distance to a reference cloud.
    #[command(
        after_help = "Examples:\n  scansurf render bunny.obj -o bunny.png\n  scansurf render scan.ply -o scan.png --view front --size 800x600\n  scansurf render recon.ply -o dev.png --against scan.xyz\n  scansurf render part.step -o dev.png --deviation dev.ply   # from fit --deviation-ply"
    )]
    Render(render::Args),
    /// Closed, manifold triangle mesh from a point cloud or a mesh with holes (implicit surface
    /// of seeds 003/004, marching cubes, relaxation, subdivision with projection).
    #[command(
        after_help = "Examples:\n  scansurf reconstruct scan.xyz -o closed.ply\n  scansurf reconstruct bunny.obj -o bunny.ply --report bunny.json"
    )]
    Reconstruct(reconstruct::Args),
    /// Closed 3D mesh from a 2D drawing of closed contours, overlapping parts kept apart in
    /// depth (chordal axis, constrained least-squares skeleton, spherical implicits; seed 001).
    #[command(
        after_help = "Examples:\n  scansurf sketch blob.svg -o blob.ply\n  scansurf sketch knot.svg -o knot.obj --weights 1,0.1,0.5 --report knot.json"
    )]
    Sketch(sketch::Args),
}

/// Runs the command line; returns the process exit code.
pub fn run() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { 2 } else { 0 };
        }
    };
    interrupt::install();
    let budget = match cli.max_memory.as_deref().map(crate::limits::parse_size) {
        Some(Ok(b)) => Some(b),
        Some(Err(e)) => {
            eprintln!("scansurf: error: {e}");
            return 2;
        }
        None => crate::limits::default_max_memory(),
    };
    if let Some(b) = budget {
        crate::limits::set_max_memory(b);
    }
    let result = match cli.command {
        Command::Fit(a) => fit::run(a, cli.quiet),
        Command::FillHoles(a) => fill_holes::run(a, cli.quiet),
        Command::Features(a) => features::run(a, cli.quiet),
        Command::Inspect(a) => inspect::run(a, cli.quiet),
        Command::Smooth(a) => smooth::run(a, cli.quiet),
        Command::Render(a) => render::run(a, cli.quiet),
        Command::Reconstruct(a) => reconstruct::run(a, cli.quiet),
        Command::Sketch(a) => sketch::run(a, cli.quiet),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("scansurf: error: {e}");
            1
        }
    }
}

/// Refuses an output path whose extension is none of `allowed` (lower case, without the dot),
/// naming the file and what it is for, or that cannot be written
/// ([`crate::io::atomic::check_target`]: a directory, or in a directory that does not exist).
pub(crate) fn check_ext(path: &std::path::Path, allowed: &[&str], what: &str) -> crate::Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if allowed.contains(&ext.as_str()) {
        crate::io::atomic::check_target(path).map(|_| ())
    } else {
        let names: Vec<String> = allowed.iter().map(|e| format!(".{e}")).collect();
        Err(crate::Error::unsupported(
            path,
            format!("{what} must end in {}", names.join(" or ")),
        ))
    }
}

/// Writes a report as pretty JSON, atomically.
pub(crate) fn write_json<T: serde::Serialize>(
    path: &std::path::Path,
    value: &T,
) -> crate::Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| crate::Error::Numerical(format!("cannot serialize the report: {e}")))?;
    crate::io::write_atomic(path, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
}

/// Names the input file in an error from an algorithm that does not know it (degenerate data,
/// numerical failure), so every message says which file it is about.
pub(crate) fn with_input(e: crate::Error, input: &std::path::Path) -> crate::Error {
    match e {
        crate::Error::Degenerate(m) | crate::Error::Numerical(m) | crate::Error::Limit(m) => {
            crate::Error::content(input, m)
        }
        other => other,
    }
}
