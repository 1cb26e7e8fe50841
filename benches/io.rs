//! Reader throughput: a 1,000,000-point binary PLY (with normals) and the bunny OBJ.
//!
//!     cargo bench --bench io
//!
//! Prints the best of five reads. Figures go to docs/BENCHMARKS.md.

mod common;
use common::best_of;
use nalgebra::{Point3, Vector3};
use scansurf::io::{read_mesh, write_mesh, WriteOptions};
use scansurf::Mesh;
use std::path::Path;
use std::time::Instant;

fn main() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Points on a sphere, deterministic.
    let n = 1_000_000usize;
    let mut pts = Vec::with_capacity(n);
    let mut nrm = Vec::with_capacity(n);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let t = golden * i as f64;
        let v = Vector3::new(r * t.cos(), r * t.sin(), z);
        pts.push(Point3::from(v * 50.0));
        nrm.push(v);
    }
    let cloud = Mesh::from_points(pts, Some(nrm));
    for (name, ascii) in [("cloud_1m_binary.ply", false), ("cloud_1m_ascii.ply", true)] {
        let p = dir.path().join(name);
        let tw = Instant::now();
        write_mesh(&p, &cloud, WriteOptions { ascii }).expect("write");
        let write_s = tw.elapsed().as_secs_f64();
        let size = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        let s = best_of(5, || {
            let m = read_mesh(&p).expect("read");
            assert_eq!(m.positions.len(), n);
        });
        println!(
            "{name}: {:.1} MB, read {:.3} s (best of 5), write {:.3} s",
            size as f64 / 1e6,
            s,
            write_s
        );
    }
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/stanford-bunny.obj");
    if bunny.exists() {
        let s = best_of(5, || {
            let m = read_mesh(&bunny).expect("read bunny");
            let _ = m.topology();
        });
        println!("stanford-bunny.obj: read + topology {:.3} s (best of 5)", s);
    }
}
