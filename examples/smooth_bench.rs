//! Benchmarks for the smoothing passes (docs/BENCHMARKS.md, "## smooth").
//!
//! ```text
//! # noisy fandisk: smooth NOISY.ply (written by shared/tools/peer_smooth.py), write OUT.ply and
//! # print our own error figures against the clean mesh
//! cargo run --release --example smooth_bench -- fandisk CLEAN.obj NOISY.ply OUT.ply \
//!     [--method anisotropic|arc|centroid] [--iterations N] [--step S] [--lambda L] [--r R]
//! # speed: 10 iterations on a generated noisy torus of about N vertices
//! cargo run --release --example smooth_bench -- speed 2000000 [--method M]
//! ```
//!
//! Meshes are read and written with the crate's own readers (`scansurf::io`).

use nalgebra::{Point3, Vector3};
use scansurf::mesh::Mesh;
use scansurf::smooth::{self, Adjacency, Control};
use std::time::Instant;

type Res<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn read(path: &str) -> Res<Mesh> {
    Ok(scansurf::io::read_mesh(std::path::Path::new(path))?)
}

fn write_ply(path: &str, m: &Mesh) -> Res<()> {
    Ok(scansurf::io::write_mesh(
        std::path::Path::new(path),
        m,
        scansurf::io::WriteOptions::default(),
    )?)
}

fn face_normals(m: &Mesh) -> Vec<Vector3<f64>> {
    (0..m.faces.len())
        .map(|f| {
            m.face_cross(f)
                .try_normalize(0.0)
                .unwrap_or_else(Vector3::zeros)
        })
        .collect()
}

/// Angle in degrees between the normals of the two faces of each interior edge.
fn edge_angles(m: &Mesh, adj: &Adjacency) -> Vec<Option<f64>> {
    let n = face_normals(m);
    (0..adj.edges.len())
        .map(|e| {
            let fs = adj.faces_of_edge(e);
            (fs.len() == 2).then(|| {
                n[fs[0] as usize]
                    .dot(&n[fs[1] as usize])
                    .clamp(-1.0, 1.0)
                    .acos()
                    .to_degrees()
            })
        })
        .collect()
}

/// Error figures of `ours` against `clean` (same connectivity), the script's three plus the
/// feature-edge angle change.
fn report(clean: &Mesh, ours: &Mesh, adj: &Adjacency, feature_deg: f64) {
    let el = adj
        .edges
        .iter()
        .map(|e| (clean.positions[e[0] as usize] - clean.positions[e[1] as usize]).norm())
        .sum::<f64>()
        / adj.edges.len() as f64;
    let d = clean
        .positions
        .iter()
        .zip(&ours.positions)
        .map(|(a, b)| (a - b).norm())
        .sum::<f64>()
        / clean.positions.len() as f64
        / el;
    let (nc, no) = (face_normals(clean), face_normals(ours));
    let mut ang: Vec<f64> = nc
        .iter()
        .zip(&no)
        .map(|(a, b)| a.dot(b).clamp(-1.0, 1.0).acos().to_degrees())
        .collect();
    let mean = ang.iter().sum::<f64>() / ang.len() as f64;
    ang.sort_by(f64::total_cmp);
    // numpy's default (linear) percentile.
    let rank = 0.95 * (ang.len() - 1) as f64;
    let (lo, hi) = (rank.floor() as usize, rank.ceil() as usize);
    let p95 = ang[lo] + (ang[hi] - ang[lo]) * (rank - lo as f64);
    let (ac, ao) = (edge_angles(clean, adj), edge_angles(ours, adj));
    let (mut n, mut abs, mut signed) = (0usize, 0.0, 0.0);
    for (c, o) in ac.iter().zip(&ao) {
        if let (Some(c), Some(o)) = (c, o) {
            if *c > feature_deg {
                n += 1;
                abs += (o - c).abs();
                signed += o - c;
            }
        }
    }
    println!(
        "dist/el {d:.3}  normal err mean {mean:.2} deg p95 {p95:.2}  feature edges (> {feature_deg} deg): {n}, angle change mean |.| {:.2} deg, signed {:.2} deg",
        abs / n.max(1) as f64,
        signed / n.max(1) as f64
    );
}

