//! Writes the Stanford bunny's vertices as scanner files, for the user guide
//! (`docs/GUIDE.md`): `bunny_2scans.e57` (two posed scans) and `bunny.laz` (LAS 1.2, 1e-6 grid),
//! by the `e57` and `las` crates' own writers (scansurf only reads these formats).
//!
//!     cargo run --release --example bunny_scans -- ../shared/data/stanford-bunny.obj /tmp/guide

#[path = "../tests/it/support/scanner_writers.rs"]
mod scanner_writers;

use scansurf::io::read_mesh;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1);
    let (Some(input), Some(dir)) = (args.next(), args.next()) else {
        return Err("usage: bunny_scans BUNNY.obj OUT_DIR".into());
    };
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(&dir)?;
    let points = read_mesh(&PathBuf::from(input))?.positions;
    scanner_writers::write_e57_two_scans(&dir.join("bunny_2scans.e57"), &points)?;
    scanner_writers::write_las(&dir.join("bunny.laz"), &points)?;
    for name in ["bunny_2scans.e57", "bunny.laz"] {
        let p = dir.join(name);
        let m = read_mesh(&p)?;
        println!(
            "{}: {} bytes, {} points read back",
            p.display(),
            std::fs::metadata(&p)?.len(),
            m.positions.len()
        );
    }
    Ok(())
}
