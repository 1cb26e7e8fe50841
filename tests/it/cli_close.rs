//! `scansurf fit --close`: partial scans (issue 34). A machined part scanned from above
//! (make_parts' `-occluded.xyz`: no underside) fits open by default, accurately, and
//! OpenCASCADE reads a valid open shell; a mesh whose bottom was cut away does the same; a
//! closed input stays closed and byte-identical to `--close smooth`, unless its closed surface
//! cannot follow the data (the cow as a cloud), which then fits open; `--close smooth` closes an
//! opening by extrapolation; bad values are refused before any work.

use crate::common::{self, json_f64 as f};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

struct OpenFit {
    dir: PathBuf,
    input: PathBuf,
    report: serde_json::Value,
}

/// The default fit of the block scanned from above, shared by the tests that check it.
fn block_open() -> Option<&'static OpenFit> {
    static FIT: OnceLock<Result<OpenFit, String>> = OnceLock::new();
    let parts = common::make_parts()?;
    Some(common::shared(&FIT, || {
        let dir = common::scratch_dir("cli_close_block");
        let input = parts.join("block-occluded.xyz");
        let iges = dir.join("b.igs");
        let report = common::fit_report(
            &input,
            &dir.join("b.step"),
            &[
                "--iges",
                iges.to_str().unwrap(),
                "--preview",
                dir.join("b.png").to_str().unwrap(),
                "--net",
                dir.join("b-net.obj").to_str().unwrap(),
                "--features",
            ],
        );
        OpenFit { dir, input, report }
    }))
}

/// The acceptance of issue 34 on the block: the default run chooses open and says why, fits
/// only what was scanned (input deviation p99 <= 5e-4 of the diagonal; under 0.2 % of the area
/// farther than 1 % of the diagonal from the data), aims the patch count at the open net, and
/// reports the rim it carried to the data's edge.
#[test]
fn slow_block_scanned_from_above_fits_open_by_default() {
    let Some(b) = block_open() else { return };
    let r = &b.report;
    assert_eq!(r["close"]["requested"], "auto", "{}", r["close"]);
    assert_eq!(r["close"]["chosen"], "open", "{}", r["close"]);
    let reason = r["close"]["reason"].as_str().unwrap();
    assert!(reason.contains("do not enclose"), "{reason}");
    assert!(f(r, &["close", "enclosure", "escape_share"]) > 0.1);
    assert_eq!(r["closed"], false);
    assert!(f(r, &["free_edges"]) > 0.0);
    let p99 = f(r, &["deviation", "relative", "p99"]);
    assert!(p99 <= 5e-4, "p99 {p99}");
    let far = f(r, &["support_far", "unsupported_fraction"]);
    assert!(far < 2e-3, "{}", r["support_far"]);
    let patches = f(r, &["patches"]);
    assert!(
        (patches - 1500.0).abs() <= 0.2 * 1500.0,
        "{patches} patches"
    );
    assert!(
        f(r, &["close", "rim", "strip_quads"]) > 0.0,
        "{}",
        r["close"]
    );
    assert!(f(r, &["close", "trim", "quads_kept"]) > 0.0);
    // The preview exists and shows the open boundary in orange.
    let img = scansurf::render::Image::load_png(&b.dir.join("b.png")).unwrap();
    let orange = (0..img.height)
        .flat_map(|y| (0..img.width).map(move |x| (x, y)))
        .map(|(x, y)| img.get(x, y))
        .filter(|p| p[0] > 190 && (80..170).contains(&p[1]) && p[2] < 90)
        .count();
    assert!(orange > 500, "{orange} orange pixels");
}

/// OpenCASCADE reads the open block's STEP as one valid open shell with every patch, and its
/// IGES with the same faces.
#[test]
fn slow_block_open_shell_reads_back_in_opencascade() {
    let Some(b) = block_open() else { return };
    let Some((py, script)) = common::checker() else {
        eprintln!("SKIPPED: cad_check");
        return;
    };
    let patches = f(&b.report, &["patches"]);
    for file in ["b.step", "b.igs"] {
        let c = common::cad_check_with(&py, &script, &b.dir.join(file), None, &["--no-jumps"]);
        assert_eq!(c["valid"], true, "{file}: {c}");
        assert_eq!(f(&c, &["faces"]), patches, "{file}: {c}");
        assert_eq!(c["closed"], false, "{file}: {c}");
        if file == "b.step" {
            assert_eq!(f(&c, &["shells"]), 1.0, "{c}");
        }
    }
    let step = std::fs::read_to_string(b.dir.join("b.step")).unwrap();
    assert!(step.contains("OPEN_SHELL(") && step.contains("SHELL_BASED_SURFACE_MODEL("));
    assert!(!step.contains("MANIFOLD_SOLID_BREP("));
    let _ = &b.input;
}

