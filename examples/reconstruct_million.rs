//! Reconstruction of a large cloud: points sampled from a smooth closed surface (a torus with
//! a wavy tube), with or without normals. Prints the report's summary.
//!
//! cargo run --release --example reconstruct_million [-- N [--no-normals]]

use nalgebra::{Point3, Vector3};
use scansurf::reconstruct::{reconstruct, ReconstructOptions};
use scansurf::Mesh;
use std::time::Instant;

/// Point and outward normal of the wavy torus at parameters (u, v).
fn surface(u: f64, v: f64) -> (Point3<f64>, Vector3<f64>) {
    let big = 1.0;
    let p = |u: f64, v: f64| {
        let small = 0.35 + 0.05 * (5.0 * u).sin();
        let (su, cu) = u.sin_cos();
        let (sv, cv) = v.sin_cos();
        Point3::new((big + small * cv) * cu, (big + small * cv) * su, small * sv)
    };
    let h = 1e-6;
    let du = (p(u + h, v) - p(u - h, v)) / (2.0 * h);
    let dv = (p(u, v + h) - p(u, v - h)) / (2.0 * h);
    (p(u, v), du.cross(&dv).normalize())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args
        .iter()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .map_or(1_000_000, |s| s.parse().expect("N"));
    let with_normals = !args.iter().any(|a| a == "--no-normals");
    // Jittered grid in (u, v), about area-uniform.
    let nv = ((n as f64) * 0.35 / 1.35).sqrt() as usize;
    let nu = n / nv;
    let mut seed = 7u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut pts = Vec::with_capacity(n);
    let mut nrm = Vec::with_capacity(n);
    for i in 0..nu {
        for j in 0..nv {
            let u = (i as f64 + 0.8 * rnd()) / nu as f64 * std::f64::consts::TAU;
            let v = (j as f64 + 0.8 * rnd()) / nv as f64 * std::f64::consts::TAU;
            let (p, q) = surface(u, v);
            pts.push(p);
            nrm.push(q);
        }
    }
    let cloud = Mesh::from_points(pts, with_normals.then_some(nrm));
    let opts = ReconstructOptions::default();
    let t = Instant::now();
    let (_, r) = reconstruct(&cloud, &opts, &mut |stage, _| {
        eprintln!("{:8.2} s  {stage}", t.elapsed().as_secs_f64())
    })
    .expect("reconstruct");
    let d = r.deviation.expect("deviation");
    println!("{}", serde_json::to_string_pretty(&r.timings).unwrap());
    println!("{}", serde_json::to_string_pretty(&r.fit).unwrap());
    println!(
        "{} points (normals {:?}) -> {} faces, closed manifold {}, euler {}, components {}, deviation/diag mean {:.3e} p99 {:.3e} max {:.3e}, {:.1} s",
        r.input_points,
        r.normal_source,
        r.faces,
        r.closed_manifold,
        r.euler_characteristic,
        r.components,
        d.relative.mean,
        d.relative.p99,
        d.relative.max,
        t.elapsed().as_secs_f64()
    );
}
