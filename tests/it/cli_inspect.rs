//! `scansurf inspect` on good and bad input, through the binary.

use std::path::{Path, PathBuf};

use crate::common::run as scansurf;

fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(name)
}

#[test]
fn bunny_figures() {
    let b = shared("stanford-bunny.obj");
    if !b.exists() {
        eprintln!("skipping: no shared data");
        return;
    }
    let (code, out, err) = scansurf(&["inspect", b.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["vertices"], 35947);
    assert_eq!(v["referenced_vertices"], 34834);
    assert_eq!(v["faces"], 69451);
    let mut sizes: Vec<u64> = v["boundary_loops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["vertices"].as_u64().unwrap())
        .collect();
    sizes.sort();
    assert_eq!(sizes, vec![22, 39, 40, 42, 80]);
    assert_eq!(v["verdict"], "open: 5 holes");
    let (code, out, _) = scansurf(&["inspect", b.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(out.contains("open: 5 holes"));
}

#[test]
fn closed_fixture_and_tristrips() {
    let f = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot_tristrips_le.ply");
    let (code, out, _) = scansurf(&["inspect", f.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["faces"], 5856);
    assert_eq!(v["verdict"], "closed manifold");
    assert_eq!(v["euler_characteristic"], 2);
}

/// Writes `bytes` to a file named `name` in a fresh directory, runs inspect on it, and checks
/// the exit code is non-zero, the message names the file and contains `expect`, and no panic.
fn bad(name: &str, bytes: &[u8], expect: &str) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    let (code, out, err) = scansurf(&["inspect", p.to_str().unwrap()]);
    assert_ne!(code, 0, "{name}: accepted; stdout {out}");
    assert!(
        err.contains(name),
        "{name}: message does not name the file: {err}"
    );
    assert!(
        err.to_lowercase().contains(&expect.to_lowercase()),
        "{name}: expected '{expect}' in: {err}"
    );
    assert!(!err.contains("panicked"), "{name}: {err}");
    assert_eq!(
        err.trim().lines().count(),
        1,
        "{name}: one line expected: {err}"
    );
}

fn ply_header(format: &str, nv: usize, nf: usize) -> Vec<u8> {
    format!("ply\nformat {format} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n").into_bytes()
}

#[test]
fn empty_files() {
    for n in ["e.ply", "e.obj", "e.stl", "e.xyz"] {
        bad(n, b"", "empty");
    }
}

#[test]
fn truncated_binary_ply() {
    let mut b = ply_header("binary_little_endian", 3, 1);
    b.extend_from_slice(&[0u8; 36]); // vertices
    b.extend_from_slice(&[3u8, 0, 0, 0, 0]); // face cut short
    bad("t.ply", &b, "byte");
    let mut b = ply_header("binary_big_endian", 100, 0);
    b.extend_from_slice(&[0u8; 50]);
    bad("t2.ply", &b, "truncated");
}

#[test]
fn truncated_binary_stl() {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&5u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 120]);
    bad("t.stl", &b, "truncated");
}

#[test]
fn truncated_ascii() {
    let mut b = ply_header("ascii", 3, 1);
    b.extend_from_slice(b"0 0 0\n1 0 0\n");
    bad("a.ply", &b, "truncated");
    bad(
        "a.stl",
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
        "truncated",
    );
}

#[test]
fn wrong_headers() {
    bad("w.ply", b"plx\nformat ascii 1.0\n", "not a PLY");
    bad("w2.ply", b"ply\nformat ascii 2.0\nend_header\n", "version");
    bad(
        "w3.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float32x x\nend_header\n",
        "line 4",
    );
    bad(
        "w.stl",
        b"this is not an stl file at all, it is too short",
        "STL",
    );
}

#[test]
fn nan_and_inf() {
    bad("n.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "line 2");
    bad("n.xyz", b"0 0 0\n1 inf 0\n", "non-finite");
    let mut b = ply_header("ascii", 3, 0);
    b.extend_from_slice(b"0 0 0\n1 0 0\n0 -inf 0\n");
    bad("n.ply", &b, "non-finite");
    let mut b = ply_header("binary_little_endian", 1, 0);
    for c in [0f32, f32::NAN, 0.0] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    bad("nb.ply", &b, "non-finite");
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 12]);
    for c in [0f32, 0.0, f32::INFINITY, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    b.extend_from_slice(&[0, 0]);
    bad("n.stl", &b, "non-finite");
}

#[test]
fn faces_past_vertex_list() {
    bad("f.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4");
    let mut b = ply_header("ascii", 3, 1);
    b.extend_from_slice(b"0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    bad("f.ply", &b, "vertex index 3");
    let mut b = ply_header("binary_little_endian", 3, 1);
    b.extend_from_slice(&[0u8; 36]);
    b.push(3);
    for i in [0i32, 1, 77] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    bad("fb.ply", &b, "vertex index 77");
}

#[test]
fn non_utf8_text() {
    bad("u.obj", b"v 0 0 0\nv 1 \xff\xfe 0\n", "UTF-8");
    bad("u.xyz", b"\x00\x01\x02\xff\xff", "UTF-8");
    bad("u.stl", b"solid \xff\xfe\xfd", "STL");
}

#[test]
fn syntax_errors_name_lines() {
    bad("s.obj", b"v 0 0 0\nv 1 0\n", "line 2");
    bad("s.xyz", b"1 2 3\n4 5 six\n", "line 2");
    bad("s.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 zero 0\n", "line 8");
}

#[test]
fn directories_and_missing_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("scan.ply");
    std::fs::create_dir(&d).unwrap();
    let (code, _, err) = scansurf(&["inspect", d.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(
        err.contains("scan.ply") && err.contains("directory"),
        "{err}"
    );
    let m = dir.path().join("missing.obj");
    let (code, _, err) = scansurf(&["inspect", m.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(
        err.contains("missing.obj") && err.contains("No such file"),
        "{err}"
    );
}

#[test]
fn unknown_extension() {
    bad("scan.dat", b"1 2 3\n", "unknown extension");
}

#[test]
fn usage_errors_exit_2() {
    let (code, _, err) = scansurf(&["inspect"]);
    assert_eq!(code, 2, "{err}");
    let (code, out, _) = scansurf(&["--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("inspect"));
}