struct Opts {
    method: String,
    iterations: Option<usize>,
    step: Option<f64>,
    lambda: Option<f64>,
    r: Option<f64>,
    passes: Option<usize>,
    sigma: Option<f64>,
    free_boundary: bool,
    no_volume: bool,
}

fn parse_opts(args: &[String]) -> Res<Opts> {
    let mut o = Opts {
        method: "anisotropic".into(),
        iterations: None,
        step: None,
        lambda: None,
        r: None,
        passes: None,
        sigma: None,
        free_boundary: false,
        no_volume: false,
    };
    let mut i = 0;
    while i < args.len() {
        if args[i] == "--free-boundary" {
            o.free_boundary = true;
            i += 1;
            continue;
        }
        if args[i] == "--no-volume" {
            o.no_volume = true;
            i += 1;
            continue;
        }
        let v = args.get(i + 1).ok_or("missing value")?;
        match args[i].as_str() {
            "--method" => o.method = v.clone(),
            "--iterations" => o.iterations = Some(v.parse()?),
            "--step" => o.step = Some(v.parse()?),
            "--lambda" => o.lambda = Some(v.parse()?),
            "--r" => o.r = Some(v.parse()?),
            "--passes" => o.passes = Some(v.parse()?),
            "--sigma" => o.sigma = Some(v.parse()?),
            a => return Err(format!("unknown option {a}").into()),
        }
        i += 2;
    }
    Ok(o)
}

/// Runs the chosen method; `--step` and `--lambda` for anisotropic are in mean edge lengths
/// (squared for the step).
fn run(m: &mut Mesh, adj: &Adjacency, o: &Opts) -> Res<smooth::SmoothReport> {
    let ctl = Control::default();
    let l = m.mean_edge_length();
    Ok(match o.method.as_str() {
        "anisotropic" => {
            let mut p = smooth::AnisotropicParams::default();
            if let Some(n) = o.iterations {
                p.iterations = n;
            }
            p.step = o.step.map(|s| s * l * l);
            p.lambda = o.lambda.map(|x| x * l);
            if let Some(r) = o.r {
                p.r = r;
            }
            if let Some(x) = o.passes {
                p.guide_passes = x;
            }
            if let Some(x) = o.sigma {
                p.guide_sigma = x;
            }
            p.fix_boundary = !o.free_boundary;
            p.preserve_volume = !o.no_volume;
            smooth::anisotropic(m, adj, &p, &ctl)?
        }
        "arc" => {
            let mut p = smooth::ArcParams::default();
            if let Some(n) = o.iterations {
                p.iterations = n;
            }
            if let Some(s) = o.step {
                p.step = s;
            }
            p.fix_boundary = !o.free_boundary;
            smooth::arc(m, adj, &p, &ctl)?
        }
        "centroid" => {
            let mut p = smooth::CentroidParams::default();
            if let Some(n) = o.iterations {
                p.iterations = n;
            }
            if let Some(s) = o.step {
                p.step = s;
            }
            smooth::centroid(m, adj, &p, None, &ctl)?
        }
        x => return Err(format!("unknown method {x}").into()),
    })
}

