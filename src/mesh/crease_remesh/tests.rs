use super::*;
use nalgebra::Rotation3;
use std::collections::HashMap;

/// A unit cube's faces, each an n x n grid of squares cut into two triangles, labelled by face
/// (0..6), welded, counter-clockwise from outside.
fn fine_cube(n: usize) -> LabelledMesh {
    let mut index: HashMap<[usize; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut labels = Vec::new();
    let mut vertex = |g: [usize; 3]| -> u32 {
        *index.entry(g).or_insert_with(|| {
            positions.push(Point3::new(
                g[0] as f64 / n as f64,
                g[1] as f64 / n as f64,
                g[2] as f64 / n as f64,
            ));
            (positions.len() - 1) as u32
        })
    };
    // Face by its normal axis and side; (u, v) axes chosen so u x v points outward.
    for (label, (axis, side)) in [(0, 0), (0, 1), (1, 0), (1, 1), (2, 0), (2, 1)]
        .into_iter()
        .enumerate()
    {
        let (mut u, mut v) = ((axis + 1) % 3, (axis + 2) % 3);
        if side == 0 {
            std::mem::swap(&mut u, &mut v);
        }
        let at = |i: usize, j: usize| {
            let mut g = [0; 3];
            g[axis] = side * n;
            g[u] = i;
            g[v] = j;
            g
        };
        for i in 0..n {
            for j in 0..n {
                let q = [
                    vertex(at(i, j)),
                    vertex(at(i + 1, j)),
                    vertex(at(i + 1, j + 1)),
                    vertex(at(i, j + 1)),
                ];
                triangles.push([q[0], q[1], q[2]]);
                triangles.push([q[0], q[2], q[3]]);
                labels.push(label as u32);
                labels.push(label as u32);
            }
        }
    }
    LabelledMesh {
        positions,
        triangles,
        labels,
    }
}

fn transformed(m: &LabelledMesh, r: &Rotation3<f64>) -> LabelledMesh {
    LabelledMesh {
        positions: m.positions.iter().map(|p| r * p).collect(),
        ..m.clone()
    }
}

/// Distance of `p` (in the cube's own frame) from the unit cube's surface, and how many of
/// its coordinates are 0 or 1 (2 on an edge, 3 at a corner).
fn off_cube(p: &Point3<f64>) -> (f64, usize) {
    let inside = p
        .iter()
        .map(|&x| x.min(1.0 - x))
        .fold(f64::INFINITY, f64::min);
    let on = p
        .iter()
        .filter(|&&x| x.abs() < 1e-9 || (x - 1.0).abs() < 1e-9)
        .count();
    (inside.abs(), on)
}

fn edges(m: &LabelledMesh) -> HashMap<(u32, u32), Vec<u32>> {
    let mut e: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (f, t) in m.triangles.iter().enumerate() {
        for i in 0..3 {
            e.entry(key(t[i], t[(i + 1) % 3]))
                .or_default()
                .push(f as u32);
        }
    }
    e
}

fn check_cube(out: &LabelledMesh, back: &Rotation3<f64>, target: f64) {
    let p: Vec<Point3<f64>> = out.positions.iter().map(|q| back * q).collect();
    // Closed 2-manifold, every edge between two triangles, Euler characteristic 2.
    let e = edges(out);
    assert!(e.values().all(|fs| fs.len() == 2));
    assert_eq!(
        out.positions.len() as i64 - e.len() as i64 + out.triangles.len() as i64,
        2
    );
    // On the cube, its 8 corners kept.
    for q in &p {
        assert!(off_cube(q).0 < 1e-9, "{q} off the cube");
    }
    assert_eq!(p.iter().filter(|q| off_cube(q).1 == 3).count(), 8);
    // Every edge between two labels lies on a cube edge, and each cube edge is covered.
    let mut crease_length = 0.0;
    for (&(a, b), fs) in &e {
        if out.labels[fs[0] as usize] != out.labels[fs[1] as usize] {
            let (pa, pb) = (p[a as usize], p[b as usize]);
            assert!(off_cube(&pa).1 >= 2 && off_cube(&pb).1 >= 2, "{pa} {pb}");
            crease_length += (pa - pb).norm();
        }
    }
    assert!((crease_length - 12.0).abs() < 1e-9, "{crease_length}");
    // Each triangle within one face of the cube (all its corners share the face's plane).
    for (t, &l) in out.triangles.iter().zip(&out.labels) {
        let axis = (l / 2) as usize;
        let side = (l % 2) as f64;
        for &v in t {
            assert!((p[v as usize][axis] - side).abs() < 1e-9);
        }
    }
    // Edge lengths near the target.
    let mut lengths: Vec<f64> = e
        .keys()
        .map(|&(a, b)| (p[a as usize] - p[b as usize]).norm())
        .collect();
    lengths.sort_by(f64::total_cmp);
    let median = lengths[lengths.len() / 2];
    assert!(
        median > 0.7 * target && median < 1.3 * target,
        "median {median}"
    );
    let max = lengths[lengths.len() - 1];
    assert!(max < 4.0 / 3.0 * target + 1e-9, "max {max}");
}

#[test]
fn a_fine_cube_is_coarsened_keeping_its_edges_and_corners() {
    let m = fine_cube(24);
    let out = remesh(&m, &RemeshOptions::new(0.2)).unwrap();
    assert!(out.triangles.len() < m.triangles.len() / 4);
    check_cube(&out, &Rotation3::identity(), 0.2);
}

#[test]
fn a_rotated_cube_keeps_its_edges_too() {
    let r = Rotation3::from_euler_angles(0.3, 0.52, -0.2);
    let m = transformed(&fine_cube(20), &r);
    let out = remesh(&m, &RemeshOptions::new(0.25)).unwrap();
    check_cube(&out, &r.inverse(), 0.25);
}

#[test]
fn a_coarse_cube_is_refined() {
    let m = fine_cube(1);
    let out = remesh(&m, &RemeshOptions::new(0.2)).unwrap();
    assert!(out.triangles.len() > 100);
    check_cube(&out, &Rotation3::identity(), 0.2);
}

#[test]
fn bad_input_is_an_error() {
    let mut m = fine_cube(2);
    m.labels.pop();
    assert!(remesh(&m, &RemeshOptions::new(0.2)).is_err());
    let m = fine_cube(2);
    assert!(remesh(&m, &RemeshOptions::new(0.0)).is_err());
    // A triangle repeating a vertex; an edge of three triangles (a fin on a cube edge).
    let mut bad = m.clone();
    bad.triangles.push([0, 0, 1]);
    bad.labels.push(0);
    let e = remesh(&bad, &RemeshOptions::new(0.2)).unwrap_err();
    assert!(e.to_string().contains("repeats a vertex"), "{e}");
    let mut fin = m.clone();
    let t = fin.triangles[0];
    fin.positions.push(Point3::new(-1.0, -1.0, -1.0));
    fin.triangles
        .push([t[1], t[0], (fin.positions.len() - 1) as u32]);
    fin.labels.push(0);
    let e = remesh(&fin, &RemeshOptions::new(0.2)).unwrap_err();
    assert!(e.to_string().contains("both walk edge"), "{e}");
    assert!(remesh(&m, &RemeshOptions::new(f64::NAN)).is_err());
}

/// A closed cylinder of radius 1 and height 1 around z: side (region 0) an `n` x `n / 4` grid,
/// caps (regions 1 bottom, 2 top) polar grids of `n` segments and `n / 8` rings.
fn fine_cylinder(n: usize) -> LabelledMesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut labels = Vec::new();
    let rings = n / 8;
    let rows = n / 4;
    let at = |r: f64, k: usize, z: f64| {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        Point3::new(r * a.cos(), r * a.sin(), z)
    };
    // Side rows 0..=rows at z = row / rows; vertex (row, k) = row * n + k.
    for row in 0..=rows {
        for k in 0..n {
            positions.push(at(1.0, k, row as f64 / rows as f64));
        }
    }
    let side = |row: usize, k: usize| (row * n + k % n) as u32;
    for row in 0..rows {
        for k in 0..n {
            let q = [
                side(row, k),
                side(row, k + 1),
                side(row + 1, k + 1),
                side(row + 1, k),
            ];
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
            labels.extend([0, 0]);
        }
    }
    // Caps: inner rings 1..rings (ring `rings` is the side's rim), and a centre.
    for (label, z, rim_row) in [(1u32, 0.0, 0usize), (2, 1.0, rows)] {
        let centre = positions.len() as u32;
        positions.push(Point3::new(0.0, 0.0, z));
        let first = positions.len();
        for ring in 1..rings {
            for k in 0..n {
                positions.push(at(ring as f64 / rings as f64, k, z));
            }
        }
        let v = |ring: usize, k: usize| -> u32 {
            if ring == rings {
                side(rim_row, k)
            } else {
                (first + (ring - 1) * n + k % n) as u32
            }
        };
        let mut add = |t: [u32; 3]| {
            // Bottom faces -z, top faces +z.
            triangles.push(if label == 1 { [t[0], t[2], t[1]] } else { t });
            labels.push(label);
        };
        for k in 0..n {
            add([centre, v(1, k), v(1, k + 1)]);
            for ring in 1..rings {
                add([v(ring, k), v(ring + 1, k), v(ring + 1, k + 1)]);
                add([v(ring, k), v(ring + 1, k + 1), v(ring, k + 1)]);
            }
        }
    }
    LabelledMesh {
        positions,
        triangles,
        labels,
    }
}

