//! `scansurf fit` end to end, checked by the independent OpenCASCADE reader
//! (`../shared/tools/cad_check.py`): the bunny acceptance of the fit issue, IGES, point clouds
//! without normals, determinism and bad options.

use crate::common;
use crate::common::{fit_report as fit, json_f64 as f};

use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_scansurf"))
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn bunny() -> Option<PathBuf> {
    common::shared_model("stanford-bunny.obj")
}

/// The bunny fit (default options, STEP and IGES), computed once and shared by the tests that
/// check it.
struct BunnyFit {
    input: PathBuf,
    step: PathBuf,
    iges: PathBuf,
    dir: PathBuf,
    report: serde_json::Value,
}

fn bunny_fit() -> Option<&'static BunnyFit> {
    static FIT: OnceLock<Result<BunnyFit, String>> = OnceLock::new();
    let input = bunny()?;
    Some(common::shared(&FIT, || {
        let dir = common::scratch_dir("cli_fit_bunny");
        let step = dir.join("bunny.step");
        let iges = dir.join("bunny.igs");
        let report = fit(&input, &step, &["--iges", iges.to_str().unwrap()]);
        BunnyFit {
            input,
            step,
            iges,
            dir,
            report,
        }
    }))
}

/// The fit issue's acceptance on the Stanford bunny (default options), by the fit's own report.
#[test]
fn slow_bunny_report_meets_the_bars() {
    let Some(b) = bunny_fit() else { return };
    let r = &b.report;
    let patches = f(r, &["patches"]);
    assert!(
        (patches - 1500.0).abs() <= 0.15 * 1500.0,
        "{patches} patches"
    );
    assert_eq!(r["closed"], true);
    assert_eq!(f(r, &["free_edges"]), 0.0);
    // Only the base holes are closed without data (0.4 % of the area).
    assert!(
        f(r, &["support", "unsupported_fraction"]) < 0.01,
        "{}",
        r["support"]
    );
    // Our own measure (exact edge parameters) of the normal jump: the bars, max 5 and
    // p95 1 degree (measured: max 3.2, p95 0.24, 0 of 14,100 samples over 5).
    assert!(
        f(r, &["continuity", "all_deg", "p95"]) <= 1.0,
        "{}",
        r["continuity"]
    );
    assert!(
        f(r, &["continuity", "all_deg", "max"]) <= 5.0
            && f(r, &["continuity", "samples_over_5_deg"]) == 0.0,
        "{}",
        r["continuity"]
    );
    let dev = &r["deviation"]["relative"];
    assert!(
        f(dev, &["mean"]) <= 2e-4 && f(dev, &["p99"]) <= 1e-3,
        "{dev}"
    );
    // Spike guard: at the crease of the base two interior section rows once ran onto the
    // bottom sheet (max 1.7e-3); with those rows rejected the max was 1.16e-3 at 16
    // intervals per side, 1.55e-3 at the 12 that patches this small get (the crease itself,
    // less finely sampled); 7.9e-4 since the implicit's blending band widened.
    assert!(f(dev, &["max"]) <= 1.6e-3, "{dev}");
    // Folds: patches whose normal turns more than 45 degrees away from the implicit's at
    // all four corners of some grid cell (measured: 1, a pit 1e-4 across on the flat base
    // near its rim; 5 with seed 003's 10 % overlap alone, before the implicit's blending band
    // widened).
    assert!(
        f(r, &["folds", "patches_over_45_deg"]) <= 3.0,
        "{}",
        r["folds"]
    );
    assert_eq!(f(r, &["sampling", "max_intervals"]), 12.0);
    // Patches under 0.06 mm (the bunny read as millimetres): every STEP face lies on a surface
    // extended by an apron, so that OpenCASCADE's point projection finds its edge points.
    assert_eq!(f(r, &["step", "extended_faces"]), patches, "{}", r["step"]);
}

/// The bunny STEP rendered back (issue 9): shaded, filling the frame, patch boundaries as dark
/// lines, hardly any orange back faces (folds). Measured on a 1,472-patch bunny STEP:
/// foreground 0.29, 229 grey levels, dark 0.30, coloured 0.0013.
#[test]
fn slow_bunny_step_renders() {
    let Some(b) = bunny_fit() else { return };
    let png = b.dir.join("bunny.png");
    let o = bin()
        .args(["render", "-q", "--view", "side", "--size", "480x360", "-o"])
        .arg(&png)
        .arg(&b.step)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let px = scansurf::render::Image::load_png(&png)
        .unwrap()
        .stats([255; 3]);
    assert!(
        px.foreground_fraction > 0.25 && px.grey_levels >= 60,
        "{px:?}"
    );
    assert!(
        px.dark_fraction > 0.08 && px.colored_fraction < 0.01,
        "{px:?}"
    );
}

