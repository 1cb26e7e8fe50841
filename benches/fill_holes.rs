//! Hole-filling speed: the Stanford bunny's five base holes, and a 2-million-triangle sphere
//! with 50 holes cut out of it.
//!
//!     cargo bench --bench fill_holes
//!
//! Prints the best of several runs for each method. Figures go to docs/BENCHMARKS.md under
//! "## fill-holes". With `FILL_HOLES_BENCH_MESH=path.ply` the cut sphere is also written there,
//! for the peer comparison `scripts/peer_close_holes.py`.

use nalgebra::{Point3, Vector3};
use scansurf::holes::cut::cut_balls;
use scansurf::holes::testing::cube_sphere;
use scansurf::holes::{fill_holes, FillMethod, FillOptions, FillReport};
use scansurf::Mesh;
use std::path::Path;
use std::time::Instant;

/// CPU time (user + system) of this process so far, seconds: on a shared machine the wall time
/// depends on the other jobs, the CPU time much less. Linux only (`/proc/self/stat`, clock ticks
/// of 1/100 s); 0 elsewhere.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the parenthesized command name; utime and stime are the 12th and
            // 13th of them.
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
            Some(ticks / 100.0)
        })
        .unwrap_or(0.0)
}

/// Best wall time of `runs` fills and the CPU time of that run, with the last report.
fn best_fill(mesh: &Mesh, method: FillMethod, runs: usize) -> (f64, f64, FillReport) {
    let opts = FillOptions {
        method,
        ..Default::default()
    };
    let (mut best, mut best_cpu) = (f64::INFINITY, 0.0);
    let mut report = None;
    for _ in 0..runs {
        let (t, c) = (Instant::now(), cpu_seconds());
        let (out, rep) = fill_holes(mesh, &opts).expect("fill");
        let wall = t.elapsed().as_secs_f64();
        if wall < best {
            best = wall;
            best_cpu = cpu_seconds() - c;
        }
        assert!(
            out.topology().is_closed_manifold(),
            "{method:?} left it open"
        );
        report = Some(rep);
    }
    (best, best_cpu, report.expect("at least one run"))
}

fn summary(rep: &FillReport) -> String {
    let worst = rep
        .holes
        .iter()
        .filter_map(|h| h.max_deviation)
        .fold(0.0, f64::max);
    let fallbacks = rep.holes.iter().filter(|h| h.fallback.is_some()).count();
    format!(
        "{} holes filled, {} failed, {} fallbacks, {} triangles added, worst deviation {:.2e}",
        rep.holes_filled, rep.holes_failed, fallbacks, rep.triangles_added, worst
    )
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bunny = ["../shared/data", "../../shared/data"]
        .iter()
        .map(|d| root.join(d).join("stanford-bunny.obj"))
        .find(|p| p.exists());
    if let Some(path) = bunny {
        let mesh = scansurf::io::read_mesh(&path).expect("read bunny");
        for method in [FillMethod::Rbf, FillMethod::Planar] {
            let (s, cpu, rep) = best_fill(&mesh, method, 5);
            println!(
                "bunny {method:?}: {s:.3} s (best of 5, CPU {cpu:.2} s); {}",
                summary(&rep)
            );
        }
    } else {
        println!("bunny: shared data not found, skipped");
    }

    // 12 * 409^2 = 2,007,372 triangles.
    let t = Instant::now();
    let sphere = cube_sphere(409, 1.0);
    // 50 centres spread evenly (Fibonacci lattice), radii 10 to 25 edge lengths.
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let edge = sphere.mean_edge_length();
    let balls: Vec<(Point3<f64>, f64)> = (0..50)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / 50.0;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            let c = Point3::from(Vector3::new(r * a.cos(), r * a.sin(), z));
            (c, edge * (10.0 + 15.0 * (i % 4) as f64 / 3.0))
        })
        .collect();
    let cut = cut_balls(&sphere, &balls);
    let loops = cut.topology().loops.len();
    if let Ok(path) = std::env::var("FILL_HOLES_BENCH_MESH") {
        scansurf::io::write_mesh(Path::new(&path), &cut, Default::default()).expect("write");
    }
    println!(
        "sphere: {} triangles before cutting, {} after, {} holes cut (built in {:.1} s)",
        sphere.faces.len(),
        cut.faces.len(),
        loops,
        t.elapsed().as_secs_f64()
    );
    for method in [FillMethod::Rbf, FillMethod::Planar] {
        let (s, cpu, rep) = best_fill(&cut, method, 2);
        println!(
            "sphere 2M, 50 holes, {method:?}: {s:.2} s (best of 2, CPU {cpu:.1} s); {}",
            summary(&rep)
        );
    }
}