#[test]
fn a_round_crease_gets_edges_short_enough_for_the_tolerance() {
    let m = fine_cylinder(256);
    let tolerance = 2e-3;
    let mut opts = RemeshOptions::new(0.5);
    let chord = |out: &LabelledMesh| -> (f64, usize) {
        let e = edges(out);
        let mut worst: f64 = 0.0;
        let mut n = 0;
        for (&(a, b), fs) in &e {
            assert_eq!(fs.len(), 2);
            if out.labels[fs[0] as usize] != out.labels[fs[1] as usize] {
                let m = nalgebra::center(&out.positions[a as usize], &out.positions[b as usize]);
                worst = worst.max(1.0 - m.coords.xy().norm());
                n += 1;
            }
        }
        (worst, n)
    };
    let (coarse, n_coarse) = chord(&remesh(&m, &opts).unwrap());
    opts.crease_tolerance = Some(tolerance);
    let out = remesh(&m, &opts).unwrap();
    let (fine, n_fine) = chord(&out);
    // Without: edges of about 0.5, sagitta 0.03; with: within the tolerance (and the input
    // polygon's own sagitta, 7.5e-5), with about sqrt(8 R tol) = 0.13 long edges.
    assert!(coarse > 5.0 * tolerance, "{coarse}");
    assert!(fine < tolerance + 1e-4, "{fine}");
    assert!(
        n_fine > 2 * n_coarse && n_fine < 2 * 2 * 80,
        "{n_coarse} -> {n_fine}"
    );
    // The caps stay flat and the side round.
    for (t, &l) in out.triangles.iter().zip(&out.labels) {
        for &v in t {
            let p = out.positions[v as usize];
            match l {
                0 => assert!((p.coords.xy().norm() - 1.0).abs() < 1e-3, "{p}"),
                1 => assert!(p.z.abs() < 1e-12),
                _ => assert!((p.z - 1.0).abs() < 1e-12),
            }
        }
    }
}

