//! Renders the pictures in `docs/images/` (or another directory): the spot and bunny meshes,
//! their vertices as point clouds, a deviation-coloured render, and a patch network with its
//! patch boundaries (plain and deviation-coloured).
//!
//!     cargo run --release --example render_gallery [OUT_DIR] [WIDTHxHEIGHT]
//!
//! The bunny is read from `$SCANSURF_SHARED_DATA` or `../shared/data` when present.

use nalgebra::Point3;
use scansurf::io::read_mesh;
use scansurf::render::{parse_size, render_mesh, ColorScale, RenderOptions, View};
use scansurf::Mesh;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn shared(name: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("SCANSURF_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let p = dir.join(name);
    p.exists().then_some(p)
}

fn save(
    out: &Path,
    name: &str,
    mesh: &Mesh,
    scalars: Option<(&[f64], ColorScale)>,
    lines: &[Vec<Point3<f64>>],
    o: &RenderOptions,
) -> Result<(), Box<dyn std::error::Error>> {
    let t = Instant::now();
    let img = render_mesh(mesh, scalars, lines, o)?;
    let dt = t.elapsed().as_secs_f64();
    let p = out.join(name);
    img.save_png(&p)?;
    let s = img.stats(o.background);
    println!(
        "{}: {:.3} s, {} KB, foreground {:.2}, grey levels {}, coloured {:.2}",
        p.display(),
        dt,
        std::fs::metadata(&p)?.len() / 1024,
        s.foreground_fraction,
        s.grey_levels,
        s.colored_fraction
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = PathBuf::from(args.get(1).map(String::as_str).unwrap_or("docs/images"));
    let (width, height) = parse_size(args.get(2).map(String::as_str).unwrap_or("800x600"))?;
    std::fs::create_dir_all(&out)?;
    let o = RenderOptions {
        width,
        height,
        ..Default::default()
    };
    let spot = read_mesh(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj"))?;
    save(&out, "spot_iso.png", &spot, None, &[], &o)?;
    let side = RenderOptions {
        view: View::Side,
        ..o.clone()
    };
    save(&out, "spot_side.png", &spot, None, &[], &side)?;
    let cloud = Mesh::from_points(spot.positions.clone(), None);
    save(&out, "spot_cloud.png", &cloud, None, &[], &o)?;
    // A made-up signed "deviation": height above the middle, to show the colour map.
    let c = spot.aabb().ok_or("empty")?.center();
    let dev: Vec<f64> = spot.positions.iter().map(|p| 0.01 * (p.y - c.y)).collect();
    let sc = ColorScale::auto(&dev)?;
    save(&out, "spot_deviation.png", &spot, Some((&dev, sc)), &[], &o)?;
    // A patch network like a fitted STEP file: a bumpy sphere made of 6 x 3 x 3 patches,
    // each tessellated on its own, with the patch boundaries drawn; then coloured by the
    // bumps' height (a stand-in for a deviation report).
    let (net, boundaries, bump) = patch_sphere(3, 24);
    save(&out, "patches_iso.png", &net, None, &boundaries, &o)?;
    let sc = ColorScale::auto(&bump)?;
    save(
        &out,
        "patches_deviation.png",
        &net,
        Some((&bump, sc)),
        &boundaries,
        &o,
    )?;
    if let Some(b) = shared("stanford-bunny.obj") {
        let bunny = read_mesh(&b)?;
        save(&out, "bunny_iso.png", &bunny, None, &[], &o)?;
        let cloud = Mesh::from_points(bunny.positions.clone(), None);
        save(&out, "bunny_cloud.png", &cloud, None, &[], &o)?;
    }
    Ok(())
}

/// A bumpy sphere as a network of `6 k^2` patches (a cube's faces split k x k, projected),
/// each tessellated with `n / k` segments per side; returns the mesh, the patch boundaries,
/// and the bump height per vertex.
fn patch_sphere(k: usize, n: usize) -> (Mesh, Vec<Vec<Point3<f64>>>, Vec<f64>) {
    let bump = |d: nalgebra::Vector3<f64>| {
        0.04 * (5.0 * d.x).sin() * (4.0 * d.y).cos() * (3.0 * d.z + 1.0).sin()
    };
    let on = |face: usize, u: f64, v: f64| -> (Point3<f64>, f64) {
        let c = match face {
            0 => nalgebra::Vector3::new(1.0, v, -u),
            1 => nalgebra::Vector3::new(-1.0, v, u),
            2 => nalgebra::Vector3::new(u, 1.0, -v),
            3 => nalgebra::Vector3::new(u, -1.0, v),
            4 => nalgebra::Vector3::new(u, v, 1.0),
            _ => nalgebra::Vector3::new(-u, v, -1.0),
        };
        let d = c.normalize();
        let h = bump(d);
        (Point3::from(d * (1.0 + h)), h)
    };
    let mut mesh = Mesh::default();
    let mut lines = Vec::new();
    let mut heights = Vec::new();
    let m = n / k; // segments per patch side
    for face in 0..6 {
        for pi in 0..k {
            for pj in 0..k {
                let base = mesh.positions.len() as u32;
                let uv = |i: usize, j: usize| {
                    (
                        -1.0 + 2.0 * (pi * m + i) as f64 / n as f64,
                        -1.0 + 2.0 * (pj * m + j) as f64 / n as f64,
                    )
                };
                for j in 0..=m {
                    for i in 0..=m {
                        let (u, v) = uv(i, j);
                        let (p, h) = on(face, u, v);
                        mesh.positions.push(p);
                        heights.push(h);
                    }
                }
                let id = |i: usize, j: usize| base + (j * (m + 1) + i) as u32;
                for j in 0..m {
                    for i in 0..m {
                        mesh.faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                        mesh.faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                    }
                }
                // The patch's four boundary curves, finely sampled.
                let fine = 8 * m;
                let curve = |f: &dyn Fn(f64) -> (f64, f64)| -> Vec<Point3<f64>> {
                    (0..=fine)
                        .map(|s| {
                            let (a, b) = f(s as f64 / fine as f64);
                            let (u0, v0) = uv(0, 0);
                            let (u1, v1) = uv(m, m);
                            on(face, u0 + a * (u1 - u0), v0 + b * (v1 - v0)).0
                        })
                        .collect()
                };
                lines.push(curve(&|t| (t, 0.0)));
                lines.push(curve(&|t| (1.0, t)));
                lines.push(curve(&|t| (1.0 - t, 1.0)));
                lines.push(curve(&|t| (0.0, 1.0 - t)));
            }
        }
    }
    (mesh, lines, heights)
}
