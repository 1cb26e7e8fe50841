//! Round trips through every writer and reader.

use nalgebra::{Point3, Vector3};
use scansurf::io::{read_mesh, write_mesh, WriteOptions};
use scansurf::Mesh;
use std::path::Path;

fn tetra(with_normals: bool) -> Mesh {
    let positions = vec![
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(1.0, 0.0, 0.0),
        Point3::new(0.0, 1.0, 0.0),
        Point3::new(0.0, 0.0, 1.0 / 3.0),
    ];
    let normals = with_normals.then(|| {
        positions
            .iter()
            .map(|p: &Point3<f64>| (p.coords - Vector3::new(0.25, 0.25, 0.1)).normalize())
            .collect()
    });
    Mesh {
        positions,
        normals,
        faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
    }
}

fn roundtrip(name: &str, mesh: &Mesh, ascii: bool) -> Mesh {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    write_mesh(&p, mesh, WriteOptions { ascii }).unwrap();
    read_mesh(&p).unwrap()
}

#[test]
fn ply_binary_and_ascii_exact() {
    for ascii in [false, true] {
        let m = tetra(true);
        let r = roundtrip("t.ply", &m, ascii);
        assert_eq!(r.positions, m.positions);
        assert_eq!(r.faces, m.faces);
        let (a, b) = (r.normals.unwrap(), m.normals.unwrap());
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).norm() < 1e-6);
        }
    }
}

#[test]
fn obj_exact_with_and_without_normals() {
    for n in [false, true] {
        let m = tetra(n);
        let r = roundtrip("t.obj", &m, false);
        assert_eq!(r, m);
    }
}

#[test]
fn stl_binary_and_ascii() {
    for ascii in [false, true] {
        let m = tetra(false);
        let r = roundtrip("t.stl", &m, ascii);
        // STL has no shared vertices: compare triangles corner by corner, by position.
        assert_eq!(r.faces.len(), m.faces.len());
        assert_eq!(r.positions.len(), m.positions.len(), "corners not welded");
        for (fr, fm) in r.faces.iter().zip(&m.faces) {
            for k in 0..3 {
                let (a, b) = (r.positions[fr[k] as usize], m.positions[fm[k] as usize]);
                assert!((a - b).norm() < 1e-6, "{a} {b}");
            }
        }
    }
}

#[test]
fn xyz_points_and_normals() {
    let m = tetra(true);
    let r = roundtrip("t.xyz", &m, false);
    assert_eq!(r.positions, m.positions);
    assert_eq!(r.normals, m.normals);
    assert!(r.faces.is_empty());
    let r = roundtrip("t.csv", &tetra(false), false);
    assert_eq!(r.positions.len(), 4);
    assert!(r.normals.is_none());
}

#[test]
fn point_cloud_ply() {
    let m = Mesh::from_points(tetra(false).positions, None);
    let r = roundtrip("c.ply", &m, false);
    assert_eq!(r, m);
}

#[test]
fn stl_refuses_point_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("c.stl");
    let m = Mesh::from_points(tetra(false).positions, None);
    assert!(write_mesh(&p, &m, WriteOptions::default()).is_err());
    assert!(!p.exists());
}

#[test]
fn tristrips_fixtures_match_obj() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let obj = read_mesh(&root.join("spot.obj")).unwrap();
    for f in ["spot_tristrips_le.ply", "spot_tristrips_be.ply"] {
        let m = read_mesh(&root.join(f)).unwrap();
        assert_eq!(m.faces.len(), 5856, "{f}");
        assert_eq!(m.faces, obj.faces, "{f}");
        for (a, b) in m.positions.iter().zip(&obj.positions) {
            assert!((a - b).norm() < 1e-6);
        }
    }
}

#[test]
fn bunny_large_mesh_roundtrip_binary_ply() {
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/stanford-bunny.obj");
    if !bunny.exists() {
        eprintln!("skipping: {} not present", bunny.display());
        return;
    }
    let m = read_mesh(&bunny).unwrap();
    let r = roundtrip("b.ply", &m, false);
    assert_eq!(r, m);
}
