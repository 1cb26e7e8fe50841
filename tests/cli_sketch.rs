//! `scansurf sketch` through the binary on the drawings of fixtures/sketch (seed 001).

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/sketch")
        .join(name)
}

/// Runs the command; returns the mesh and the report.
fn run(name: &str) -> (scansurf::Mesh, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    let rep = dir.path().join("r.json");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args(["sketch", fixture(name).to_str().unwrap(), "-o"])
        .arg(&out)
        .arg("--report")
        .arg(&rep)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let m = scansurf::io::read_mesh(&out).unwrap();
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    let t = scansurf::mesh::Topology::build(&m);
    assert!(t.is_closed_manifold(), "{name}: not a closed 2-manifold");
    assert!(m.signed_volume() > 0.0, "{name}: inward oriented");
    assert_eq!(r["closed_manifold"], true);
    // Silhouette: projected area within 10 % of the drawing's, and a good overlap.
    let ratio = r["silhouette_area_ratio"].as_f64().unwrap();
    let iou = r["silhouette_iou"].as_f64().unwrap();
    assert!((ratio - 1.0).abs() < 0.1, "{name}: area ratio {ratio}");
    // The ring's hole comes out a little small (1/d^2 blending around a loop): IoU 0.85.
    assert!(iou > 0.8, "{name}: IoU {iou}");
    (m, r)
}

#[test]
fn blob_is_one_sphere_like_body() {
    for name in ["blob.svg", "blob.json"] {
        let (m, r) = run(name);
        assert_eq!(m.topology().components.len(), 1, "{name}");
        assert_eq!(r["genus"], 0, "{name}");
    }
}

#[test]
fn ring_has_genus_one() {
    let (m, r) = run("ring.svg");
    assert_eq!(m.topology().components.len(), 1);
    assert_eq!(r["genus"], 1);
}

#[test]
fn overlapping_ellipses_are_two_bodies_in_drawing_order() {
    let (m, r) = run("ellipses.svg");
    let t = m.topology();
    // The depth constraints (gap d_MinSurf) keep them apart: two components.
    assert_eq!(t.components.len(), 2);
    assert_eq!(r["overlaps"][0], serde_json::json!([1, 0]));
    // The right ellipse (drawn second) is in front (larger z) of the left one.
    let mut sum = [[0.0f64; 2]; 2];
    for (f, tri) in m.faces.iter().enumerate() {
        let c = t.face_component[f] as usize;
        for &v in tri {
            let p = m.positions[v as usize];
            sum[c][0] += p.x;
            sum[c][1] += p.z;
        }
    }
    let (left, right) =
        if sum[0][0] / (t.components[0] as f64) < sum[1][0] / (t.components[1] as f64) {
            (0, 1)
        } else {
            (1, 0)
        };
    let z = |c: usize| sum[c][1] / t.components[c] as f64;
    assert!(z(right) > z(left), "front {} back {}", z(right), z(left));
    let parts = r["parts"].as_array().unwrap();
    assert!(parts[1]["mean_z"].as_f64().unwrap() > parts[0]["mean_z"].as_f64().unwrap());
}

#[test]
fn knot_and_curled_tail_are_closed_with_depth_constraints() {
    for name in ["knot.svg", "tail.svg"] {
        let (_, r) = run(name);
        assert!(r["active_constraints"].as_u64().unwrap() > 0, "{name}");
        assert_eq!(r["parts"].as_array().unwrap().len(), 3, "{name}");
    }
}

#[test]
fn bad_drawings_fail_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    for (name, what) in [
        ("bad/open.svg", "open"),
        ("bad/open.json", "open"),
        ("bad/empty.svg", "empty"),
        ("bad/malformed.svg", "line"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
            .args(["sketch", fixture(name).to_str().unwrap(), "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(what), "{name}: {err}");
        assert!(
            err.contains(name.trim_start_matches("bad/")),
            "{name}: {err}"
        );
        assert!(!out.exists());
    }
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args(["sketch", fixture("blob.svg").to_str().unwrap(), "-o"])
        .arg(&out)
        .args(["--weights", "1,1e-4,1"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("1e3"));
}

#[test]
fn blob_to_step_through_the_fit_pipeline() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("blob.step");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args(["sketch", fixture("blob.svg").to_str().unwrap(), "-o"])
        .arg(&out)
        .args(["--patches", "200", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.starts_with("ISO-10303-21;"));
    assert!(text.contains("CLOSED_SHELL"));
    let Some((python, script)) = common::checker() else {
        println!("SKIPPED: no .venv-check python or cad_check.py found");
        return;
    };
    let v = common::cad_check(&python, &script, &out, None);
    assert_eq!(v["read_ok"], true, "{v}");
    assert_eq!(v["valid"], true, "{v}");
    assert_eq!(v["closed"], true, "{v}");
    assert_eq!(v["shells"].as_u64(), Some(1), "{v}");
}
