//! Runs the implicit fit (and later the whole reconstruction) on the Stanford bunny and prints
//! accuracy figures and timings.
//!
//! cargo run --release --example reconstruct_bunny [-- PATH.obj [--cloud]]

use nalgebra::Point3;
use scansurf::reconstruct::{reconstruct, ReconstructOptions};
use scansurf::Mesh;
use std::time::Instant;

/// Minimal `v x y z` / `f a b c` reader (the crate's OBJ reader lives in src/io).
fn read_obj(path: &str) -> Mesh {
    let text = std::fs::read_to_string(path).expect("read OBJ");
    let mut m = Mesh::default();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|s| s.parse().unwrap()).collect();
                m.positions.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let v: Vec<u32> = it
                    .map(|s| s.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..v.len() - 1 {
                    m.faces.push([v[0], v[k], v[k + 1]]);
                }
            }
            _ => {}
        }
    }
    m
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .iter()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| "/work/shared/data/stanford-bunny.obj".into());
    let cloud = args.iter().any(|a| a == "--cloud");
    let mut mesh = read_obj(&path);
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
