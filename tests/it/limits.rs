//! `--max-memory`: an input or a grid that would need more than the budget fails before the
//! allocation with a message that names the file and suggests a coarser setting.

use crate::common::run;
use std::path::Path;

fn spot() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/spot.obj")
        .to_string_lossy()
        .into_owned()
}

#[test]
fn too_fine_a_patch_size_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.step");
    let (code, _, err) = run(&[
        "fit",
        &spot(),
        "-o",
        out.to_str().unwrap(),
        "--patch-size",
        "0.0005",
        "--max-memory",
        "1G",
        "--quiet",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("spot.obj") && err.contains("--max-memory 1.0 GiB"),
        "{err}"
    );
    assert!(err.contains("--patch-size"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn too_fine_a_resolution_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.ply");
    let (code, _, err) = run(&[
        "reconstruct",
        &spot(),
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "0.001",
        "--max-memory",
        "2G",
        "--quiet",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("spot.obj") && err.contains("--resolution"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn a_file_larger_than_the_budget_is_refused() {
    let (code, _, err) = run(&["inspect", &spot(), "--max-memory", "100K"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("spot.obj") && err.contains("--max-memory 100.0 KiB"),
        "{err}"
    );
    let (code, _, _) = run(&["inspect", &spot(), "--max-memory", "64M"]);
    assert_eq!(code, 0);
}

#[test]
fn a_bad_size_is_a_usage_error() {
    let (code, _, err) = run(&["inspect", &spot(), "--max-memory", "12Q"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--max-memory 12Q"), "{err}");
}
