//! End-to-end checks of `render_mesh` on the spot fixture and analytic shapes.

use super::*;
use nalgebra::Vector3;
use std::path::Path;

fn spot() -> Mesh {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/spot.obj");
    crate::io::read_mesh(&p).unwrap()
}

fn small() -> RenderOptions {
    RenderOptions {
        width: 400,
        height: 300,
        ..Default::default()
    }
}

/// A UV sphere of radius 1 at the origin; `cap` < pi keeps only latitudes up to `cap` from
/// the north pole (an open bowl).
fn sphere(nu: usize, nv: usize, cap: f64) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=nv {
        let th = cap * j as f64 / nv as f64;
        for i in 0..nu {
            let ph = std::f64::consts::TAU * i as f64 / nu as f64;
            positions.push(Point3::new(
                th.sin() * ph.cos(),
                th.cos(),
                th.sin() * ph.sin(),
            ));
        }
    }
    let mut faces = Vec::new();
    let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
    for j in 0..nv {
        for i in 0..nu {
            // Counter-clockwise seen from outside.
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

/// Bounding box of the non-background pixels as fractions of the width and height.
fn extent(img: &Image, bg: [u8; 3]) -> (f64, f64) {
    let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            if img.get(x, y) != bg {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    (
        (x1 + 1).saturating_sub(x0) as f64 / img.width as f64,
        (y1 + 1).saturating_sub(y0) as f64 / img.height as f64,
    )
}

/// Checks a render of spot: the object spans ~90% of the frame along its limiting side, is
/// shaded (many grey levels, not a flat silhouette) and covers a good part of the picture.
fn check_spot(img: &Image, o: &RenderOptions, min_fraction: f64) {
    let s = img.stats(o.background);
    assert!(s.foreground_fraction > min_fraction, "{:?} {s:?}", o.view);
    assert!(s.grey_levels >= 20, "{:?} {s:?}", o.view);
    let (ex, ey) = extent(img, o.background);
    assert!(
        ex.max(ey) > 0.85 && ex.max(ey) <= 0.95,
        "{:?}: {ex} {ey}",
        o.view
    );
}

#[test]
fn spot_mesh_is_shaded_and_fills_the_frame() {
    let m = spot();
    // Spot is long and narrow: in a 4:3 frame it covers a fifth to a third of the picture
    // depending on the view; in its side profile on a square frame, over 30%.
    for view in [View::Iso, View::Front, View::Top, View::Side] {
        let o = RenderOptions { view, ..small() };
        let img = render_mesh(&m, None, &[], &o).unwrap();
        assert_eq!((img.width, img.height), (400, 300));
        check_spot(&img, &o, 0.2);
    }
    let o = RenderOptions {
        view: View::Side,
        width: 300,
        height: 300,
        ..small()
    };
    check_spot(&render_mesh(&m, None, &[], &o).unwrap(), &o, 0.3);
}

#[test]
fn spot_cloud_is_shaded_and_fills_the_frame() {
    let cloud = Mesh::from_points(spot().positions, None);
    let o = small();
    check_spot(&render_mesh(&cloud, None, &[], &o).unwrap(), &o, 0.2);
    let o = RenderOptions {
        view: View::Side,
        width: 300,
        height: 300,
        ..small()
    };
    check_spot(&render_mesh(&cloud, None, &[], &o).unwrap(), &o, 0.3);
}

#[test]
fn deviation_colours_and_legend() {
    let o = small();
    let m = spot();
    let c = m.aabb().unwrap().center();
    let dev: Vec<f64> = m.positions.iter().map(|p| p.y - c.y).collect();
    let scale = ColorScale::auto(&dev).unwrap();
    assert_eq!(scale.map, ColorMap::Diverging);
    let img = render_mesh(&m, Some((&dev, scale)), &[], &o).unwrap();
    let s = img.stats(o.background);
    assert!(s.colored_fraction > 0.4, "{s:?}");
    // The model moved left of the legend; the legend's bar holds both ends of the map.
    let right: Vec<[u8; 3]> = (0..img.height)
        .flat_map(|y| (img.width * 3 / 4..img.width).map(move |x| (x, y)))
        .map(|(x, y)| img.get(x, y))
        .collect();
    let near = |a: [u8; 3], b: [u8; 3]| a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) < 12);
    assert!(right
        .iter()
        .any(|&p| near(p, ColorMap::Diverging.srgb8(1.0))));
    assert!(right
        .iter()
        .any(|&p| near(p, ColorMap::Diverging.srgb8(0.0))));
    // Points: per-point colours.
    let cloud = Mesh::from_points(m.positions.clone(), None);
    let img = render_mesh(&cloud, Some((&dev, scale)), &[], &o).unwrap();
    assert!(img.stats(o.background).colored_fraction > 0.4);
}

#[test]
fn visible_lines_show_and_hidden_ones_do_not() {
    // The equator of a sphere in the iso view (from above): its front half runs below the
    // centre of the picture, its back half (hidden) above.
    let m = sphere(96, 48, std::f64::consts::PI);
    let equator: Vec<Point3<f64>> = (0..=200)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 200.0;
            Point3::new(a.cos(), 0.0, a.sin())
        })
        .collect();
    let o = RenderOptions {
        line_color: [255, 0, 0],
        ..small()
    };
    let img = render_mesh(&m, None, &[equator], &o).unwrap();
    let red = |y0: u32, y1: u32| {
        (y0..y1)
            .flat_map(|y| (0..img.width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let [r, g, b] = img.get(x, y);
                r > 150 && g < 90 && b < 90
            })
            .count()
    };
    let (below, above) = (red(150, 300), red(0, 150));
    assert!(below > 300, "{below}");
    assert!(above < below / 10, "{above} vs {below}");
}

