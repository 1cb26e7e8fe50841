//! Fuzzes the mesh adjacency builders (`mesh::Topology::build` and the CSR
//! `mesh::adjacency::Adjacency::build` the smoothers use) on arbitrary small face lists:
//! repeated vertices, degenerate faces, edges shared by many faces, unreferenced vertices.
//! Faces index within the vertex list (the readers guarantee it), except when the first byte
//! asks for out-of-range indices, which `Adjacency::build` must reject with an `Err`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use nalgebra::Point3;
use scansurf::mesh::adjacency::Adjacency;
use scansurf::mesh::{Mesh, Topology};

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let out_of_range = data[0] & 0x80 != 0;
    let nv = (data[0] & 0x3f) as usize + 1;
    let positions: Vec<Point3<f64>> = (0..nv)
        .map(|i| {
            let b = data.get(1 + i % (data.len() - 1)).copied().unwrap_or(0) as f64;
            Point3::new(i as f64, b, (i * 7 % 5) as f64)
        })
        .collect();
    let faces: Vec<[u32; 3]> = data[1..]
        .chunks_exact(3)
        .map(|c| {
            let m = if out_of_range { 256 } else { nv };
            [c[0] as usize % m, c[1] as usize % m, c[2] as usize % m].map(|v| v as u32)
        })
        .collect();
    let mesh = Mesh {
        positions,
        normals: None,
        faces,
    };
    let in_range = mesh.faces.iter().flatten().all(|&v| (v as usize) < nv);
    match Adjacency::build(&mesh) {
        Ok(adj) => {
            assert!(in_range);
            assert!(adj.fits(&mesh));
            for v in 0..nv {
                for &n in adj.neighbors_of(v) {
                    assert!(adj.neighbors_of(n as usize).contains(&(v as u32)));
                }
            }
        }
        Err(_) => assert!(!in_range),
    }
    if in_range {
        let topo = Topology::build(&mesh);
        let _ = topo.is_closed_manifold();
        let _ = topo.boundary_edge_count();
    }
});
