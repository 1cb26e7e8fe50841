//! `scansurf render` and `inspect` on scanner files, through the binary.

use scansurf::render::Image;
use std::path::Path;
use std::process::Command;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args(args)
        .output()
        .expect("run scansurf");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn fixture(n: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(n)
        .display()
        .to_string()
}

#[test]
fn renders_mesh_and_cloud_shaded() {
    let dir = tempfile::tempdir().unwrap();
    for input in ["spot.obj", "spot.laz"] {
        let png = dir.path().join(format!("{input}.png"));
        let (code, _, err) = run(&[
            "render",
            &fixture(input),
            "-o",
            png.to_str().unwrap(),
            "--view",
            "side",
            "--size",
            "400x400",
            "--quiet",
        ]);
        assert_eq!(code, 0, "{err}");
        let s = Image::load_png(&png).unwrap().stats([255, 255, 255]);
        assert!(s.foreground_fraction > 0.3, "{input}: {s:?}");
        assert!(s.grey_levels >= 20, "{input}: {s:?}");
    }
}

#[test]
fn against_cloud_colours_with_legend() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("d.png");
    let (code, _, err) = run(&[
        "render",
        &fixture("spot.obj"),
        "-o",
        png.to_str().unwrap(),
        "--against",
        &fixture("spot.las"),
        "--size",
        "400x300",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let s = Image::load_png(&png).unwrap().stats([255, 255, 255]);
    assert!(s.colored_fraction > 0.3, "{s:?}");
}

#[test]
fn render_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("x.jpg");
    let (code, _, err) = run(&["render", &fixture("spot.obj"), "-o", bad.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("x.jpg") && err.contains("PNG"), "{err}");
    let png = dir.path().join("x.png");
    let (code, _, err) = run(&[
        "render",
        &fixture("spot.obj"),
        "-o",
        png.to_str().unwrap(),
        "--view",
        "diagonal",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("diagonal"), "{err}");
    assert!(!png.exists());
}

#[test]
fn inspect_reports_scans() {
    let (code, out, err) = run(&["inspect", &fixture("spot_2scans.e57"), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["scans"], 2);
    assert_eq!(v["vertices"], 1981);
}
