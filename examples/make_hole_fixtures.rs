//! Regenerates the hole-filling fixtures `fixtures/holes/*_holes.ply`: spot and fandisk
//! (`../shared/data/`) with holes cut out by `scansurf::holes::cut` (binary PLY).
//!
//!     cargo run --release --example make_hole_fixtures
//!
//! Each hole removes the faces within a ball around a chosen vertex (connected to it), so the
//! holes are round on smooth parts and follow the creases on fandisk.

use nalgebra::Point3;
use scansurf::holes::cut::cut_ball;
use std::path::Path;

/// (model, [(vertex index, radius as a fraction of the bounding-box diagonal)])
const CUTS: &[(&str, &[(usize, f64)])] = &[
    (
        "spot",
        &[
            (100, 0.05),
            (700, 0.04),
            (1000, 0.06),
            (2100, 0.03),
            (2700, 0.05),
        ],
    ),
    (
        "fandisk",
        &[
            (200, 0.04),
            (1300, 0.05),
            (2500, 0.03),
            (3900, 0.05),
            (5200, 0.04),
            (6100, 0.03),
        ],
    ),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(root.join("fixtures/holes"))?;
    for (name, cuts) in CUTS {
        // ../shared from the main checkout, ../../shared from a worktree under wt/.
        let src = ["../shared/data", "../../shared/data"]
            .iter()
            .map(|d| root.join(d).join(format!("{name}.obj")))
            .find(|p| p.exists())
            .ok_or("shared data directory not found")?;
        let mut mesh = scansurf::io::read_mesh(&src)?;
        let diag = mesh.aabb().map(|b| b.diagonal()).unwrap_or(1.0);
        // Centres are taken from the original model, so the holes do not depend on each other.
        let centres: Vec<(Point3<f64>, f64)> = cuts
            .iter()
            .map(|&(v, r)| (mesh.positions[v % mesh.positions.len()], r * diag))
            .collect();
        for (c, r) in &centres {
            mesh = cut_ball(&mesh, c, *r);
        }
        let t = mesh.topology();
        if t.components.len() != 1 || t.loops.len() != cuts.len() {
            return Err(format!(
                "{name}: the cuts gave {} components and {} loops; expected 1 and {}",
                t.components.len(),
                t.loops.len(),
                cuts.len()
            )
            .into());
        }
        let out = root.join(format!("fixtures/holes/{name}_holes.ply"));
        scansurf::io::write_mesh(&out, &mesh, Default::default())?;
        println!(
            "wrote {} ({} faces, {} holes: {:?})",
            out.display(),
            mesh.faces.len(),
            t.loops.len(),
            t.loops.iter().map(|l| l.vertices.len()).collect::<Vec<_>>()
        );
    }
    Ok(())
}