/// Smallest angle of a triangle, degrees.
fn min_angle(out: &LabelledMesh, t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| out.positions[v as usize]);
    crate::mesh::shape::min_angle_deg(&a, &b, &c)
}

/// With the chord tolerance alone the caps' triangles fan out from the rim's short edges to
/// the coarse cap; with the sizing field graded away from the rim (and the final Delaunay
/// flips) they grow over a few rings: far fewer slivers, the rim as fine as before.
#[test]
fn graded_sizes_remove_the_fans_beside_a_finely_split_crease() {
    let m = fine_cylinder(256);
    let mut opts = RemeshOptions::new(0.5);
    opts.crease_tolerance = Some(2e-3);
    let slivers = |out: &LabelledMesh| {
        out.triangles
            .iter()
            .filter(|t| min_angle(out, t) < 15.0)
            .count()
    };
    let fan = remesh(&m, &opts).unwrap();
    opts.grade = Some(0.5);
    opts.delaunay = true;
    let graded = remesh(&m, &opts).unwrap();
    let (a, b) = (slivers(&fan), slivers(&graded));
    assert!(a > 20 && b * 5 < a, "slivers {a} -> {b}");
    assert!(
        graded.triangles.len() < 4 * fan.triangles.len(),
        "{} -> {}",
        fan.triangles.len(),
        graded.triangles.len()
    );
    // The rim keeps its chord tolerance.
    for t in &graded.triangles {
        for &v in t {
            let p = graded.positions[v as usize];
            assert!(p.z.abs() < 1e-12 || (p.z - 1.0).abs() < 1e-12 || p.coords.xy().norm() > 0.99);
        }
    }
}