/// A noisy torus of about `n` vertices (grid of u x v, v = 2u).
fn torus(n: usize) -> Mesh {
    let nu = ((n as f64 / 2.0).sqrt().round() as usize).max(3);
    let nv = 2 * nu;
    let (rr, r) = (3.0, 1.0);
    let mut m = Mesh::default();
    let mut seed = 12345u64;
    let mut rnd = || {
        // xorshift64*, uniform in [-0.5, 0.5)
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        (seed.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let h = 2.0 * std::f64::consts::PI * r / nu as f64;
    for j in 0..nv {
        let b = 2.0 * std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let a = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            let rad = r + 0.3 * h * rnd();
            m.positions.push(Point3::new(
                (rr + rad * a.cos()) * b.cos(),
                (rr + rad * a.cos()) * b.sin(),
                rad * a.sin(),
            ));
        }
    }
    let id = |i: usize, j: usize| ((j % nv) * nu + (i % nu)) as u32;
    for j in 0..nv {
        for i in 0..nu {
            m.faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            m.faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    m
}

/// CPU seconds (user + system, all threads) this process has used so far; Linux only, 0 elsewhere.
/// The shared benchmark machine is often loaded, so CPU time is the figure that carries over.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the parenthesised command name; utime and stime are the 12th and 13th.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11).and_then(|x| x.parse().ok()).unwrap_or(0.0)
        + f.get(12).and_then(|x| x.parse().ok()).unwrap_or(0.0);
    ticks / 100.0
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("fandisk") if args.len() >= 4 => {
            let clean = read(&args[1])?;
            // NOISY is a PLY file, or "noise:S" for Gaussian noise of S mean edge lengths along the
            // vertex normals (seed 7), made here.
            let mut m = match args[2].strip_prefix("noise:") {
                Some(s) => {
                    let mut m = clean.clone();
                    let n = scansurf::mesh::normals::vertex_normals(&m);
                    let sigma = s.parse::<f64>()? * m.mean_edge_length();
                    let mut seed = 7u64;
                    let mut uni = || {
                        seed ^= seed >> 12;
                        seed ^= seed << 25;
                        seed ^= seed >> 27;
                        ((seed.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 + 0.5)
                            / (1u64 << 53) as f64
                    };
                    for (p, n) in m.positions.iter_mut().zip(n) {
                        let g =
                            (-2.0 * uni().ln()).sqrt() * (2.0 * std::f64::consts::PI * uni()).cos();
                        *p += n * (sigma * g);
                    }
                    m
                }
                None => read(&args[2])?,
            };
            if m.faces != clean.faces {
                return Err("noisy mesh's faces differ from the clean mesh's".into());
            }
            let o = parse_opts(&args[4..])?;
            let adj = Adjacency::build(&m)?;
            print!("noisy  ");
            report(&clean, &m, &adj, 30.0);
            let rep = run(&mut m, &adj, &o)?;
            print!("ours   ");
            report(&clean, &m, &adj, 30.0);
            println!("{}", serde_json::to_string(&rep)?);
            write_ply(&args[3], &m)?;
        }
        Some("speed") if args.len() >= 2 => {
            let n: usize = args[1].parse()?;
            let mut o = parse_opts(&args[2..])?;
            o.iterations = o.iterations.or(Some(10));
            let mut m = torus(n);
            println!(
                "torus: {} vertices, {} faces, {} threads",
                m.positions.len(),
                m.faces.len(),
                rayon::current_num_threads()
            );
            let (t, c0) = (Instant::now(), cpu_seconds());
            let adj = Adjacency::build(&m)?;
            let (ta, c1) = (t.elapsed().as_secs_f64(), cpu_seconds());
            let rep = run(&mut m, &adj, &o)?;
            let c2 = cpu_seconds();
            println!(
                "adjacency {ta:.2} s wall ({:.2} s cpu), {} x{} {:.2} s wall ({:.2} s cpu), total {:.2} s wall ({:.2} s cpu)",
                c1 - c0,
                rep.method,
                rep.iterations,
                rep.seconds,
                c2 - c1,
                t.elapsed().as_secs_f64(),
                c2 - c0
            );
        }
        _ => {
            eprintln!("usage: smooth_bench fandisk CLEAN.obj NOISY.ply OUT.ply [options] | speed N [options]");
            std::process::exit(2);
        }
    }
    Ok(())
}
