//! `scansurf reconstruct` through the binary; `--sharp` on make_parts' block measured by the
//! independent `../shared/tools/part_check.py` (OpenCASCADE) against its exact CAD truth.

use crate::common::{self, json_f64 as f};
use std::path::Path;
use std::process::Command;

/// `reconstruct` of make_parts' `input` into `dir` with `extra` options: the mesh written and
/// the report.
fn reconstruct_part(
    parts: &Path,
    input: &str,
    dir: &Path,
    extra: &[&str],
) -> (std::path::PathBuf, serde_json::Value) {
    let out = dir.join(format!("{input}.ply"));
    let report = dir.join(format!("{input}.json"));
    let input_path = parts.join(input);
    let mut args = vec![
        "reconstruct",
        input_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = common::run(&args);
    assert_eq!(code, 0, "{input}: {err}");
    let r = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    (out, r)
}

/// `reconstruct --sharp` keeps the block's creases, from its mesh and from its noisy cloud: the
/// mesh's triangles split on the creases (1.6e-4 and 3.5e-4 of the diagonal at the 95th
/// percentile; without `--sharp` 1.2e-3 and 1.6e-3), the band beside them and the faces turned
/// right (0.9 and 2.3 degrees; without: band 14 degrees at the 95th percentile), nothing folded.
#[test]
fn sharp_keeps_the_block_creases() {
    let Some(parts) = common::make_parts() else {
        return;
    };
    let dir = common::scratch_dir("cli_reconstruct_sharp");
    let truth = parts.join("block.step");
    for (input, crease_p95, band_p95, normal_p95) in
        [("block.stl", 3e-4, 1.5, 1.5), ("block.xyz", 4e-4, 2.7, 2.0)]
    {
        let (out, r) = reconstruct_part(parts, input, &dir, &[]);
        assert_eq!(r["closed_manifold"], true, "{input}");
        // `--sharp auto`, the default, finds the part machined.
        assert_eq!(r["sharp"]["requested"], "auto", "{input}");
        assert_eq!(r["sharp"]["sharp"], true, "{input}: {}", r["sharp"]);
        assert!(
            f(&r, &["features", "regions"]) >= 10.0,
            "{input}: {}",
            r["features"]
        );
        assert!(
            f(&r, &["creases", "split_edges"]) > 1000.0,
            "{input}: {}",
            r["creases"]
        );
        assert!(
            r["creases"]["flipped_edges"].is_u64(),
            "{input}: {}",
            r["creases"]
        );
        let c = common::tool_json("part_check.py", &[&out, &truth]);
        let crease = f(&c, &["crease", "distance_p95"]);
        let band = f(&c, &["crease", "band_normal_err_deg", "p95"]);
        let normal = f(&c, &["normal_err_deg", "p95"]);
        assert!(crease <= crease_p95, "{input}: crease p95 {crease}");
        assert!(band <= band_p95, "{input}: band p95 {band}");
        assert!(normal <= normal_p95, "{input}: face normal p95 {normal}");
        assert!(f(&c, &["flipped_area"]) <= 1e-4, "{input}: {c}");
    }
}

/// `reconstruct --remesh` turns the block's sharp mesh into a light one (under 150,000
/// triangles against half a million) whose edges run on the creases, within issue 35's bars
/// for the crease (max 5e-4 of the diagonal), the band beside it (3 degrees) and the faces
/// (2.5) (measured: 4.7e-4, 1.1 and 1.4 degrees, 59,000 triangles, none degenerate). From the
/// mesh only: the noisy cloud takes 36 s and its crease max, 5.8e-4, is over the bar (its
/// figures are in docs/BENCHMARKS.md).
#[test]
fn remesh_gives_a_light_mesh_with_edges_on_the_creases() {
    let Some(parts) = common::make_parts() else {
        return;
    };
    let dir = common::scratch_dir("cli_reconstruct_remesh");
    let truth = parts.join("block.step");
    let input = "block.stl";
    let (out, r) = reconstruct_part(parts, input, &dir, &["--remesh"]);
    assert_eq!(r["closed_manifold"], true, "{input}");
    assert_eq!(r["components"], 1, "{input}");
    let faces = f(&r, &["faces"]);
    assert!(faces < 150_000.0, "{input}: {faces} faces");
    assert!(
        f(&r, &["remesh", "crease_edges"]) > 500.0,
        "{input}: {}",
        r["remesh"]
    );
    assert!(f(&r, &["timings", "remesh"]) > 0.0, "{input}");
    assert_eq!(
        f(&r, &["triangles", "degenerate"]),
        0.0,
        "{input}: {}",
        r["triangles"]
    );
    let c = common::tool_json("part_check.py", &[&out, &truth]);
    let crease = f(&c, &["crease", "distance_max"]);
    let band = f(&c, &["crease", "band_normal_err_deg", "p95"]);
    let normal = f(&c, &["normal_err_deg", "p95"]);
    assert!(crease <= 5e-4, "{input}: crease max {crease}");
    assert!(band <= 3.0, "{input}: band p95 {band}");
    assert!(normal <= 2.5, "{input}: face normal p95 {normal}");
    assert!(f(&c, &["flipped_area"]) <= 1e-4, "{input}: {c}");
}

/// Without sharp edges to keep there is nothing to remesh along: the mesh is the plain one,
/// the report has no remesh, and the user is told.
#[test]
fn remesh_without_sharp_edges_says_so() {
    let dir = common::scratch_dir("cli_reconstruct_remesh_off");
    let spot = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    let out = dir.join("spot.ply");
    let report = dir.join("spot.json");
    let (code, _, err) = common::run(&[
        "reconstruct",
        spot.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--sharp",
        "off",
        "--remesh",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("--remesh: no sharp edges kept"), "{err}");
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert!(r["remesh"].is_null(), "{}", r["remesh"]);
    assert_eq!(r["closed_manifold"], true);
}

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

/// An organic model has one smooth region (its horns are surface detail), so every `--sharp`
/// mode (`auto` the default, `--sharp` alone meaning `on`) leaves the output as `off` makes
/// it, byte for byte.
#[test]
fn sharp_leaves_an_organic_model_as_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let spot = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    let mut outputs = Vec::new();
    let modes: [&[&str]; 4] = [&["--sharp", "off"], &[], &["--sharp"], &["--sharp", "auto"]];
    for (k, extra) in modes.into_iter().enumerate() {
        let out = dir.path().join(format!("spot{k}.ply"));
        let args = [
            &[
                "reconstruct",
                spot.to_str().unwrap(),
                "-q",
                "-o",
                out.to_str().unwrap(),
            ][..],
            extra,
        ]
        .concat();
        let (code, _, err) = common::run(&args);
        assert_eq!(code, 0, "{err}");
        outputs.push(std::fs::read(&out).unwrap());
    }
    for (k, o) in outputs.iter().enumerate().skip(1) {
        assert!(
            *o == outputs[0],
            "{:?} changed an organic model's mesh",
            modes[k]
        );
    }
}
