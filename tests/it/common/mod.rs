//! Test support shared by the integration tests: the independent CAD checker
//! (`../shared/tools/cad_check.py`, OpenCASCADE) run from the repo's `.venv-check`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The checker's python and script; `None` outside CI when they are missing (the test then
/// prints SKIPPED), a panic in CI (CI=true), where `scripts/test.sh` must have created them.
pub fn checker() -> Option<(PathBuf, PathBuf)> {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = [repo.join(".venv-check/bin/python")]
        .into_iter()
        .find(|p| p.exists());
    // `$SCANSURF_SHARED_DATA/../tools` when the shared data lives elsewhere (see
    // tests/it/support/mod.rs), else `../shared/tools` beside the crate.
    let shared_tools = std::env::var_os("SCANSURF_SHARED_DATA")
        .map(|d| PathBuf::from(d).join("../tools/cad_check.py"));
    let script = shared_tools
        .into_iter()
        .chain([repo.join("../shared/tools/cad_check.py")])
        .find(|p| p.exists());
    match (python, script) {
        (Some(p), Some(s)) => Some((p, s)),
        _ if std::env::var_os("CI").is_some() => {
            panic!("CI: the CAD checker is missing (.venv-check or ../shared/tools/cad_check.py); run bash scripts/test.sh")
        }
        _ => None,
    }
}

pub fn cad_check(
    python: &Path,
    script: &Path,
    model: &Path,
    points: Option<&Path>,
) -> serde_json::Value {
    cad_check_with(python, script, model, points, &[])
}

/// [`cad_check`] with more arguments (e.g. `--no-jumps`, which skips the slow normal-jump
/// sampling of a model with many faces).
pub fn cad_check_with(
    python: &Path,
    script: &Path,
    model: &Path,
    points: Option<&Path>,
    extra: &[&str],
) -> serde_json::Value {
    let mut cmd = Command::new(python);
    cmd.arg(script).arg(model).args(extra);
    if let Some(p) = points {
        cmd.arg("--points").arg(p);
    }
    let out = cmd.output().expect("running cad_check.py");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.trim_start().starts_with('{'))
        .unwrap_or_else(|| {
            panic!(
                "cad_check printed no JSON for {}: {}\n{}",
                model.display(),
                stdout,
                String::from_utf8_lossy(&out.stderr)
            )
        });
    let v: serde_json::Value = serde_json::from_str(line).expect("cad_check JSON");
    println!("cad_check {}: {v}", model.display());
    v
}

/// Runs the scansurf binary with `args`; returns (exit code, stdout, stderr), -1 for a code
/// when a signal ended it.
pub fn run(args: &[&str]) -> (i32, String, String) {
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

/// The number at `path` in a JSON report (panics naming the path when it is missing).
pub fn json_f64(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[*k];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("{path:?} missing in {v}"))
}

/// Runs `scansurf fit INPUT -o OUT --report OUT.json -q EXTRA...`, asserts success and
/// returns the report.
pub fn fit_report(input: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let report = out.with_extension("json");
    let o = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .arg("fit")
        .arg(input)
        .arg("-o")
        .arg(out)
        .arg("--report")
        .arg(&report)
        .arg("-q")
        .args(extra)
        .output()
        .expect("run scansurf");
    assert!(
        o.status.success(),
        "fit {} failed ({:?}): {}",
        input.display(),
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&std::fs::read(&report).expect("read the report")).expect("JSON report")
}

/// A directory for the outputs of one computation shared by several tests:
/// `$CARGO_TARGET_TMPDIR/NAME` (under `target/`), emptied first. It stays after the run (a
/// shared result lives in a static, which is never dropped), so a failure can be looked at.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create the scratch directory");
    dir
}

/// The value of `cell`, computed by `make` on first use and shared by every test that checks
/// it (one expensive fit, several tests of its validity, accuracy and continuity). A panic in
/// `make` is kept: every test that shares the value fails with its message, without running
/// `make` again.
pub fn shared<T: Send + Sync>(
    cell: &'static std::sync::OnceLock<Result<T, String>>,
    make: impl FnOnce() -> T,
) -> &'static T {
    let result = cell.get_or_init(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(make)).map_err(|payload| {
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "(no message)".to_string())
        })
    });
    match result {
        Ok(v) => v,
        Err(msg) => panic!("the shared computation failed: {msg}"),
    }
}