/// spot with its top cut away (a mesh with a large opening): `auto` decides on the mesh as
/// read, before the local hole fill could close the opening, and fits it open; `--close
/// smooth` lets the fill close it (a solid).
#[test]
fn mesh_with_a_cut_away_top_follows_the_same_choice() {
    let mut mesh = scansurf::io::read_mesh(&repo().join("fixtures/spot.obj")).unwrap();
    let positions = mesh.positions.clone();
    mesh.faces
        .retain(|t| t.iter().all(|&i| positions[i as usize].y < 0.5));
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("spot_cut.ply");
    scansurf::io::write_mesh(&input, &mesh, Default::default()).unwrap();
    let r = common::fit_report(&input, &dir.path().join("a.step"), &[]);
    assert_eq!(r["close"]["chosen"], "open", "{}", r["close"]);
    assert_eq!(r["closed"], false);
    assert!(r["hole_fill"].is_null(), "{}", r["hole_fill"]);
    // Measured: far 0.085 %, p99 4.1e-4.
    let far = f(&r, &["support_far", "unsupported_fraction"]);
    assert!(far < 2e-3, "{}", r["support_far"]);
    let p99 = f(&r, &["deviation", "relative", "p99"]);
    assert!(p99 <= 5e-4, "p99 {p99}");
    let s = common::fit_report(
        &input,
        &dir.path().join("s.step"),
        &["--patches", "300", "--close", "smooth"],
    );
    assert_eq!(s["close"]["chosen"], "smooth");
    assert_eq!(s["closed"], true);
    assert!(
        f(&s, &["hole_fill", "holes_filled"]) >= 1.0,
        "{}",
        s["hole_fill"]
    );
}

/// The stepped shaft seen from above: at the default 1,500 patches the net misses the thin
/// crescents of its shoulders' lower halves (measured: 3.4 % of the points; input deviation
/// p99 8.6e-2 of the diagonal before the coverage check), so `fit` builds the net again with
/// twice the patches and says so (measured: 3,144 patches, 0.45 % missed, p99 2.5e-4); with
/// `--patches 1500` given it keeps the count and fits the shoulders by finer pieces.
#[test]
fn slow_parts_thinner_than_a_patch_get_smaller_patches() {
    let Some(dir) = common::stepped_part() else {
        return;
    };
    let input = dir.join("stepped-occluded.xyz");
    let out = tempfile::tempdir().unwrap();
    let r = common::fit_report(&input, &out.path().join("a.step"), &[]);
    let cov = &r["close"]["coverage"];
    let rounds = cov["rounds"].as_array().unwrap();
    assert!(rounds.len() >= 2, "{cov}");
    assert!(f(&rounds[0], &["missed_share"]) > 0.01, "{cov}");
    let kept = &rounds[cov["kept"].as_u64().unwrap() as usize];
    assert!(f(kept, &["missed_share"]) <= 0.005, "{cov}");
    assert_eq!(f(kept, &["patches"]), f(&r, &["patches"]), "{cov}");
    assert!(
        cov["note"].as_str().unwrap().contains("made again"),
        "{cov}"
    );
    assert_eq!(cov["covered"], true, "{cov}");
    let p99 = f(&r, &["deviation", "relative", "p99"]);
    assert!(p99 <= 5e-4, "p99 {p99}");
    let far = f(&r, &["support_far", "unsupported_fraction"]);
    assert!(far < 2e-3, "{}", r["support_far"]);

    let (b_step, b_json) = (out.path().join("b.step"), out.path().join("b.json"));
    let (code, _, stderr) = common::run(&[
        "fit",
        input.to_str().unwrap(),
        "-o",
        b_step.to_str().unwrap(),
        "-q",
        "--patches",
        "1500",
        "--report",
        b_json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&b_json).unwrap()).unwrap();
    let cov = &b["close"]["coverage"];
    assert_eq!(cov["rounds"].as_array().unwrap().len(), 1, "{cov}");
    let net = f(&cov["rounds"][0], &["patches"]);
    assert!((net - 1500.0).abs() < 0.2 * 1500.0, "{cov}");
    // The main net keeps the count; the shoulders get finer pieces of their own (measured:
    // 11 pieces, 1,571 patches, p99 2.4e-4), and the note still names the finer net.
    let note = cov["note"].as_str().unwrap();
    assert!(
        note.contains("--patches 3000") && note.contains("finer piece"),
        "{note}"
    );
    assert_eq!(cov["covered"], true, "{cov}");
    assert!(f(&b, &["patches"]) > net, "{cov}");
    let p99 = f(&b, &["deviation", "relative", "p99"]);
    assert!(p99 <= 5e-4, "p99 {p99}");
}

