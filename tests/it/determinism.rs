//! Every subcommand, run twice with `RAYON_NUM_THREADS=1` and once with `=2` on the same small
//! input, writes byte-identical outputs. Each run writes into its own directory under the same
//! file names (STEP and IGES headers carry the output's name); the STEP/IGES time stamp is pinned
//! with `SOURCE_DATE_EPOCH`; JSON reports are compared without their wall-clock fields
//! (`timings`, `seconds`, `time_s`).

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// Runs `args` (with `{dir}` replaced by a fresh directory) under `threads` rayon threads and
/// returns the bytes of `outputs` (names inside that directory) and the stdout.
fn run(args: &[&str], outputs: &[&str], threads: usize) -> Vec<(String, Vec<u8>)> {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let args: Vec<String> = args.iter().map(|a| a.replace("{dir}", d)).collect();
    let out = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args(&args)
        .arg("--quiet")
        .env("RAYON_NUM_THREADS", threads.to_string())
        .env("SOURCE_DATE_EPOCH", "1700000000")
        .output()
        .expect("run scansurf");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut files = vec![("stdout".to_string(), out.stdout)];
    for name in outputs {
        let mut bytes = std::fs::read(dir.path().join(name)).unwrap();
        if name.ends_with(".json") {
            bytes = without_timings(&bytes);
        }
        files.push((name.to_string(), bytes));
    }
    files
}

/// Keys of wall-clock measurements in the reports.
fn is_time(key: &str) -> bool {
    matches!(key, "timings" | "seconds" | "time_s") || key.ends_with("_seconds")
}

/// A JSON report without its wall-clock fields (run time differs run to run).
fn without_timings(bytes: &[u8]) -> Vec<u8> {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, _| !is_time(k));
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v: serde_json::Value = serde_json::from_slice(bytes).expect("report is JSON");
    strip(&mut v);
    serde_json::to_vec_pretty(&v).unwrap()
}

fn assert_deterministic(args: &[&str], outputs: &[&str]) {
    let a = run(args, outputs, 1);
    let b = run(args, outputs, 1);
    let c = run(args, outputs, 2);
    for ((name, x), ((_, y), (_, z))) in a.iter().zip(b.iter().zip(c.iter())) {
        assert!(
            !x.is_empty() || name == "stdout",
            "{args:?}: {name} is empty"
        );
        assert!(x == y, "{args:?}: {name} differs between two 1-thread runs");
        assert!(x == z, "{args:?}: {name} differs between 1 and 2 threads");
    }
}

#[test]
fn inspect_is_deterministic() {
    let input = fixture("holes/spot_holes.ply");
    assert_deterministic(&["inspect", input.to_str().unwrap(), "--json"], &[]);
}

#[test]
fn smooth_is_deterministic() {
    let input = fixture("spot.obj");
    assert_deterministic(
        &[
            "smooth",
            input.to_str().unwrap(),
            "-o",
            "{dir}/s.ply",
            "--report",
            "{dir}/s.json",
        ],
        &["s.ply", "s.json"],
    );
}

#[test]
fn render_is_deterministic() {
    let input = fixture("spot.obj");
    assert_deterministic(
        &[
            "render",
            input.to_str().unwrap(),
            "-o",
            "{dir}/r.png",
            "--size",
            "200x150",
        ],
        &["r.png"],
    );
}

#[test]
fn fill_holes_is_deterministic() {
    let input = fixture("holes/spot_holes.ply");
    assert_deterministic(
        &[
            "fill-holes",
            input.to_str().unwrap(),
            "-o",
            "{dir}/f.ply",
            "--report",
            "{dir}/f.json",
        ],
        &["f.ply", "f.json"],
    );
}

#[test]
fn reconstruct_is_deterministic() {
    let input = fixture("spot.obj");
    assert_deterministic(
        &[
            "reconstruct",
            input.to_str().unwrap(),
            "-o",
            "{dir}/r.ply",
            "--resolution",
            "0.5",
            "--report",
            "{dir}/r.json",
        ],
        &["r.ply", "r.json"],
    );
}

#[test]
fn fit_is_deterministic() {
    let input = fixture("spot.obj");
    assert_deterministic(
        &[
            "fit",
            input.to_str().unwrap(),
            "-o",
            "{dir}/m.step",
            "--iges",
            "{dir}/m.igs",
            "--report",
            "{dir}/m.json",
            "--patches",
            "40",
        ],
        &["m.step", "m.igs", "m.json"],
    );
}
