//! `scansurf reconstruct` through the binary.

use std::path::Path;
use std::process::Command;

#[test]
fn cloud_without_normals_gives_closed_manifold_with_report() {
    let dir = tempfile::tempdir().unwrap();
    // spot's vertices as a bare point cloud.
    let spot =
        scansurf::io::read_mesh(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj"))
            .unwrap();
    let xyz = dir.path().join("spot.xyz");
    scansurf::io::write_mesh(
        &xyz,
        &scansurf::Mesh::from_points(spot.positions.clone(), None),
        Default::default(),
    )
    .unwrap();
    let out = dir.path().join("spot.ply");
    let rep = dir.path().join("r.json");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args([
            "reconstruct",
            xyz.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["--report", rep.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = scansurf::io::read_mesh(&out).unwrap();
    let t = m.topology();
    assert!(t.is_closed_manifold());
    assert_eq!(t.components.len(), 1);
    assert!(m.signed_volume() > 0.0, "inward oriented");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    assert_eq!(r["closed_manifold"], true);
    let mean = r["deviation"]["relative"]["mean"].as_f64().unwrap();
    assert!(mean < 3e-4, "mean deviation {mean}");
}

#[test]
fn refuses_point_output_and_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    let out = dir.path().join("x.xyz");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args([
            "reconstruct",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("x.xyz"), "{err}");
    let one = dir.path().join("one.xyz");
    std::fs::write(&one, "1 2 3\n").unwrap();
    let out = dir.path().join("x.ply");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args([
            "reconstruct",
            one.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("one.xyz") && !err.contains("panicked"),
        "{err}"
    );
    assert!(!out.exists());
}
