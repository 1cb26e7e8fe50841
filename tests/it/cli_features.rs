//! `scansurf features` end to end: creases and corners of machined parts made by
//! `../shared/tools/make_parts.py` (exact CAD truth), measured by the independent
//! `../shared/tools/feature_check.py` (OpenCASCADE), from a mesh (.stl) and from a noisy
//! cloud (.xyz); none on organic models; bad options and inputs.

use crate::common::{self, json_f64 as f};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn parts() -> Option<&'static PathBuf> {
    common::make_parts()
}

/// Runs `scansurf features INPUT -o OUT.json --ply OUT.ply`, returns the JSON.
fn features(input: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let ply = out.with_extension("ply");
    let (code, _, err) = common::run(
        &[
            &["features", input.to_str().unwrap(), "-q", "-o"],
            &[out.to_str().unwrap(), "--ply", ply.to_str().unwrap()][..],
            extra,
        ]
        .concat(),
    );
    assert_eq!(code, 0, "{err}");
    serde_json::from_slice(&std::fs::read(out).unwrap()).unwrap()
}

/// feature_check.py's verdict on FEATURES.json against the part's STEP truth.
fn feature_check(features: &Path, truth: &Path) -> serde_json::Value {
    common::tool_json("feature_check.py", &[features, truth])
}