/// The ears of `m` (module `flips`): triangles with two edges on the same crease at a vertex
/// between two regions only.
fn ears(m: &LabelledMesh) -> usize {
    let e = edges(m);
    let mut regions: Vec<Vec<u32>> = vec![Vec::new(); m.positions.len()];
    for (t, &l) in m.triangles.iter().zip(&m.labels) {
        for &v in t {
            if !regions[v as usize].contains(&l) {
                regions[v as usize].push(l);
            }
        }
    }
    let crease = |a: u32, b: u32| {
        e.get(&key(a, b)).and_then(|fs| {
            let (l0, l1) = (m.labels[fs[0] as usize], m.labels[*fs.get(1)? as usize]);
            (l0 != l1).then_some((l0.min(l1), l0.max(l1)))
        })
    };
    m.triangles
        .iter()
        .filter(|t| {
            (0..3).any(|i| {
                let (x, a, b) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
                regions[x as usize].len() == 2
                    && crease(x, a).is_some()
                    && crease(x, a) == crease(x, b)
            })
        })
        .count()
}

/// An extracted crease zigzags: every other vertex on the cube's edges pushed a third of an
/// edge into one face, so that its two crease edges turn by 37 degrees. Those turns are not
/// corners: the remesh straightens the creases (no input zigzag vertex stays where it was,
/// as a pinned one would) and leaves no ear.
#[test]
fn a_zigzag_crease_is_not_pinned_and_leaves_no_ears() {
    let n = 24;
    let mut m = fine_cube(n);
    let delta = 0.35 / n as f64;
    let mut moved = Vec::new();
    for p in m.positions.iter_mut() {
        let on: Vec<usize> = (0..3)
            .filter(|&k| p[k].abs() < 1e-9 || (p[k] - 1.0).abs() < 1e-9)
            .collect();
        if on.len() != 2 {
            continue;
        }
        let along = (0..3).find(|k| !on.contains(k)).unwrap_or(0);
        if (p[along] * n as f64).round() as usize % 2 == 1 {
            let k = on[0];
            p[k] += if p[k] < 0.5 { delta } else { -delta };
            moved.push(*p);
        }
    }
    assert_eq!(moved.len(), 12 * n / 2);
    // The plain remesh's ears were of this kind; with the zigzag vertices pinned (turns
    // measured edge by edge), 144 of them would stay put.
    let out = remesh(&m, &RemeshOptions::new(0.2)).unwrap();
    let stayed = out
        .positions
        .iter()
        .filter(|p| moved.iter().any(|q| (*p - q).norm() < 1e-12))
        .count();
    assert_eq!(stayed, 0);
    assert_eq!(ears(&out), 0);
    // The corners stay, and the creases stay within the zigzag's width of the true edges.
    let e = edges(&out);
    for (&(a, b), fs) in &e {
        if out.labels[fs[0] as usize] != out.labels[fs[1] as usize] {
            for v in [a, b] {
                let p = out.positions[v as usize];
                let off = (0..3).map(|k| p[k].min(1.0 - p[k]).abs()).fold(
                    [f64::INFINITY; 2],
                    |[x, y], d| {
                        if d < x {
                            [d, x]
                        } else {
                            [x, y.min(d)]
                        }
                    },
                );
                assert!(off[1] <= delta + 1e-9, "{p}");
            }
        }
    }
    assert_eq!(
        out.positions.iter().filter(|p| off_cube(p).1 == 3).count(),
        8
    );
}