/// A closed model given as a cloud whose thin parts the sampling does not resolve (the cow's
/// ear cups and tail: two sides a few hundredths apart, 1/100 of the diagonal between points):
/// the rays say the data enclose a volume, but the closed implicit cannot follow those parts
/// (its net fails, or closes them by blobs away from the data). `auto` then fits the scanned
/// surface open, says why, and adds no surface away from the data.
#[test]
fn slow_closed_cloud_with_unresolved_thin_parts_falls_back_to_open() {
    let Some(cow) = common::shared_model("cow.obj") else {
        return;
    };
    let mesh = scansurf::io::read_mesh(&cow).unwrap();
    let diag = scansurf::mesh::Aabb::of(&mesh.positions)
        .unwrap()
        .diagonal();
    let (samples, _) = scansurf::mesh::sample::sample_surface(&mesh, 0.01 * diag);
    let dir = common::scratch_dir("cli_close_cow");
    let cloud = dir.join("cow.xyz");
    let points = mesh.positions.iter().chain(&samples).copied().collect();
    let points = scansurf::Mesh::from_points(points, None);
    scansurf::io::write_mesh(&cloud, &points, Default::default()).unwrap();
    let r = common::fit_report(&cloud, &dir.join("cow.step"), &[]);
    let close = &r["close"];
    assert_eq!(close["requested"], "auto");
    assert_eq!(close["chosen"], "open", "{close}");
    let reason = close["reason"].as_str().unwrap();
    assert!(
        reason.contains("enclose a volume") && reason.contains("only the scanned surface"),
        "{reason}"
    );
    assert_eq!(r["closed"], false);
    let far = f(&r, &["support_far", "unsupported_fraction"]);
    assert!(far < 0.01, "{far} of the area far from the data");
}

/// The cow seen from one side (the surface points whose normals face +z): its legs are
/// half-tubes about a patch across and its tail a ribbon thinner than one, which the net of
/// the whole misses (measured: 17.5 % of the points, input deviation p99 0.14 of the diagonal
/// without the pieces). Finer nets of their own cover them ([`scansurf::openings::pieces`];
/// measured: p99 4.4e-4, 0.2 % of the points still missed) and nothing is added away from the
/// data (6e-5 of the area farther than 1 % of the diagonal).
#[test]
fn slow_thin_one_sided_legs_get_pieces_of_their_own() {
    let Some(cow) = common::shared_model("cow.obj") else {
        return;
    };
    let mesh = scansurf::io::read_mesh(&cow).unwrap();
    let diag = scansurf::mesh::Aabb::of(&mesh.positions)
        .unwrap()
        .diagonal();
    let (samples, normals) = scansurf::mesh::sample::sample_surface(&mesh, 0.004 * diag);
    let side: Vec<_> = samples
        .iter()
        .zip(&normals)
        .filter(|(_, n)| n.z > 0.05)
        .map(|(p, _)| *p)
        .collect();
    let dir = common::scratch_dir("cli_close_cow_side");
    let cloud = dir.join("cow-side.xyz");
    scansurf::io::write_mesh(
        &cloud,
        &scansurf::Mesh::from_points(side, None),
        Default::default(),
    )
    .unwrap();
    let r = common::fit_report(&cloud, &dir.join("cow-side.step"), &[]);
    assert_eq!(r["close"]["chosen"], "open", "{}", r["close"]);
    let cov = &r["close"]["coverage"];
    let pieces = &cov["pieces"];
    let list = pieces["pieces"].as_array().unwrap();
    assert!(list.len() >= 2, "{pieces}");
    assert!(
        cov["note"].as_str().unwrap().contains("finer piece"),
        "{cov}"
    );
    let missed = f(pieces, &["missed_points"]);
    let still = f(pieces, &["still_missed_points"]);
    assert!(still < 0.2 * missed, "{pieces}");
    let p99 = f(&r, &["deviation", "relative", "p99"]);
    assert!(p99 <= 2e-3, "p99 {p99}");
    let far = f(&r, &["support_far", "unsupported_fraction"]);
    assert!(far < 2e-3, "{}", r["support_far"]);
}

