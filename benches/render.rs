//! Renderer speed: 1,000,000-triangle meshes at 1600x1200 (the target is under 2 s on 2 cores),
//! and a 1,000,000-point cloud.
//!
//!     cargo bench --bench render
//!
//! Prints the best of five renders (PNG encoding timed separately). Figures go to
//! docs/BENCHMARKS.md.

mod common;
use common::best_of;
use nalgebra::Point3;
use scansurf::io::read_mesh;
use scansurf::render::{render_mesh, RenderOptions};
use scansurf::Mesh;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A bumpy UV sphere with exactly `2 nu nv` triangles.
fn bumpy_sphere(nu: usize, nv: usize) -> Mesh {
    let mut positions = Vec::with_capacity(nu * (nv + 1));
    for j in 0..=nv {
        let th = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let ph = std::f64::consts::TAU * i as f64 / nu as f64;
            let r = 1.0 + 0.05 * (7.0 * ph).sin() * (5.0 * th).sin();
            positions.push(Point3::new(
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin(),
            ));
        }
    }
    let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
    let mut faces = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            faces.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
            faces.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh {
        positions,
        normals: None,
        faces,
    }
}

/// One step of midpoint subdivision (each triangle into four).
fn subdivide(m: &Mesh) -> Mesh {
    let mut positions = m.positions.clone();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut faces = Vec::with_capacity(4 * m.faces.len());
    for f in &m.faces {
        let mut e = [0u32; 3];
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            e[k] = *mid.entry(key).or_insert_with(|| {
                positions.push(nalgebra::center(
                    &m.positions[a as usize],
                    &m.positions[b as usize],
                ));
                (positions.len() - 1) as u32
            });
        }
        faces.push([f[0], e[0], e[2]]);
        faces.push([e[0], f[1], e[1]]);
        faces.push([e[2], e[1], f[2]]);
        faces.push([e[0], e[1], e[2]]);
    }
    Mesh {
        positions,
        normals: None,
        faces,
    }
}

fn shared(name: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("SCANSURF_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let p = dir.join(name);
    p.exists().then_some(p)
}

fn bench(name: &str, mesh: &Mesh, opts: &RenderOptions) {
    let mut img = None;
    let s = best_of(5, || {
        img = Some(render_mesh(mesh, None, &[], opts).expect("render"))
    });
    let Some(img) = img else { return };
    let t = Instant::now();
    let png = img.encode_png().expect("png");
    let enc = t.elapsed().as_secs_f64();
    let st = img.stats(opts.background);
    println!(
        "{name}: {} v, {} f, {}x{} ss{}: render {:.3} s (best of 5), PNG encode {:.3} s ({} KB), \
         foreground {:.2}, grey levels {}",
        mesh.positions.len(),
        mesh.faces.len(),
        opts.width,
        opts.height,
        opts.supersample,
        s,
        enc,
        png.len() / 1024,
        st.foreground_fraction,
        st.grey_levels
    );
}

fn main() {
    println!("threads: {}", rayon::current_num_threads());
    let opts = RenderOptions::default();
    let sphere = bumpy_sphere(1000, 500);
    bench("bumpy sphere", &sphere, &opts);
    bench(
        "bumpy sphere, no supersampling",
        &sphere,
        &RenderOptions {
            supersample: 1,
            ..opts.clone()
        },
    );
    if let Some(p) = shared("stanford-bunny.obj") {
        let bunny = read_mesh(&p).expect("bunny");
        let big = subdivide(&subdivide(&bunny));
        bench("bunny subdivided twice", &big, &opts);
        let cloud = Mesh::from_points(big.positions.clone(), None);
        bench("bunny subdivided twice, vertices as a cloud", &cloud, &opts);
    } else {
        eprintln!("no shared data: bunny runs skipped");
    }
}
