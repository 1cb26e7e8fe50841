//! Every subcommand on every file of the hostile-input corpus `tests/bad_inputs/` (written by
//! `cargo run --release --example gen_bad_inputs`). Each run must either fail with a non-zero
//! exit code and a message that names the input file, leaving nothing in the output directory,
//! or succeed with a valid output; never panic, never hang.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Upper bound for one run on a tiny file; a run past it counts as a hang.
const HANG: Duration = Duration::from_secs(90);

fn corpus() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_inputs");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/bad_inputs exists")
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.len() >= 30, "corpus has {} files", files.len());
    files
}

struct Outcome {
    code: i32,
    stderr: String,
}

/// Runs scansurf with `args`, killing it after [`HANG`].
fn run(args: &[&str]) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let err_path = dir.path().join("stderr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_scansurf"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .spawn()
        .expect("run scansurf");
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > HANG {
            let _ = child.kill();
            let _ = child.wait();
            panic!("scansurf {args:?} hung (killed after {HANG:?})");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stderr = std::fs::read_to_string(&err_path).unwrap_or_default();
    Outcome {
        // A signal (abort, SIGSEGV) has no code: -1 fails the checks below.
        code: status.code().unwrap_or(-1),
        stderr,
    }
}

/// What a successful run must have written.
fn valid_output(path: &Path) -> Result<(), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("no output {}: {e}", path.display()))?;
    match path.extension().and_then(|e| e.to_str()) {
        Some("png") => {
            if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
                Ok(())
            } else {
                Err("output is not a PNG".into())
            }
        }
        Some("step") => {
            let text = String::from_utf8_lossy(&bytes);
            if text.starts_with("ISO-10303-21;") && text.trim_end().ends_with("END-ISO-10303-21;") {
                Ok(())
            } else {
                Err("output is not a complete STEP file".into())
            }
        }
        _ => {
            let m = scansurf::io::read_mesh(path).map_err(|e| format!("output unreadable: {e}"))?;
            if m.positions.is_empty() {
                Err("output has no vertices".into())
            } else {
                Ok(())
            }
        }
    }
}

/// Runs `command` (with its extra arguments, the output named `out.EXT`) on every corpus file.
/// Returns one line per file: `name: ok` or `name: error <first line of the message>`.
fn check_command(command: &str, out_ext: &str, extra: &[&str]) -> Vec<String> {
    let mut problems = Vec::new();
    let mut table = Vec::new();
    for input in corpus() {
        let out_dir = tempfile::tempdir().unwrap();
        let out = out_dir.path().join(format!("out.{out_ext}"));
        let mut args = vec![command, input.to_str().unwrap()];
        if command != "inspect" {
            args.push("-o");
            args.push(out.to_str().unwrap());
        }
        args.extend_from_slice(extra);
        args.push("--quiet");
        let o = run(&args);
        let name = input.file_name().unwrap().to_string_lossy().into_owned();
        let say = |p: &mut Vec<String>, what: String| p.push(format!("{command} {name}: {what}"));
        if o.stderr.contains("panicked") || o.stderr.contains("RUST_BACKTRACE") {
            say(&mut problems, format!("panic:\n{}", o.stderr));
            continue;
        }
        let left: Vec<String> = std::fs::read_dir(out_dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        if o.code == 0 {
            if command != "inspect" {
                if let Err(e) = valid_output(&out) {
                    say(&mut problems, e);
                }
                if left.len() != 1 {
                    say(&mut problems, format!("stray files {left:?}"));
                }
            }
            table.push(format!("{name}: ok"));
        } else {
            let first = o.stderr.lines().next().unwrap_or("").to_string();
            if o.code < 0 {
                say(&mut problems, format!("killed by a signal: {}", o.stderr));
            }
            if !o.stderr.contains(&name) {
                say(
                    &mut problems,
                    format!("message does not name the file: {first}"),
                );
            }
            if !o.stderr.contains("error") || first.trim_end().ends_with(':') {
                say(&mut problems, format!("message names no problem: {first}"));
            }
            if !left.is_empty() {
                say(&mut problems, format!("left files behind: {left:?}"));
            }
            table.push(format!("{name}: error {first}"));
        }
    }
    println!("{command}:\n  {}", table.join("\n  "));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    table
}

#[test]
fn inspect_every_bad_input() {
    check_command("inspect", "txt", &[]);
}

#[test]
fn smooth_every_bad_input() {
    check_command("smooth", "ply", &["--iterations", "3"]);
}

#[test]
fn render_every_bad_input() {
    check_command("render", "png", &["--size", "64x48"]);
}

#[test]
fn reconstruct_every_bad_input() {
    check_command("reconstruct", "ply", &["--resolution", "0.3"]);
}

#[test]
fn fill_holes_every_bad_input() {
    check_command("fill-holes", "ply", &[]);
}

#[test]
fn fit_every_bad_input() {
    let table = check_command("fit", "step", &["--patches", "6"]);
    // The flat scan: record what fit does with it (an open sheet or a clear error).
    let flat = table
        .iter()
        .find(|l| l.starts_with("coplanar.xyz"))
        .unwrap();
    println!("fit on a flat scan -> {flat}");
}