/// The half of the shared `model` (e.g. "cow") above its vertices' mean along `axis`, made by
/// `scripts/half_scans.py` (None, and the test skipped, without the checker or the model).
fn half_scan(model: &str, axis: usize) -> Option<std::path::PathBuf> {
    let (py, _) = common::checker()?;
    let obj = common::shared_model(&format!("{model}.obj"))?;
    let data = obj.parent()?.to_str()?;
    let dir = common::make_with(
        &py,
        &repo().join("scripts/half_scans.py"),
        &format!("cli_close_{model}_half"),
        &[
            "--models",
            model,
            "--axes",
            &axis.to_string(),
            "--data",
            data,
        ],
    );
    Some(dir.join(format!("{model}-h{axis}.xyz")))
}

/// `fit` at defaults on [`half_scan`]`(model, axis)`, checked against issue 34's bars: chosen
/// open, input deviation p99 <= 5e-4 of the diagonal, under 0.2 % of the area farther than
/// 1 % of the diagonal from the data. Returns the report (None when the test is skipped).
fn fit_half_scan_on_its_data(model: &str, axis: usize) -> Option<serde_json::Value> {
    let cloud = half_scan(model, axis)?;
    let r = common::fit_report(&cloud, &cloud.with_extension("step"), &[]);
    assert_eq!(r["close"]["chosen"], "open", "{}", r["close"]);
    let far = f(&r, &["support_far", "unsupported_fraction"]);
    assert!(far < 2e-3, "{}", r["support_far"]);
    let p99 = f(&r, &["deviation", "relative", "p99"]);
    assert!(p99 <= 5e-4, "p99 {p99}");
    Some(r)
}

/// The front half of an organic scan never tuned on: cow.obj cut at its vertices' mean z
/// (`scripts/half_scans.py`: random surface points every 0.3 % of the diagonal, noise 1e-4;
/// the cut runs through the body, an ear and the tail). Section curves between two supported
/// net nodes can run out along the implicit's extrapolation below the cut and back; in an
/// open fit the samples are kept near the data ([`scansurf::fit::samples::NearData`]).
/// Measured: 12.9 % of the area farther than 1 % of the diagonal from the data without that
/// (a crumpled sheet hanging below the tail), 0.005 % with it; p99 5.0e-4 -> 4.5e-4.
#[test]
fn slow_front_half_of_an_organic_scan_stays_on_its_data() {
    fit_half_scan_on_its_data("cow", 2);
}

/// A half scan whose thin parts the net reaches but follows only as blobs: beetle.obj (a car
/// body, never tuned on) cut at its vertices' mean x. Its mirror and trim are a few voxels
/// across: fewer than 0.5 % of the points lie half a voxel from the quads, so coverage alone
/// makes no pieces, yet 1 % lie a sixth of a voxel off the trial patches (p99 2.6e-3 of the
/// diagonal). Pieces are made when the trial patches' 99th percentile exceeds
/// [`scansurf::openings::coverage::FAR_POINTS_P99`] voxels: p99 2.7e-4.
#[test]
fn slow_thin_parts_followed_loosely_get_pieces() {
    let Some(r) = fit_half_scan_on_its_data("beetle", 0) else {
        return;
    };
    let pieces = &r["close"]["coverage"]["pieces"]["pieces"];
    assert!(
        pieces.as_array().is_some_and(|p| !p.is_empty()),
        "{}",
        r["close"]
    );
}

