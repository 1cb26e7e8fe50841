//! `scansurf fill-holes` through the binary.

use std::path::Path;
use std::process::Command;

#[test]
fn bunny_holes_close_and_originals_stay() {
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/stanford-bunny.obj");
    if !bunny.exists() {
        eprintln!("skipping: no shared data");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for method in ["rbf", "planar"] {
        let out = dir.path().join(format!("{method}.ply"));
        let rep = dir.path().join(format!("{method}.json"));
        let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
            .args([
                "fill-holes",
                bunny.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ])
            .args([
                "--method",
                method,
                "--report",
                rep.to_str().unwrap(),
                "--quiet",
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let a = scansurf::io::read_mesh(&bunny).unwrap();
        let b = scansurf::io::read_mesh(&out).unwrap();
        assert_eq!(&b.positions[..a.positions.len()], &a.positions[..]);
        assert_eq!(&b.faces[..a.faces.len()], &a.faces[..]);
        assert!(b.topology().is_closed_manifold(), "{method}");
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
        assert_eq!(r["holes_filled"], 5, "{method}: {r}");
    }
}

#[test]
fn bad_method_and_clouds() {
    let dir = tempfile::tempdir().unwrap();
    let spot = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    let out = dir.path().join("o.ply");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args([
            "fill-holes",
            spot.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["--method", "magic"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("magic"));
    let cloud = dir.path().join("c.xyz");
    std::fs::write(&cloud, "0 0 0\n1 0 0\n0 1 0\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args([
            "fill-holes",
            cloud.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("c.xyz") && err.contains("point cloud"),
        "{err}"
    );
    assert!(!out.exists());
}