#[test]
fn inside_of_an_open_bowl_shows_the_back_colour() {
    // A dome (the cap around +Y, open toward -Y) seen from above shows its outside; the same
    // dome mirrored to open toward +Y (winding reversed to stay outward) shows its inside.
    let dome = sphere(64, 24, 1.2);
    let bowl = Mesh {
        positions: dome
            .positions
            .iter()
            .map(|p| Point3::new(p.x, -p.y, p.z))
            .collect(),
        normals: None,
        faces: dome.faces.iter().map(|f| [f[0], f[2], f[1]]).collect(),
    };
    let o = RenderOptions {
        view: View::Top,
        ..small()
    };
    let warm = |m: &Mesh| {
        let s = render_mesh(m, None, &[], &o).unwrap().stats(o.background);
        assert!(s.foreground_fraction > 0.3, "{s:?}");
        s.colored_fraction
    };
    assert!(warm(&dome) < 0.05, "outside of the dome: {}", warm(&dome));
    assert!(warm(&bowl) > 0.5, "inside of the bowl: {}", warm(&bowl));
}

#[test]
fn cloud_normals_are_used_when_given() {
    // A flat square cloud: with normals facing the viewer it is lit evenly; with normals
    // pointing sideways it is darker.
    let pts: Vec<Point3<f64>> = (0..40)
        .flat_map(|i| (0..40).map(move |j| Point3::new(i as f64 * 0.025, j as f64 * 0.025, 0.0)))
        .collect();
    let o = RenderOptions {
        view: View::Front,
        outline: false,
        ..small()
    };
    let mean = |m: &Mesh| {
        let img = render_mesh(m, None, &[], &o).unwrap();
        let fg: Vec<u32> = img
            .pixels
            .iter()
            .filter(|p| **p != o.background)
            .map(|p| p[0] as u32)
            .collect();
        fg.iter().sum::<u32>() as f64 / fg.len() as f64
    };
    let facing = Mesh::from_points(pts.clone(), Some(vec![Vector3::z(); pts.len()]));
    let sideways = Mesh::from_points(pts.clone(), Some(vec![Vector3::x(); pts.len()]));
    let estimated = Mesh::from_points(pts, None);
    let (a, b, c) = (mean(&facing), mean(&sideways), mean(&estimated));
    assert!(a > b + 30.0, "{a} vs {b}");
    assert!(
        (a - c).abs() < 2.0,
        "estimated normals of a plane face the viewer: {a} vs {c}"
    );
}

#[test]
fn deterministic_across_thread_counts() {
    let m = spot();
    let o = small();
    let a = render_mesh(&m, None, &[], &o).unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = one.install(|| render_mesh(&m, None, &[], &o).unwrap());
    assert_eq!(a, b);
    let cloud = Mesh::from_points(m.positions.clone(), None);
    let a = render_mesh(&cloud, None, &[], &o).unwrap();
    let b = one.install(|| render_mesh(&cloud, None, &[], &o).unwrap());
    assert_eq!(a, b);
}

#[test]
fn bad_input_is_an_error() {
    let o = small();
    assert!(render_mesh(&Mesh::default(), None, &[], &o).is_err());
    let m = spot();
    let short = vec![0.0; 3];
    let sc = ColorScale::symmetric(1.0).unwrap();
    assert!(render_mesh(&m, Some((&short, sc)), &[], &o).is_err());
    for bad in [
        RenderOptions {
            width: 0,
            ..small()
        },
        RenderOptions {
            supersample: 9,
            ..small()
        },
        RenderOptions {
            fill: 0.0,
            ..small()
        },
        RenderOptions {
            point_radius: Some(f32::NAN),
            ..small()
        },
    ] {
        assert!(render_mesh(&m, None, &[], &bad).is_err());
    }
    let mut nan = m.clone();
    nan.positions[0].x = f64::NAN;
    assert!(render_mesh(&nan, None, &[], &o).is_err());
    let mut out_of_range = m.clone();
    out_of_range.faces.push([0, 1, 999_999]);
    assert!(render_mesh(&out_of_range, None, &[], &o).is_err());
    assert_eq!(parse_size("1600x1200").unwrap(), (1600, 1200));
    assert!(parse_size("1600").is_err() && parse_size("0x5").is_err());
    // One point, a degenerate "mesh" of coincident vertices: a picture, not a panic.
    let one = Mesh::from_points(vec![Point3::new(1.0, 2.0, 3.0)], None);
    assert!(render_mesh(&one, None, &[], &o).is_ok());
    let flat = Mesh {
        positions: vec![Point3::origin(); 3],
        normals: None,
        faces: vec![[0, 1, 2]],
    };
    assert!(render_mesh(&flat, None, &[], &o).is_ok());
}