/// A move that turns a triangle inside out is undone, with every vertex of that triangle; a
/// move that keeps the triangles' orientation stays.
#[test]
fn folding_moves_are_undone() {
    // A hexagon fan around vertex 0 in the plane z = 0.
    let mut pos = vec![Point3::origin()];
    for k in 0..6 {
        let a = std::f64::consts::TAU * k as f64 / 6.0;
        pos.push(Point3::new(a.cos(), a.sin(), 0.0));
    }
    let tris: Vec<[u32; 3]> = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
    let mut s = State::new(&LabelledMesh {
        positions: pos.clone(),
        labels: vec![0; tris.len()],
        triangles: tris,
    });
    // The centre a little off: no triangle turns.
    s.pos[0] = Point3::new(0.2, 0.1, 0.0);
    assert_eq!(undo_folds(&mut s, &pos), 0);
    assert_eq!(s.pos[0], Point3::new(0.2, 0.1, 0.0));
    // The centre past the rim (and a rim vertex nudged): the fan folds, all goes back.
    s.pos[0] = Point3::new(1.5, 0.0, 0.0);
    s.pos[4] = Point3::new(-1.1, 0.0, 0.0);
    assert!(undo_folds(&mut s, &pos) >= 3);
    assert_eq!(s.pos[0], pos[0]);
    // Vertex 4's triangles did not fold: its move stays.
    assert_eq!(s.pos[4], Point3::new(-1.1, 0.0, 0.0));
}

/// A crease vertex next to a corner, pushed into a face: its turn, measured over the short
/// chord to the corner, pins it unless it lies within the corner gap (then the clean-up's jog
/// rule takes it onto the corner instead of leaving a short edge that can never go).
#[test]
fn a_vertex_beside_a_corner_is_pinned_only_outside_the_gap() {
    let n = 24;
    let mut m = fine_cube(n);
    let h = 1.0 / n as f64;
    let v = m
        .positions
        .iter()
        .position(|p| (p - Point3::new(h, 0.0, 0.0)).norm() < 1e-12)
        .unwrap() as u32;
    // Turned by atan(1/2) + atan(1/6), 36 degrees, over the chords to the corner and 3 h on.
    m.positions[v as usize].y = 0.5 * h;
    let s = State::new(&m);
    let topo = s.topo();
    let creases = crease_edges(&s, &topo);
    let pins = |gap: f64| crease_turns(&s, &topo, creases.iter().map(|c| c.0), true, gap);
    assert!(pins(0.0).contains(&v));
    // 0.047 from the corner: left free by a gap of 0.05, pinned by one of 0.04.
    assert!(!pins(0.05).contains(&v));
    assert!(pins(0.04).contains(&v));
}

/// A crease vertex moved onto its crease neighbour (as putting nodes onto a crease can do)
/// leaves two triangles with a zero-length edge; [`clean`] collapses it away: no degenerate
/// triangle is left, the mesh stays closed and edge-manifold, the crease keeps its edges.
#[test]
fn clean_removes_a_zero_length_crease_edge() {
    let n = 8;
    let mut m = fine_cube(n);
    let at = |m: &LabelledMesh, p: Point3<f64>| {
        m.positions
            .iter()
            .position(|q| (q - p).norm() < 1e-12)
            .unwrap() as u32
    };
    let a = at(&m, Point3::new(1.0 / 8.0, 0.0, 0.0));
    let b = at(&m, Point3::new(2.0 / 8.0, 0.0, 0.0));
    m.positions[a as usize] = m.positions[b as usize];
    let degenerate = |m: &LabelledMesh| {
        m.triangles
            .iter()
            .filter(|t| min_angle(m, t) < crate::mesh::shape::DEGENERATE_ANGLE_DEG)
            .count()
    };
    assert_eq!(degenerate(&m), 2);
    let (out, repairs) = clean(&m, 1.0 / n as f64, Some(1e-3)).unwrap();
    assert!(repairs >= 1);
    assert_eq!(degenerate(&out), 0);
    assert_eq!(out.positions.len(), m.positions.len() - 1);
    let e = edges(&out);
    assert!(
        e.values().all(|fs| fs.len() == 2),
        "not closed and edge-manifold"
    );
    let on_x_edge = e
        .iter()
        .filter(|(_, fs)| out.labels[fs[0] as usize] != out.labels[fs[1] as usize])
        .filter(|(&(p, q), _)| {
            [p, q].iter().all(|&v| {
                let x = out.positions[v as usize];
                x.y.abs() < 1e-12 && x.z.abs() < 1e-12
            })
        })
        .count();
    assert_eq!(on_x_edge, n - 1);
}