/// Reads a bunny file (STEP or IGES) back through OpenCASCADE: valid with one B-spline face per
/// patch, the normal jump and the deviation within the bars: the max 5 degrees
/// (measured 3.2 on both, equal to ours: none of the 28,200 edge-point projections misses; 14.8
/// before the implicit's blending band widened and the net relaxed unrolled, one projection
/// caught in a fold at the rim of the base) and p95 (measured 0.24). The IGES file has the same
/// faces, the small ones trimmed surfaces (entity 144) on the same extended surfaces (with bare
/// entity 128 surfaces its p95 read 9.6). `None` when the checker is missing outside CI.
fn bunny_read_back(b: &BunnyFit, file: &std::path::Path) -> Option<serde_json::Value> {
    let Some((py, script)) = common::checker() else {
        eprintln!("SKIPPED: cad_check");
        return None;
    };
    let patches = f(&b.report, &["patches"]);
    let c = common::cad_check(&py, &script, file, Some(&b.input));
    assert_eq!(c["read_ok"], true);
    assert_eq!(c["reader_problems"].as_array().map(|a| a.len()), Some(0));
    assert_eq!(c["valid"], true);
    assert_eq!(f(&c, &["faces"]), patches);
    assert_eq!(f(&c, &["bspline_faces"]), patches);
    assert!(
        f(&c, &["normal_jump_deg", "p95"]) <= 0.5 && f(&c, &["normal_jump_deg", "max"]) <= 5.0,
        "{}",
        c["normal_jump_deg"]
    );
    let d = &c["deviation"];
    assert!(f(d, &["mean_rel"]) <= 2e-4, "{d}");
    assert!(f(d, &["p99_rel"]) <= 1e-3, "{d}");
    assert!(f(d, &["max_rel"]) <= 5e-3, "{d}");
    Some(c)
}

/// The bunny STEP file, read by OpenCASCADE: valid, accurate, one sewn closed shell, and its
/// projection-based normal jump agrees with our own measure.
#[test]
fn slow_bunny_step_reads_back_in_opencascade() {
    let Some(b) = bunny_fit() else { return };
    let Some(c) = bunny_read_back(b, &b.step) else {
        return;
    };
    // The STEP file is one sewn shell.
    assert_eq!(c["closed"], true);
    assert_eq!(f(&c, &["free_edges"]), 0.0);
    // OpenCASCADE's projection-based measure agrees with ours (exact edge parameters): on the
    // bare 0.0076 mm patches its projection missed 1 % of the edge points and its mean read
    // 1.08 deg against our 0.16.
    let (occ, ours) = (
        f(&c, &["normal_jump_deg", "mean"]),
        f(&b.report, &["continuity", "all_deg", "mean"]),
    );
    assert!(
        (occ - ours).abs() <= 0.25 * ours,
        "cad_check mean {occ} vs ours {ours}"
    );
}

/// The bunny IGES file, read by OpenCASCADE: valid and accurate, the same faces as the STEP.
#[test]
fn slow_bunny_iges_reads_back_in_opencascade() {
    let Some(b) = bunny_fit() else { return };
    bunny_read_back(b, &b.iges);
}

/// IGES 5.3 of the same network reads back with one B-spline face per patch; the STEP and IGES
/// files of two runs are byte-identical (including the header stamps).
#[test]
fn iges_reads_back_and_runs_are_deterministic() {
    let input = repo().join("fixtures/spot.obj");
    // Same file names in two directories: the names are part of the headers.
    let (d1, d2) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (a, b) = (d1.path().join("spot.step"), d2.path().join("spot.step"));
    let (ia, ib) = (d1.path().join("spot.igs"), d2.path().join("spot.igs"));
    let ra = fit(
        &input,
        &a,
        &["--patches", "300", "--iges", ia.to_str().unwrap()],
    );
    fit(
        &input,
        &b,
        &["--patches", "300", "--iges", ib.to_str().unwrap()],
    );
    assert!(
        std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
        "STEP files of two runs differ"
    );
    assert!(
        std::fs::read(&ia).unwrap() == std::fs::read(&ib).unwrap(),
        "IGES files of two runs differ"
    );
    assert_eq!(ra["closed"], true);
    assert!(f(&ra["deviation"]["relative"], &["mean"]) <= 3e-4);
    let Some((py, script)) = common::checker() else {
        eprintln!("SKIPPED: cad_check");
        return;
    };
    let c = common::cad_check(&py, &script, &ia, None);
    assert_eq!(c["read_ok"], true);
    assert_eq!(c["valid"], true);
    assert_eq!(f(&c, &["faces"]), f(&ra, &["patches"]));
    assert_eq!(f(&c, &["bspline_faces"]), f(&ra, &["patches"]));
}