/// `fit --net`: the quad net the patches were built on, one quad per patch, its nodes the
/// patch corners; the open block's net has the report's node count and its boundary the
/// report's free edges.
#[test]
fn slow_block_quad_net_is_written_as_obj() {
    let Some(fit) = block_open() else {
        return;
    };
    let text = std::fs::read_to_string(fit.dir.join("b-net.obj")).unwrap();
    let faces: Vec<Vec<usize>> = text
        .lines()
        .filter_map(|l| l.strip_prefix("f "))
        .map(|l| l.split_whitespace().map(|k| k.parse().unwrap()).collect())
        .collect();
    let nodes = text.lines().filter(|l| l.starts_with("v ")).count();
    assert_eq!(faces.len() as f64, f(&fit.report, &["patches"]));
    assert!(faces
        .iter()
        .all(|q| q.len() == 4 && q.iter().all(|&k| (1..=nodes).contains(&k))));
    assert_eq!(nodes as f64, f(&fit.report, &["net", "nodes"]));
    // Boundary edges: used by one quad.
    let mut uses = std::collections::HashMap::new();
    for q in &faces {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let boundary = uses.values().filter(|&&n| n == 1).count();
    assert_eq!(boundary as f64, f(&fit.report, &["free_edges"]));
    assert!(uses.values().all(|&n| n <= 2));
}

/// `fit --features --net`: the net's quads in groups by smooth region and the edges between
/// regions as lines; the block seen from above has its top, four sides, the pocket's walls
/// and floor and the hole's wall as regions, and every crease line is an edge between two
/// groups.
#[test]
fn slow_block_net_is_labelled_by_region() {
    let Some(fit) = block_open() else {
        return;
    };
    let r = &fit.report["net_regions"];
    assert!(f(r, &["regions"]) >= 6.0, "{r}");
    assert_eq!(f(r, &["unlabelled_quads"]), 0.0, "{r}");
    let text = std::fs::read_to_string(fit.dir.join("b-net.obj")).unwrap();
    let mut group = String::new();
    let mut edge_groups: std::collections::HashMap<(usize, usize), Vec<String>> =
        Default::default();
    let mut lines = Vec::new();
    for l in text.lines() {
        if let Some(g) = l.strip_prefix("g ") {
            group = g.to_string();
        } else if let Some(q) = l.strip_prefix("f ") {
            assert!(group.starts_with("region_"), "{group}");
            let q: Vec<usize> = q.split_whitespace().map(|k| k.parse().unwrap()).collect();
            for k in 0..4 {
                let (a, b) = (q[k], q[(k + 1) % 4]);
                edge_groups
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(group.clone());
            }
        } else if let Some(e) = l.strip_prefix("l ") {
            assert_eq!(group, "creases");
            let e: Vec<usize> = e.split_whitespace().map(|k| k.parse().unwrap()).collect();
            lines.push((e[0], e[1]));
        }
    }
    assert_eq!(lines.len() as f64, f(r, &["crease_edges_count"]), "{r}");
    assert!(lines.len() > 50, "{r}");
    for e in &lines {
        let g = &edge_groups[e];
        assert!(g.len() == 2 && g[0] != g[1], "{e:?}: {g:?}");
    }
}

/// A closed input: `auto` keeps it closed, byte for byte what `--close smooth` writes.
#[test]
fn closed_input_is_unchanged_by_auto() {
    let input = repo().join("fixtures/spot.obj");
    let (a, s) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let ra = common::fit_report(&input, &a.path().join("f.step"), &["--patches", "200"]);
    let rs = common::fit_report(
        &input,
        &s.path().join("f.step"),
        &["--patches", "200", "--close", "smooth"],
    );
    assert_eq!(ra["close"]["chosen"], "smooth", "{}", ra["close"]);
    assert!(ra["close"]["reason"]
        .as_str()
        .unwrap()
        .contains("enclose a volume"));
    assert_eq!(rs["close"]["requested"], "smooth");
    assert_eq!(ra["closed"], true);
    let read = |d: &Path| std::fs::read(d.join("f.step")).unwrap();
    assert!(
        read(a.path()) == read(s.path()),
        "auto and smooth STEP differ"
    );
}

/// `--close` takes auto, smooth or open; anything else fails before the input is read, naming
/// the option, and writes nothing.
#[test]
fn bad_close_value_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.step");
    let input = repo().join("fixtures/spot.obj");
    let (code, _, err) = common::run(&[
        "fit",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--close",
        "sideways",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("--close") && err.contains("sideways"), "{err}");
    assert!(!out.exists());
}
