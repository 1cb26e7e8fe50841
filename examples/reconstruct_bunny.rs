//! Runs the implicit fit (and later the whole reconstruction) on the Stanford bunny and prints
//! accuracy figures and timings.
//!
//! cargo run --release --example reconstruct_bunny [-- PATH.obj [--cloud]]

use nalgebra::Point3;
use scansurf::implicit::{FitOptions, Implicit, PouImplicit};
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

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| "/work/shared/data/stanford-bunny.obj".into());
    let mesh = read_obj(&path);
    let t0 = Instant::now();
    let normals = scansurf::mesh::normals::vertex_normals(&mesh);
    let used = mesh.referenced();
    let (pts, nrm): (Vec<_>, Vec<_>) = mesh
        .positions
        .iter()
        .zip(&normals)
        .zip(&used)
        .filter(|(_, &u)| u)
        .map(|((p, n), _)| (*p, *n))
        .unzip();
    let mut opts = FitOptions::default();
    if let Ok(v) = std::env::var("TOL") {
        opts.tolerance = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("OVERLAP") {
        opts.overlap = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("MAXPTS") {
        opts.max_points = v.parse().unwrap();
    }
    let f = PouImplicit::fit(&pts, &nrm, &opts).expect("fit");
    let t_fit = t0.elapsed().as_secs_f64();
    println!("points {} fit {:.2} s", pts.len(), t_fit);
    println!("{:#?}", f.stats());
    let d = f.diagonal();
    let t1 = Instant::now();
    let mut r: Vec<f64> = pts.iter().map(|p| f.value(p).abs() / d).collect();
    let t_eval = t1.elapsed().as_secs_f64();
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let p99 = percentile(&mut r, 0.99);
    let max = percentile(&mut r, 1.0);
    println!(
        "|F| at points / diag: mean {mean:.3e} p99 {p99:.3e} max {max:.3e}  ({} evals in {t_eval:.3} s)",
        r.len()
    );
}
