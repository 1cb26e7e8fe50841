//! Regenerates the in-tree fixtures that are derived from public models:
//! `fixtures/spot_tristrips_le.ply` and `fixtures/spot_tristrips_be.ply` (spot's triangles as
//! a `tristrips` element with -1 restarts, binary little and big endian).
//!
//!     cargo run --example make_fixtures

use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let spot = scansurf::io::read_mesh(&root.join("fixtures/spot.obj"))?;
    for (name, be) in [
        ("spot_tristrips_le.ply", false),
        ("spot_tristrips_be.ply", true),
    ] {
        let out = root.join("fixtures").join(name);
        scansurf::io::write_atomic(&out, |w| scansurf::io::ply::write_tristrips(w, &spot, be))?;
        println!("wrote {} ({} triangles)", out.display(), spot.faces.len());
    }
    Ok(())
}
