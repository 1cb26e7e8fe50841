//! Hole filling on real models: the Stanford bunny's five base holes, and holes cut out of spot
//! and fandisk (`fixtures/holes/`, made by `cargo run --release --example make_hole_fixtures`).
//! Every hole must close, by the method asked for (no fallback), leaving the original vertices
//! and faces as they were, with a manifold, consistently oriented result and no fill triangle
//! cutting through the mesh or through another fill triangle.

use scansurf::holes::intersect::fill_intersections;
use scansurf::holes::{fill_holes, FillMethod, FillOptions, HoleStatus};
use scansurf::io::read_mesh;
use scansurf::Mesh;
use std::path::{Path, PathBuf};

/// A file of the shared data set: `../shared/data` from the main checkout, `../../shared/data`
/// from a worktree; `None` (the test is skipped) when neither exists.
fn shared(name: &str) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    ["../shared/data", "../../shared/data"]
        .iter()
        .map(|d| root.join(d).join(name))
        .find(|p| p.exists())
}

fn fixture(name: &str) -> Mesh {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/holes")
        .join(name);
    read_mesh(&p).unwrap()
}

/// Fills every hole of `mesh` with `method` and checks the result; returns it.
fn fill_all(name: &str, mesh: &Mesh, method: FillMethod) -> Mesh {
    let opts = FillOptions {
        method,
        fallback: false,
        ..Default::default()
    };
    let (out, rep) = fill_holes(mesh, &opts).unwrap();
    for h in &rep.holes {
        assert_eq!(h.status, HoleStatus::Filled, "{name} {method:?}: {h:?}");
        assert_eq!(h.method, Some(method), "{name}: {h:?}");
        assert_eq!(h.self_intersections, 0, "{name} {method:?}: {h:?}");
        assert!(h.max_deviation.is_some_and(|d| d.is_finite()));
    }
    assert_eq!(&out.positions[..mesh.positions.len()], &mesh.positions[..]);
    assert_eq!(&out.faces[..mesh.faces.len()], &mesh.faces[..]);
    let t = out.topology();
    assert!(
        t.is_closed_manifold(),
        "{name} {method:?}: {} loops, {} non-manifold edges, {} non-manifold vertices, {} \
         misoriented edges",
        t.loops.len(),
        t.non_manifold_edges.len(),
        t.non_manifold_vertices.len(),
        t.misoriented_edges
    );
    let crossings = fill_intersections(&out, mesh.faces.len());
    assert!(crossings.is_empty(), "{name} {method:?}: {crossings:?}");
    let json = serde_json::to_value(&rep).unwrap();
    assert_eq!(
        json["holes"].as_array().map(|a| a.len()),
        Some(rep.holes.len())
    );
    out
}

#[test]
fn bunny_base_holes_close() {
    let Some(path) = shared("stanford-bunny.obj") else {
        eprintln!("skipping: shared data not found");
        return;
    };
    let bunny = read_mesh(&path).unwrap();
    let before = bunny.topology();
    assert_eq!(before.loops.len(), 5);
    for method in [FillMethod::Rbf, FillMethod::Planar] {
        let out = fill_all("bunny", &bunny, method);
        // The 1,113 unreferenced vertices stay as they are.
        assert_eq!(
            out.topology().unreferenced_vertices,
            before.unreferenced_vertices
        );
    }
}

#[test]
fn spot_holes_close_with_both_methods() {
    let spot = fixture("spot_holes.ply");
    assert_eq!(spot.topology().loops.len(), 5);
    for method in [FillMethod::Rbf, FillMethod::Planar] {
        fill_all("spot", &spot, method);
    }
}

#[test]
fn fandisk_holes_close_with_both_methods() {
    // Holes across fandisk's creases and around the corner of its thin plate.
    let fandisk = fixture("fandisk_holes.ply");
    assert_eq!(fandisk.topology().loops.len(), 6);
    for method in [FillMethod::Rbf, FillMethod::Planar] {
        fill_all("fandisk", &fandisk, method);
    }
}

#[test]
fn the_fill_does_not_depend_on_the_thread_count() {
    let spot = fixture("spot_holes.ply");
    let par = fill_holes(&spot, &FillOptions::default()).unwrap().0;
    let seq = fill_holes(
        &spot,
        &FillOptions {
            parallel: false,
            ..Default::default()
        },
    )
    .unwrap()
    .0;
    assert_eq!(par, seq);
}