/// `$SCANSURF_SHARED_DATA/../tools`, else `../shared/tools` beside the crate, when it holds
/// make_parts.py.
pub fn shared_tools() -> Option<PathBuf> {
    let dir = std::env::var_os("SCANSURF_SHARED_DATA")
        .map(|d| PathBuf::from(d).join("../tools"))
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/tools"));
    dir.join("make_parts.py").exists().then_some(dir)
}

/// Runs `../shared/tools/SCRIPT` with the checker's Python on `args` and returns the JSON
/// object it prints last (feature_check.py, part_check.py).
pub fn tool_json(script: &str, args: &[&Path]) -> serde_json::Value {
    let (py, _) = checker().expect("the checker venv (tests skip before without it)");
    let tools = shared_tools().expect("../shared/tools (tests skip before without it)");
    let o = std::process::Command::new(py)
        .arg(tools.join(script))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("run {script}: {e}"));
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_else(|| {
            panic!(
                "{script} printed no JSON: {text} {}",
                String::from_utf8_lossy(&o.stderr)
            )
        });
    println!(
        "{script} {}: {line}",
        args.first()
            .map_or(String::new(), |a| a.display().to_string())
    );
    serde_json::from_str(line).unwrap()
}

/// A model of the shared test data (`$SCANSURF_SHARED_DATA` when set, as in tests/it/support,
/// else `../shared/data`): `None` (the test skips) when it is missing, a failure under CI.
pub fn shared_model(name: &str) -> Option<PathBuf> {
    let data = std::env::var_os("SCANSURF_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let p = data.join(name);
    if p.exists() {
        Some(p)
    } else if std::env::var_os("CI").is_some() {
        panic!("CI: ../shared/data/{name} is missing");
    } else {
        eprintln!("SKIPPED: no ../shared/data/{name}");
        None
    }
}

/// Runs the generator `script` (make_parts.py, scripts/extra_parts.py or
/// scripts/half_scans.py: `script OUT_DIR ARGS...`) with the checker's `py` into a scratch
/// directory `name`; the directory.
pub fn make_with<S: AsRef<std::ffi::OsStr>>(
    py: &Path,
    script: &Path,
    name: &str,
    args: &[S],
) -> PathBuf {
    let dir = scratch_dir(name);
    let o = std::process::Command::new(py)
        .arg(script)
        .arg(&dir)
        .args(args)
        .output()
        .expect("run the part generator");
    assert!(
        o.status.success(),
        "{}: {}",
        script.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    dir
}

/// `scripts/extra_parts.py`'s stepped shaft (a turned part lying along x: seen from above, the
/// lower halves of its shoulders are thin one-sided crescents), made once per test run, as
/// make_parts writes its parts; `None` outside CI when the tools or the venv are missing.
pub fn stepped_part() -> Option<&'static PathBuf> {
    static PART: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let (py, _) = checker()?;
    make_parts()?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/extra_parts.py");
    Some(shared(&PART, || {
        make_with(&py, &script, "extra_parts_stepped", &["--parts", "stepped"])
    }))
}

/// make_parts' block and bracket (200,000 points, noise 0.01 mm; each as NAME.step, the exact
/// truth, NAME.stl, NAME.xyz and NAME-occluded.xyz, seen from above), made once per test run;
/// `None` outside CI when the tools or the checker's venv are missing.
pub fn make_parts() -> Option<&'static PathBuf> {
    static PARTS: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let (py, _) = checker()?;
    let Some(tools) = shared_tools() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI: ../shared/tools/make_parts.py is missing"
        );
        eprintln!("SKIPPED: no make_parts.py");
        return None;
    };
    Some(shared(&PARTS, || {
        make_with(
            &py,
            &tools.join("make_parts.py"),
            "make_parts",
            &["--parts", "block,bracket"],
        )
    }))
}