/// The bunny's vertices alone, as a cloud without normals: normals are estimated and oriented,
/// the result is closed and within the bar.
#[test]
fn slow_bunny_cloud_without_normals() {
    let Some(input) = bunny() else { return };
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(&input).unwrap();
    let xyz: String = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| format!("{l}\n"))
        .collect();
    let cloud = dir.path().join("bunny.xyz");
    std::fs::write(&cloud, xyz).unwrap();
    let r = fit(&cloud, &dir.path().join("cloud.step"), &[]);
    assert_eq!(r["normal_source"], "Estimated");
    assert_eq!(r["closed"], true);
    assert!(
        f(&r["deviation"]["relative"], &["mean"]) <= 3e-4,
        "{}",
        r["deviation"]
    );
}

/// The bar for the other models, default options: spot, fandisk and cow (one test each,
/// so they run side by side) fit to a closed shell whose deviation from the input vertices has
/// mean_rel <= 3e-4 (our point inversion; for the cow also OpenCASCADE's, with validity and
/// sewing). The cow's horns are thinner than a voxel: before the medial voxels of
/// `polygonize::voxel_net` the net left them out and the mean was 3.7e-4.
fn other_model_meets_the_mean_deviation_bar(name: &str) {
    let Some(bunny) = bunny() else { return };
    let data = bunny.parent().unwrap().to_path_buf();
    let dir = tempfile::tempdir().unwrap();
    let input = data.join(format!("{name}.obj"));
    let step = dir.path().join(format!("{name}.step"));
    let r = fit(&input, &step, &[]);
    assert_eq!(r["closed"], true, "{name}");
    assert_eq!(f(&r, &["net", "components"]), 1.0, "{name}");
    assert!(
        f(&r["deviation"]["relative"], &["mean"]) <= 3e-4,
        "{name}: {}",
        r["deviation"]
    );
    // No patch's control points wander off the part (measured: spot 1.1e-3 of the diagonal,
    // the cow 3.6e-2, beside its horns and ears).
    assert_eq!(f(&r, &["control_net", "patches_outside"]), 0.0, "{name}");
    assert!(
        f(&r, &["control_net", "outside_max"]) < 0.06,
        "{name}: {}",
        r["control_net"]
    );
    // OpenCASCADE's deviation needs a tessellation of the whole STEP file (about a minute
    // per model here): checked on the cow, the model at risk.
    if name != "cow" {
        return;
    }
    let Some((py, script)) = common::checker() else {
        eprintln!("SKIPPED: cad_check");
        return;
    };
    let c = common::cad_check(&py, &script, &step, Some(&input));
    assert_eq!(c["valid"], true, "{name}: {c}");
    assert_eq!(c["closed"], true, "{name}: {c}");
    assert_eq!(f(&c, &["free_edges"]), 0.0, "{name}: {c}");
    assert!(f(&c["deviation"], &["mean_rel"]) <= 3e-4, "{name}: {c}");
}

#[test]
fn slow_spot_meets_the_mean_deviation_bar() {
    other_model_meets_the_mean_deviation_bar("spot");
}

#[test]
fn slow_fandisk_meets_the_mean_deviation_bar() {
    other_model_meets_the_mean_deviation_bar("fandisk");
}

#[test]
fn slow_cow_meets_the_mean_deviation_bar_and_reads_back() {
    other_model_meets_the_mean_deviation_bar("cow");
}

/// Surface the data does not back is measured and warned about: spot with everything above
/// y = 0.5 cut away (a quarter of its triangles), fitted with `--fill-holes implicit`, so the
/// implicit closes the opening by extrapolation, with spikes where its bridges disagree: 36 to
/// 41 % of the patch area lies more than half a patch from every input point (measured; the
/// spikes' area moves with the last bits of the local fits; the bunny's base holes are 0.4 %).
#[test]
fn extrapolated_area_is_reported_and_warned() {
    let mut mesh = scansurf::io::read_mesh(&repo().join("fixtures/spot.obj")).unwrap();
    let before = mesh.faces.len();
    let positions = mesh.positions.clone();
    mesh.faces
        .retain(|t| t.iter().all(|&i| positions[i as usize].y < 0.5));
    assert!(mesh.faces.len() < before * 4 / 5);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("spot_cut.ply");
    scansurf::io::write_mesh(&input, &mesh, Default::default()).unwrap();
    let (step, report) = (dir.path().join("t.step"), dir.path().join("t.json"));
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (code, _, err) = common::run(&[
        "fit",
        &path(&input),
        "-q",
        "-o",
        &path(&step),
        "--report",
        &path(&report),
        "--patches",
        "300",
        "--fill-holes",
        "implicit",
        "--close",
        "smooth",
    ]);
    assert_eq!(code, 0, "{err}");
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(r["closed"], true);
    let frac = f(&r, &["support", "unsupported_fraction"]);
    assert!(frac > 0.1 && frac < 0.6, "{}", r["support"]);
    assert!(
        err.contains("warning:") && err.contains("extrapolation"),
        "{err}"
    );
}

