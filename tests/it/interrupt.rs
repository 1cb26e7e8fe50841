//! SIGINT and SIGKILL in the middle of `scansurf fit`: afterwards the output directory holds no
//! STEP file (or, had the run already finished writing it, a complete one) and no temporary file.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn start_fit(out_dir: &Path) -> std::process::Child {
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .arg("fit")
        .arg(&input)
        .arg("-o")
        .arg(out_dir.join("X.step"))
        .arg("--iges")
        .arg(out_dir.join("X.igs"))
        .arg("--quiet")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start scansurf fit")
}

fn wait(child: &mut std::process::Child) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "scansurf did not stop"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The directory holds nothing, or only complete outputs; returns the names left.
fn check_dir(dir: &Path) -> Vec<String> {
    let names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    for n in &names {
        assert!(
            !n.ends_with(".tmp"),
            "stray temporary file {n} in {names:?}"
        );
        if n == "X.step" {
            let text = std::fs::read_to_string(dir.join(n)).unwrap();
            assert!(
                text.trim_end().ends_with("END-ISO-10303-21;"),
                "partial X.step"
            );
        }
    }
    names
}

#[test]
fn sigint_mid_run_leaves_no_output() {
    for delay_ms in [150u64, 500] {
        let dir = tempfile::tempdir().unwrap();
        let mut child = start_fit(dir.path());
        std::thread::sleep(Duration::from_millis(delay_ms));
        assert!(
            child.try_wait().unwrap().is_none(),
            "fit finished before the signal"
        );
        let ok = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .expect("run kill");
        assert!(ok.success());
        let status = wait(&mut child);
        let mut err = String::new();
        std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
        assert_eq!(status.code(), Some(130), "exit status {status:?}: {err}");
        assert!(err.contains("interrupted"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        let left = check_dir(dir.path());
        assert!(left.is_empty(), "after SIGINT at {delay_ms} ms: {left:?}");
    }
}

#[test]
fn sigkill_mid_run_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let mut child = start_fit(dir.path());
    std::thread::sleep(Duration::from_millis(400));
    assert!(
        child.try_wait().unwrap().is_none(),
        "fit finished before the signal"
    );
    child.kill().unwrap();
    wait(&mut child);
    let left = check_dir(dir.path());
    assert!(left.is_empty(), "after SIGKILL: {left:?}");
}
