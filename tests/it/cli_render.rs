//! `scansurf render` and `inspect` on scanner files, through the binary.

use crate::common::run;
use scansurf::render::Image;
use std::path::Path;

fn fixture(n: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(n)
        .display()
        .to_string()
}

#[test]
fn renders_mesh_and_cloud_shaded() {
    let dir = tempfile::tempdir().unwrap();
    for input in ["spot.obj", "spot.laz"] {
        let png = dir.path().join(format!("{input}.png"));
        let (code, _, err) = run(&[
            "render",
            &fixture(input),
            "-o",
            png.to_str().unwrap(),
            "--view",
            "side",
            "--size",
            "400x400",
            "--quiet",
        ]);
        assert_eq!(code, 0, "{err}");
        let s = Image::load_png(&png).unwrap().stats([255, 255, 255]);
        assert!(s.foreground_fraction > 0.3, "{input}: {s:?}");
        assert!(s.grey_levels >= 20, "{input}: {s:?}");
    }
}

#[test]
fn against_cloud_colours_with_legend() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("d.png");
    let (code, _, err) = run(&[
        "render",
        &fixture("spot.obj"),
        "-o",
        png.to_str().unwrap(),
        "--against",
        &fixture("spot.las"),
        "--size",
        "400x300",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let s = Image::load_png(&png).unwrap().stats([255, 255, 255]);
    assert!(s.colored_fraction > 0.3, "{s:?}");
}

#[test]
fn render_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("x.jpg");
    let (code, _, err) = run(&["render", &fixture("spot.obj"), "-o", bad.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("x.jpg") && err.contains("PNG"), "{err}");
    let png = dir.path().join("x.png");
    let (code, _, err) = run(&[
        "render",
        &fixture("spot.obj"),
        "-o",
        png.to_str().unwrap(),
        "--view",
        "diagonal",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("diagonal"), "{err}");
    assert!(!png.exists());
}

#[test]
fn inspect_reports_scans() {
    let (code, out, err) = run(&["inspect", &fixture("spot_2scans.e57"), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["scans"], 2);
    assert_eq!(v["vertices"], 1981);
}

/// Fits a small STEP from the spot fixture (about 300 patches, a second) into `dir`.
/// (At 100 patches the cow's legs fold into a large back-facing sheet, seen in the render.)
fn fitted_step(dir: &Path) -> String {
    let step = dir.join("spot.step");
    let (code, _, err) = run(&[
        "fit",
        &fixture("spot.obj"),
        "-o",
        step.to_str().unwrap(),
        "--patches",
        "300",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    step.display().to_string()
}

fn render_stats(input: &str, out: &Path, extra: &[&str]) -> scansurf::render::ImageStats {
    let mut args = vec![
        "render",
        input,
        "-o",
        out.to_str().unwrap(),
        "--size",
        "480x360",
        "--view",
        "side",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{input}: {err}");
    Image::load_png(out).unwrap().stats([255, 255, 255])
}

/// A fitted STEP renders shaded, filling the frame, with its patch boundaries as dark lines:
/// many more dark pixels than the same object rendered as a mesh (outlines only); hardly any
/// coloured pixels (back faces are drawn orange: a folded patch would show).
#[test]
fn renders_step_with_patch_boundaries() {
    let dir = tempfile::tempdir().unwrap();
    let step = fitted_step(dir.path());
    let s = render_stats(&step, &dir.path().join("step.png"), &[]);
    let m = render_stats(&fixture("spot.obj"), &dir.path().join("mesh.png"), &[]);
    println!("step {s:?}\nmesh {m:?}");
    // A side view of the cow covers 30% of a 4:3 frame (its extent spans 90% of the width).
    assert!(s.foreground_fraction > 0.25, "{s:?}");
    assert!(s.grey_levels >= 40, "{s:?}");
    assert!(s.colored_fraction < 0.01, "{s:?}");
    assert!(s.dark_fraction > 0.05, "{s:?}");
    assert!(
        s.dark_fraction > 3.0 * m.dark_fraction,
        "{s:?} vs mesh {m:?}"
    );
    // The same object: the same coverage within a few percent.
    assert!(
        (s.foreground_fraction - m.foreground_fraction).abs() < 0.05,
        "{s:?} vs {m:?}"
    );
}

/// A fitted STEP coloured by the distance to the points it was fitted to (`--against`), the
/// `fit --preview` picture (coloured by the points' deviation) and the same deviation drawn
/// afterwards by `render --deviation` from `fit --deviation-ply`.
#[test]
fn renders_step_deviation_colours() {
    let dir = tempfile::tempdir().unwrap();
    let step = fitted_step(dir.path());
    let s = render_stats(
        &step,
        &dir.path().join("dev.png"),
        &["--against", &fixture("spot.laz")],
    );
    println!("against {s:?}");
    assert!(s.foreground_fraction > 0.2, "{s:?}");
    assert!(s.colored_fraction > 0.3, "{s:?}");
    let png = dir.path().join("preview.png");
    let e57_step = dir.path().join("e57.step");
    let dev_ply = dir.path().join("dev.ply");
    let (code, _, err) = run(&[
        "fit",
        &fixture("spot_2scans.e57"),
        "-o",
        e57_step.to_str().unwrap(),
        "--patches",
        "150",
        "--preview",
        png.to_str().unwrap(),
        "--preview-size",
        "640x480",
        "--deviation-ply",
        dev_ply.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let img = Image::load_png(&png).unwrap();
    assert_eq!((img.width, img.height), (640, 480));
    let p = img.stats([255, 255, 255]);
    println!("preview {p:?}");
    assert!(p.foreground_fraction > 0.2, "{p:?}");
    assert!(p.colored_fraction > 0.3, "{p:?}");
    // The same deviation drawn afterwards from the fit's --deviation-ply.
    let d = render_stats(
        e57_step.to_str().unwrap(),
        &dir.path().join("dev_ply.png"),
        &["--deviation", dev_ply.to_str().unwrap()],
    );
    println!("--deviation {d:?}");
    assert!(d.foreground_fraction > 0.2, "{d:?}");
    assert!(d.colored_fraction > 0.3, "{d:?}");
    // Not with --against; not from a PLY without the `quality` scalar.
    let out = dir.path().join("x.png");
    let (code, _, err) = run(&[
        "render",
        e57_step.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--deviation",
        dev_ply.to_str().unwrap(),
        "--against",
        &fixture("spot.laz"),
    ]);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = run(&[
        "render",
        e57_step.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--deviation",
        &fixture("spot_tristrips_le.ply"),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("quality"), "{err}");
    assert!(!out.exists());
}

/// The Stanford bunny (shared data) as a mesh and as its bare vertices: both fill the frame,
/// shaded with many grey levels, and neither shows patch lines.
#[test]
fn renders_bunny_mesh_and_cloud() {
    let Some(bunny) = shared_bunny() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mesh = render_stats(&bunny, &dir.path().join("mesh.png"), &[]);
    // Its vertices alone, as a point cloud file.
    let cloud_path = dir.path().join("bunny.xyz");
    let m = scansurf::io::read_mesh(Path::new(&bunny)).unwrap();
    let cloud = scansurf::Mesh {
        positions: m.positions,
        normals: None,
        faces: Vec::new(),
    };
    scansurf::io::write_mesh(&cloud_path, &cloud, Default::default()).unwrap();
    let cloud = render_stats(
        cloud_path.to_str().unwrap(),
        &dir.path().join("cloud.png"),
        &[],
    );
    println!("mesh {mesh:?}\ncloud {cloud:?}");
    // Measured 0.29 / 0.30 (side view, 4:3): the bunny's extent spans 90% of the height.
    // The mesh shows a little orange (0.1%): back faces seen through its open base.
    for s in [mesh, cloud] {
        assert!(s.foreground_fraction > 0.25, "{s:?}");
        assert!(s.grey_levels >= 60, "{s:?}");
        assert!(s.colored_fraction < 0.01, "{s:?}");
        assert!(s.dark_fraction < 0.05, "{s:?}");
    }
}

fn shared_bunny() -> Option<String> {
    let dir = std::env::var_os("SCANSURF_SHARED_DATA")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let p = dir.join("stanford-bunny.obj");
    if p.exists() {
        Some(p.display().to_string())
    } else if std::env::var_os("CI").is_some() {
        panic!("CI: {} is missing", p.display());
    } else {
        eprintln!("SKIPPED: no shared data");
        None
    }
}

#[test]
fn focus_frames_a_ball_and_rejects_an_empty_one() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.png");
    let near = dir.path().join("near.png");
    let args = |out: &std::path::Path| {
        vec![
            "render".to_string(),
            fixture("spot.obj"),
            "-o".into(),
            out.to_str().unwrap().into(),
            "--size".into(),
            "300x300".into(),
            "--quiet".into(),
        ]
    };
    let (code, _, err) = run(&args(&full).iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    // A ball around one vertex of spot: what is left is framed to fill the picture too.
    let m = scansurf::io::read_mesh(Path::new(&fixture("spot.obj"))).unwrap();
    // A vertex with a negative coordinate, passed as a separate argument as users type it
    // (`--focus -0.3,...` once failed: clap took it for an option).
    let p = *m.positions.iter().find(|p| p.x < 0.0).unwrap();
    let mut a = args(&near);
    a.push("--focus".into());
    a.push(format!("{},{},{},0.2", p.x, p.y, p.z));
    let (code, _, err) = run(&a.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    let (sf, sn) = (
        Image::load_png(&full).unwrap().stats([255, 255, 255]),
        Image::load_png(&near).unwrap().stats([255, 255, 255]),
    );
    // Unframed, a ball of radius 0.2 on spot (about 2 units across) would cover ~1 %.
    assert!(sn.foreground_fraction > 0.1, "{sn:?}");
    assert_ne!(std::fs::read(&full).unwrap(), std::fs::read(&near).unwrap());
    assert!(sf.foreground_fraction > 0.2, "{sf:?}");
    // Nothing inside: a clear error naming the option, and no file.
    let empty = dir.path().join("empty.png");
    let mut a = args(&empty);
    a.push("--focus=100,100,100,0.1".into());
    let (code, _, err) = run(&a.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert_ne!(code, 0);
    assert!(err.contains("--focus"), "{err}");
    assert!(!empty.exists());
    let mut a = args(&empty);
    a.push("--focus=1,2".into());
    let (code, _, err) = run(&a.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert_ne!(code, 0);
    assert!(err.contains("X,Y,Z,R"), "{err}");
}