/// `--fill-holes rbf` and `planar` close a scan's holes with the local fills of `fill-holes`
/// before the fit: every hole of the fixture is filled, the deviation is still that of the
/// scan's own vertices (the fill's vertices are not measurements), the network is closed and
/// OpenCASCADE reads it as a valid closed shell.
#[test]
fn slow_local_hole_fills_before_the_fit() {
    let input = repo().join("fixtures/holes/spot_holes.ply");
    let scan = scansurf::io::read_mesh(&input).unwrap();
    let scan_points = scan.referenced_points().0.len() as f64;
    let dir = tempfile::tempdir().unwrap();
    for method in ["rbf", "planar"] {
        let step = dir.path().join(format!("{method}.step"));
        let r = fit(&input, &step, &["--fill-holes", method, "--patches", "300"]);
        let h = &r["hole_fill"];
        assert_eq!(h["method"], method);
        assert!(f(h, &["loops"]) >= 1.0, "{h}");
        assert_eq!(f(h, &["holes_filled"]), f(h, &["loops"]), "{h}");
        assert!(f(h, &["triangles_added"]) > 0.0, "{h}");
        assert_eq!(f(&r, &["input_points"]), scan_points);
        assert_eq!(r["closed"], true);
        assert_eq!(f(&r, &["free_edges"]), 0.0);
        let dev = &r["deviation"]["relative"];
        assert!(f(dev, &["mean"]) <= 3e-4, "{method}: {dev}");
        let Some((py, script)) = common::checker() else {
            eprintln!("SKIPPED: cad_check");
            continue;
        };
        let c = common::cad_check(&py, &script, &step, None);
        assert_eq!(c["valid"], true, "{method}: {c}");
        assert_eq!(c["closed"], true, "{method}: {c}");
        assert_eq!(f(&c, &["faces"]), f(&r, &["patches"]));
    }
    // A point cloud has no holes to fill locally: a clear error, no file.
    let cloud = dir.path().join("cloud.xyz");
    let xyz: String = scan
        .positions
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(&cloud, xyz).unwrap();
    let out = dir.path().join("cloud.step");
    let (cloud_arg, out_arg) = (cloud.to_str().unwrap(), out.to_str().unwrap());
    let (code, _, err) =
        common::run(&["fit", cloud_arg, "-q", "--fill-holes", "rbf", "-o", out_arg]);
    assert!(code != 0 && err.contains("needs a triangle mesh"), "{err}");
    assert!(err.contains("cloud.xyz") && !out.exists(), "{err}");
    // `implicit` leaves the closing to the implicit and reports no local fill; the default
    // (`auto`) fills a mesh's holes with the local RBF.
    let r = fit(
        &input,
        &dir.path().join("implicit.step"),
        &["--patches", "300", "--fill-holes", "implicit"],
    );
    assert!(r.get("hole_fill").is_none());
    let r = fit(&input, &dir.path().join("auto.step"), &["--patches", "300"]);
    assert_eq!(r["hole_fill"]["method"], "rbf", "{}", r["hole_fill"]);
    assert_eq!(
        f(&r["hole_fill"], &["holes_filled"]),
        f(&r["hole_fill"], &["loops"])
    );
}

/// Bad options fail before any work, with a message, and leave no file behind.
#[test]
fn bad_options_leave_nothing() {
    let input = repo().join("fixtures/spot.obj");
    let dir = tempfile::tempdir().unwrap();
    for (out, extra, needle) in [
        ("x.txt", vec![], "must end in"),
        ("x.step", vec!["--patches", "0"], "at least 1"),
        ("x.step", vec!["--tolerance=-1"], "tolerance"),
        ("x.step", vec!["--unit", "furlong"], "furlong"),
        (
            "x.step",
            vec!["--extend-surfaces", "sometimes"],
            "expected auto or never",
        ),
        ("x.step", vec!["--iges", "y.dxf"], "must end in"),
        (
            "x.step",
            vec!["--fill-holes", "glue"],
            "expected auto, implicit, none, rbf",
        ),
        // Outputs in a directory that does not exist: refused before the fit, not after it.
        ("missing/x.step", vec![], "output directory"),
        (
            "x.step",
            vec!["--report", "no-such-dir-of-scansurf/r.json"],
            "output directory",
        ),
        (
            "x.step",
            vec!["--preview", "no-such-dir-of-scansurf/p.png"],
            "output directory",
        ),
    ] {
        let o = bin()
            .arg("fit")
            .arg(&input)
            .arg("-o")
            .arg(dir.path().join(out))
            .args(&extra)
            .arg("-q")
            .output()
            .unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{extra:?}: {err}");
        assert!(!err.contains("panicked"));
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "{extra:?}"
        );
    }
}
