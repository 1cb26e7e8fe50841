//! Runs the implicit fit (and later the whole reconstruction) on the Stanford bunny and prints
//! accuracy figures and timings.
//!
//! cargo run --release --example reconstruct_bunny [-- PATH.obj [--cloud]]

use scansurf::reconstruct::{reconstruct, ReconstructOptions};
use scansurf::Mesh;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .iter()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| "../shared/data/stanford-bunny.obj".into());
    let cloud = args.iter().any(|a| a == "--cloud");
    let mut mesh = match scansurf::io::read_mesh(std::path::Path::new(&path)) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    if cloud {
        let (p, _) = mesh.referenced_points();
        mesh = Mesh::from_points(p, None);
    }
    let mut opts = ReconstructOptions::default();
    let env = |k: &str| std::env::var(k).ok().map(|v| v.parse::<f64>().expect(k));
    if let Some(v) = env("TOL") {
        opts.fit.tolerance = v;
    }
    if let Some(v) = env("OVERLAP") {
        opts.fit.overlap = v;
    }
    if let Some(v) = env("MAXPTS") {
        opts.fit.max_points = v as usize;
    }
    if let Some(v) = env("RES") {
        opts.resolution = v;
    }
    if let Some(v) = env("MESHTOL") {
        opts.tolerance = Some(v);
    }
    if let Some(v) = env("SUBDIV") {
        opts.max_subdivisions = v as usize;
    }
    if let Some(v) = env("RELAX") {
        opts.relax_iterations = v as usize;
    }
    let t0 = Instant::now();
    let (out, report) = reconstruct(&mesh, &opts, &mut |_, _| {}).expect("reconstruct");
    let secs = t0.elapsed().as_secs_f64();
    println!("{}", serde_json::to_string_pretty(&report).unwrap());
    if let Some(d) = report.deviation {
        println!(
            "bunny: {} -> {} faces, closed manifold {}, euler {}, deviation/diag mean {:.3e} p99 {:.3e} max {:.3e}, {:.2} s",
            report.input_points,
            report.faces,
            report.closed_manifold,
            report.euler_characteristic,
            d.relative.mean,
            d.relative.p99,
            d.relative.max,
            secs
        );
    }
    if let Ok(o) = std::env::var("OUT") {
        write_obj(&o, &out);
    }
}

fn write_obj(path: &str, m: &Mesh) {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    for p in &m.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z).unwrap();
    }
    for f in &m.faces {
        writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1).unwrap();
    }
}
