//! `scansurf smooth` through the binary.

use crate::common::run;
use std::path::Path;

#[test]
fn smooths_keeps_connectivity_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    let out = dir.path().join("s.ply");
    let rep = dir.path().join("s.json");
    for method in ["anisotropic", "arc", "centroid"] {
        let (code, _, err) = run(&[
            "smooth",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--method",
            method,
            "--report",
            rep.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(code, 0, "{method}: {err}");
        let a = scansurf::io::read_mesh(&input).unwrap();
        let b = scansurf::io::read_mesh(&out).unwrap();
        assert_eq!(a.faces, b.faces);
        assert!(b.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
        let moved = a
            .positions
            .iter()
            .zip(&b.positions)
            .filter(|(p, q)| (*p - *q).norm() > 0.0)
            .count();
        assert!(
            moved > a.positions.len() / 2,
            "{method}: only {moved} moved"
        );
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
        assert_eq!(r["method"], method);
    }
    // Only a region: the faces from 5000 on and one ring.
    let (code, _, err) = run(&[
        "smooth",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--only-region",
        "5000",
        "--rings",
        "1",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let a = scansurf::io::read_mesh(&input).unwrap();
    let b = scansurf::io::read_mesh(&out).unwrap();
    let fixed = a.faces[..100]
        .iter()
        .flatten()
        .filter(|&&v| a.positions[v as usize] == b.positions[v as usize])
        .count();
    assert!(fixed > 250, "vertices far from the region moved");
}

#[test]
fn bad_options_and_point_clouds_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    let out = dir.path().join("s.ply");
    let (code, _, err) = run(&[
        "smooth",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--method",
        "taubin",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("taubin"), "{err}");
    assert!(!out.exists());
    let cloud = dir.path().join("c.xyz");
    std::fs::write(&cloud, "0 0 0\n1 0 0\n0 1 0\n").unwrap();
    let (code, _, err) = run(&[
        "smooth",
        cloud.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(
        err.contains("c.xyz") && err.contains("point cloud"),
        "{err}"
    );
    assert!(!out.exists());
}
