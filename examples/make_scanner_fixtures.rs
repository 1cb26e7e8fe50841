//! Writes the scanner-format fixtures from `fixtures/spot.obj`: its vertices voxel-subsampled to
//! at most 2,000 points, as
//!
//! - `fixtures/spot_2scans.e57`: two scans with different poses, one Cartesian (with an
//!   intensity channel) and one spherical;
//! - `fixtures/spot.las` and `fixtures/spot.laz`: LAS 1.2 point format 1 on a 1e-6 grid.
//!
//!     cargo run --release --example make_scanner_fixtures
//!
//! The files are written by the `e57` and `las` crates' own writers (scansurf only reads them).

#[path = "../tests/it/support/scanner_writers.rs"]
mod scanner_writers;

use scansurf::io::read_mesh;
use scansurf::mesh::subsample::voxel_grid;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let spot = read_mesh(&root.join("spot.obj"))?;
    let (points, _) = voxel_grid(&spot.positions, None, 2000)?;
    println!(
        "spot: {} vertices -> {} points",
        spot.positions.len(),
        points.len()
    );
    let e57 = root.join("spot_2scans.e57");
    scanner_writers::write_e57_two_scans(&e57, &points)?;
    for name in ["spot.las", "spot.laz"] {
        scanner_writers::write_las(&root.join(name), &points)?;
    }
    for name in ["spot_2scans.e57", "spot.las", "spot.laz"] {
        let p = root.join(name);
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