/// The bars: creases along at least 95 % of the true sharp edges (within 1 % of the
/// diagonal), at least 95 % of the detected length on a true edge, every true corner found.
fn meets_the_bars(input: &str, part: &str) {
    let Some(dir) = parts() else { return };
    let out = common::scratch_dir(&format!("cli_features_{part}_{input}")).join("f.json");
    let v = features(&dir.join(format!("{part}.{input}")), &out, &[]);
    assert!(v["regions"].as_u64().unwrap() >= 6, "{}", v["regions"]);
    let c = feature_check(&out, &dir.join(format!("{part}.step")));
    assert!(f(&c, &["recall"]) >= 0.95, "{c}");
    assert!(f(&c, &["precision"]) >= 0.95, "{c}");
    assert_eq!(c["corners"]["found"], c["corners"]["true"], "{c}");
    // The PLY holds every crease vertex and corner, and reads back.
    let lines = scansurf::io::read_mesh(&out.with_extension("ply")).unwrap();
    let expect: usize = v["creases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["points"].as_array().unwrap().len())
        .sum::<usize>()
        + v["corners"].as_array().unwrap().len();
    assert_eq!(lines.positions.len(), expect);
    if input == "xyz" {
        // The noise estimate is the scanner's sigma (0.01 mm), not the part's size.
        let noise = f(&v, &["noise"]);
        assert!(noise > 0.005 && noise < 0.02, "noise {noise}");
    }
}

#[test]
fn block_mesh_creases_and_corners_meet_the_bars() {
    meets_the_bars("stl", "block");
}

#[test]
fn bracket_cloud_creases_and_corners_meet_the_bars() {
    meets_the_bars("xyz", "bracket");
}

/// Organic models have no long crease: the spot fixture and the Stanford bunny, each as a mesh
/// and as its vertices (the bunny's ear tips and a groove in its base were regions behind
/// creases along part of their rims before [`scansurf::features::folds`]).
#[test]
fn organic_models_have_no_long_crease() {
    let dir = tempfile::tempdir().unwrap();
    let mut inputs = Vec::new();
    let models = [
        Some(repo().join("fixtures/spot.obj")),
        common::shared_model("stanford-bunny.obj"),
    ];
    for mesh in models.into_iter().flatten() {
        let model = scansurf::io::read_mesh(&mesh).unwrap();
        let stem = mesh.file_stem().unwrap().to_string_lossy().into_owned();
        let cloud = dir.path().join(format!("{stem}.xyz"));
        let xyz: String = model
            .positions
            .iter()
            .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
            .collect();
        std::fs::write(&cloud, xyz).unwrap();
        inputs.extend([mesh, cloud]);
    }
    for input in inputs {
        let v = features(&input, &dir.path().join("f.json"), &[]);
        let diag = f(&v, &["diagonal"]);
        for c in v["creases"].as_array().unwrap() {
            let pts: Vec<[f64; 3]> = serde_json::from_value(c["points"].clone()).unwrap();
            let len: f64 = pts
                .windows(2)
                .map(|w| {
                    (0..3)
                        .map(|k| (w[1][k] - w[0][k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .sum();
            assert!(
                len <= 0.05 * diag,
                "{}: crease {len} of {diag}",
                input.display()
            );
        }
    }
}

/// The regions PLY labels every point, coloured by region.
#[test]
fn regions_ply_labels_every_point() {
    let dir = tempfile::tempdir().unwrap();
    let input = repo().join("fixtures/spot.obj");
    let regions = dir.path().join("r.ply");
    let out = dir.path().join("f.json");
    let (code, _, err) = common::run(&[
        "features",
        input.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--regions-ply",
        regions.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let labelled: u64 = v["region_points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .sum();
    let r = scansurf::io::read_mesh(&regions).unwrap();
    let spot = scansurf::io::read_mesh(&input).unwrap();
    assert_eq!(r.positions.len(), spot.referenced_points().0.len());
    assert_eq!(labelled as usize, r.positions.len());
}

/// Bad options and inputs: a message naming the problem, exit 1 or 2, no file written.
#[test]
fn bad_options_and_inputs_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = repo().join("fixtures/spot.obj");
    let empty = dir.path().join("empty.xyz");
    std::fs::write(&empty, "").unwrap();
    let out = dir.path().join("f.json");
    let i = input.to_str().unwrap();
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["features", i, "-o", "f.txt"], "must end in .json"),
        (
            vec!["features", i, "-o", o, "--ply", "x.obj"],
            "must end in .ply",
        ),
        (vec!["features", i, "-o", o, "--angle", "200"], "--angle"),
        (vec!["features", i, "-o", o, "--angle", "nan"], "--angle"),
        (
            vec!["features", "/nonexistent/scan.ply", "-o", o],
            "scan.ply",
        ),
        (
            vec!["features", empty.to_str().unwrap(), "-o", o],
            "empty.xyz",
        ),
    ] {
        let (code, _, err) = common::run(&args);
        assert!(code != 0, "{args:?}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// `render --features` draws the creases in red and the corners in blue over the model;
/// a file that is not a features file is refused by name.
#[test]
fn render_draws_the_creases_and_corners() {
    let Some(dir) = parts() else { return };
    let out = common::scratch_dir("cli_features_render");
    let json = out.join("block.json");
    features(&dir.join("block.stl"), &json, &[]);
    let png = out.join("block.png");
    let args = |features: &Path| {
        common::run(&[
            "render",
            dir.join("block.stl").to_str().unwrap(),
            "-q",
            "--up",
            "z",
            "--size",
            "400x300",
            "-o",
            png.to_str().unwrap(),
            "--features",
            features.to_str().unwrap(),
        ])
    };
    let (code, _, err) = args(&json);
    assert_eq!(code, 0, "{err}");
    let img = scansurf::render::Image::load_png(&png).unwrap();
    let (mut red, mut blue) = (0, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            let [r, g, b] = img.get(x, y);
            red += usize::from(r > 180 && g < 90 && b < 90);
            blue += usize::from(b > 180 && r < 90 && g < 120);
        }
    }
    // Measured 5.8 % red and 0.18 % blue pixels at 400 x 300.
    let n = (img.width * img.height) as f64;
    assert!(red as f64 > 0.02 * n, "red {red}");
    assert!(blue as f64 > 0.0005 * n, "blue {blue}");
    std::fs::remove_file(&png).unwrap();
    let (code, _, err) = args(&dir.join("block.step"));
    assert!(
        code != 0 && err.contains("block.step") && err.contains("not a features file"),
        "{err}"
    );
    assert!(!png.exists());
}

/// `fit --features` carries the same summary in its report (counts, crease length, noise), from
/// a mesh and from a noisy cloud; without the flag the report has none.
#[test]
fn fit_report_carries_the_features_summary() {
    let Some(dir) = parts() else { return };
    let out = common::scratch_dir("cli_features_fit");
    for (input, method) in [("block.stl", "mesh"), ("bracket.xyz", "cloud")] {
        let step = out.join(format!("{input}.step"));
        let r = common::fit_report(&dir.join(input), &step, &["--patches", "150", "--features"]);
        let s = &r["features"];
        assert_eq!(s["method"], method, "{s}");
        // The same counts as `scansurf features` (see the tests above): make_parts' block has
        // 10 faces, 17 creases, 8 corners as a mesh; the bracket 9, 20, 10 as a cloud.
        let expect = if method == "mesh" {
            [10.0, 17.0, 8.0]
        } else {
            [9.0, 20.0, 10.0]
        };
        assert_eq!(
            [f(s, &["regions"]), f(s, &["creases"]), f(s, &["corners"])],
            expect,
            "{s}"
        );
        assert!(f(s, &["crease_length_rel"]) > 5.0, "{s}");
        assert!(f(&r, &["timings", "features"]) > 0.0);
        if method == "cloud" {
            let noise = f(s, &["noise"]);
            assert!(noise > 0.005 && noise < 0.02, "{s}");
        }
    }
    let r = common::fit_report(
        &dir.join("block.stl"),
        &out.join("plain.step"),
        &["--patches", "150"],
    );
    assert!(r.get("features").is_none());
}
