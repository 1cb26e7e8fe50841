//! Writes the hostile-input corpus `tests/bad_inputs/` (run from the repository root:
//! `cargo run --release --example gen_bad_inputs`). Every file is small and deterministic; the
//! integration test `tests/it/bad_inputs.rs` runs every subcommand on every file. Regenerating
//! rewrites the whole directory, so edit this program, not the files.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

fn main() -> std::io::Result<()> {
    let dir = Path::new("tests/bad_inputs");
    if dir.exists() {
        fs::remove_dir_all(dir)?;
    }
    fs::create_dir_all(dir)?;
    let put = |name: &str, bytes: &[u8]| fs::write(dir.join(name), bytes);

    // --- point clouds (XYZ) ---
    put("empty.xyz", b"")?;
    put("whitespace_only.xyz", b"\n  \n\t\n")?;
    put("comments_only.xyz", b"# nothing here\n# at all\n")?;
    put("one_point.xyz", b"1 2 3\n")?;
    put("two_points.xyz", b"0 0 0\n1 1 1\n")?;
    put(
        "all_equal.xyz",
        xyz(&vec![[1.5, -2.0, 3.25]; 40]).as_bytes(),
    )?;
    let line: Vec<[f64; 3]> = (0..60)
        .map(|i| [i as f64 * 0.1, i as f64 * 0.2, 1.0])
        .collect();
    put("collinear.xyz", xyz(&line).as_bytes())?;
    put("coplanar.xyz", xyz(&grid(20, 0.05)).as_bytes())?;
    let mut dup = sphere(150, 1.0, [0.0; 3]);
    dup.extend(dup.clone());
    dup.extend(dup.clone());
    put("duplicated_points.xyz", xyz(&dup).as_bytes())?;
    put("nan.xyz", b"0 0 0\n1 0 0\nnan 1 0\n0 0 1\n")?;
    put("inf.xyz", b"0 0 0\n1 0 0\n0 inf 0\n0 0 1\n")?;
    put(
        "neg_inf_normal.xyz",
        b"0 0 0 0 0 1\n1 0 0 0 0 -inf\n0 1 0 0 0 1\n",
    )?;
    let huge: Vec<[f64; 3]> = sphere(200, 1e30, [0.0; 3]);
    put("huge_coords.xyz", xyz(&huge).as_bytes())?;
    let tiny: Vec<[f64; 3]> = sphere(200, 1e-30, [0.0; 3]);
    put("tiny_coords.xyz", xyz(&tiny).as_bytes())?;
    let mut far = sphere(150, 1.0, [0.0; 3]);
    far.extend(sphere(150, 1.0, [1e6, 0.0, 0.0]));
    put("far_components.xyz", xyz(&far).as_bytes())?;
    put("ragged_columns.xyz", b"0 0 0\n1 0\n0 1 0 5\n")?;
    put("words.xyz", b"x y z\nhello world again\n")?;
    put("invalid_utf8.xyz", b"0 0 0\n\xff\xfe\xfd 1 2\n")?;
    put("binary_noise.xyz", &noise(2048, 7))?;

    // --- PLY ---
    put(
        "ply_header_only.ply",
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
    )?;
    put(
        "ply_4billion_vertices.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0\0\0\0\0\0\0\0\0",
    )?;
    put(
        "ply_huge_face_count.ply",
        &[
            b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 4000000000\nproperty list uchar int vertex_indices\nend_header\n".as_slice(),
            &f32s(&[0., 0., 0., 1., 0., 0., 0., 1., 0.]),
            &[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0],
        ]
        .concat(),
    )?;
    let tet = tetra();
    let full = ply_binary(&tet.0, &tet.1);
    put("ply_truncated_binary.ply", &full[..full.len() - 17])?;
    put("ply_truncated_in_header.ply", &full[..40])?;
    put(
        "ply_wrong_magic.ply",
        &[b"plx\n".as_slice(), &full[4..]].concat(),
    )?;
    put(
        "ply_unknown_format.ply",
        b"ply\nformat binary_middle_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
    )?;
    put(
        "ply_no_xyz.ply",
        b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float a\nproperty float b\nend_header\n1 2\n3 4\n",
    )?;
    put(
        "ply_face_index_out_of_range.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
    )?;
    put(
        "ply_negative_index.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
    )?;
    put(
        "ply_ascii_short_row.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0\n0 1 0\n",
    )?;
    put(
        "ply_ascii_missing_rows.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n",
    )?;
    put(
        "ply_list_count_255.ply",
        &[
            b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".as_slice(),
            &f32s(&[0., 0., 0., 1., 0., 0., 0., 1., 0.]),
            &[255, 0, 0, 0, 0],
        ]
        .concat(),
    )?;
    put(
        "ply_nan_binary.ply",
        &ply_binary(
            &[[0.0, 0.0, 0.0], [f64::NAN, 1.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        ),
    )?;
    let holes = holey_grid(64);
    put("many_tiny_holes.ply", &ply_binary(&holes.0, &holes.1))?;

    // --- OBJ ---
    put("obj_only_faces.obj", b"f 1 2 3\n")?;
    put(
        "obj_face_index_out_of_range.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    )?;
    put(
        "obj_zero_index.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    )?;
    put(
        "obj_negative_index_too_far.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -5\n",
    )?;
    put(
        "obj_bad_number.obj",
        b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n",
    )?;
    put(
        "obj_single_triangle.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )?;
    put(
        "obj_degenerate_faces.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\nf 2 2 2\nf 3 3 1\n",
    )?;
    // Three triangles on the edge 1-2.
    put(
        "obj_nonmanifold_edge.obj",
        b"v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0\nv 0.5 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )?;
    // Two fans touching in one vertex (bow-tie).
    put(
        "obj_bowtie.obj",
        b"v 0 0 0\nv 1 1 0\nv 1 -1 0\nv -1 1 0\nv -1 -1 0\nf 1 2 3\nf 1 5 4\n",
    )?;
    let (tp, tf) = tetra();
    let mut flipped = tf.clone();
    flipped[1].swap(1, 2);
    flipped[3].swap(0, 1);
    put(
        "obj_inconsistent_orientation.obj",
        obj(&tp, &flipped).as_bytes(),
    )?;
    put(
        "obj_zero_area_faces.obj",
        b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 0 1 0\nf 1 2 3\nf 2 3 4\nf 1 2 5\n",
    )?;
    // Two triangles piercing each other.
    put(
        "obj_self_intersecting.obj",
        b"v 0 0 0\nv 2 0 0\nv 1 2 0\nv 1 1 -1\nv 1 1 1\nv 1.2 -1 0\nf 1 2 3\nf 4 5 6\n",
    )?;
    let mut two = tetra();
    let shift = [1e5, 1e5, 0.0];
    let n0 = two.0.len() as u32;
    let moved: Vec<[f64; 3]> = two
        .0
        .iter()
        .map(|p| [p[0] + shift[0], p[1] + shift[1], p[2]])
        .collect();
    let more: Vec<[u32; 3]> = two.1.iter().map(|f| f.map(|v| v + n0)).collect();
    two.0.extend(moved);
    two.1.extend(more);
    put("obj_far_components.obj", obj(&two.0, &two.1).as_bytes())?;
    put(
        "obj_unknown_statements.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nfoo bar\nf 1 2 3\n",
    )?;

    // --- STL ---
    let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let good = stl_binary(
        &[tri, [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]],
        2,
    );
    put("stl_truncated_binary.stl", &good[..good.len() - 20])?;
    put("stl_claims_million.stl", &stl_binary(&[tri], 1_000_000))?;
    put("stl_header_only.stl", &good[..84])?;
    put("stl_short.stl", &good[..50])?;
    put(
        "stl_nan.stl",
        &stl_binary(
            &[[[0.0, 0.0, 0.0], [f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]]],
            1,
        ),
    )?;
    put("stl_empty_solid.stl", b"solid empty\nendsolid empty\n")?;
    put(
        "stl_ascii_broken.stl",
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nendloop\nendfacet\nendsolid x\n",
    )?;
    put(
        "stl_ascii_two_vertices.stl",
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid x\n",
    )?;

    // --- names ---
    put("no_extension", b"0 0 0\n1 0 0\n0 1 0\n")?;
    put("unknown_extension.foo", b"0 0 0\n1 0 0\n0 1 0\n")?;
    let count = fs::read_dir(dir)?.count();
    println!("wrote {count} files to {}", dir.display());
    Ok(())
}

fn xyz(p: &[[f64; 3]]) -> String {
    let mut s = String::new();
    for q in p {
        let _ = writeln!(s, "{:e} {:e} {:e}", q[0], q[1], q[2]);
    }
    s
}

fn obj(p: &[[f64; 3]], f: &[[u32; 3]]) -> String {
    let mut s = String::new();
    for q in p {
        let _ = writeln!(s, "v {} {} {}", q[0], q[1], q[2]);
    }
    for t in f {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn ply_binary(p: &[[f64; 3]], f: &[[u32; 3]]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        p.len(),
        f.len()
    )
    .into_bytes();
    for q in p {
        for c in q {
            out.extend((*c as f32).to_le_bytes());
        }
    }
    for t in f {
        out.push(3);
        for v in t {
            out.extend(v.to_le_bytes());
        }
    }
    out
}

fn stl_binary(tris: &[[[f64; 3]; 3]], claimed: u32) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend(claimed.to_le_bytes());
    for t in tris {
        out.extend([0u8; 12]);
        for p in t {
            for c in p {
                out.extend((*c as f32).to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

/// Fibonacci sphere of `n` points.
fn sphere(n: usize, r: f64, c: [f64; 3]) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let rr = (1.0 - y * y).sqrt();
            let t = golden * i as f64;
            [
                c[0] + r * rr * t.cos(),
                c[1] + r * y,
                c[2] + r * rr * t.sin(),
            ]
        })
        .collect()
}

fn grid(n: usize, h: f64) -> Vec<[f64; 3]> {
    let mut v = Vec::new();
    for i in 0..n {
        for j in 0..n {
            v.push([i as f64 * h, j as f64 * h, 0.5]);
        }
    }
    v
}

fn tetra() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    (
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
}

/// An `n` x `n` quad grid on a gently curved sheet with every other quad of every other row
/// removed: about n²/4 one-quad holes.
fn holey_grid(n: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            p.push([x, y, 0.1 * (x * 3.0).sin() * (y * 2.0).cos()]);
        }
    }
    let id = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    let mut f = Vec::new();
    for i in 0..n {
        for j in 0..n {
            if i % 2 == 1 && j % 2 == 1 && i + 1 < n && j + 1 < n {
                continue;
            }
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, f)
}

/// Deterministic pseudo-random bytes (xorshift).
fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 24) as u8
        })
        .collect()
}
