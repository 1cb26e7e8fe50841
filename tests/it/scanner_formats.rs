//! Round trips through the scanner formats: files written by the `e57` and `las` crates'
//! writers read back through `io::read_mesh` with the same point count and bounds.

use crate::support;

use crate::support::scanner_writers::{write_e57_two_scans, write_las};
use nalgebra::Point3;
use scansurf::io::{read_mesh, scan_info, ScanInfo};
use scansurf::mesh::subsample::{limit_points, voxel_grid};
use scansurf::mesh::Aabb;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn assert_same_cloud(path: &Path, expect: &[Point3<f64>], tol: f64) {
    let m = read_mesh(path).unwrap_or_else(|e| panic!("{e}"));
    assert!(m.is_point_cloud());
    assert_eq!(m.positions.len(), expect.len(), "{}", path.display());
    let (a, b) = (Aabb::of(&m.positions).unwrap(), Aabb::of(expect).unwrap());
    assert!(
        (a.min - b.min).amax() <= tol && (a.max - b.max).amax() <= tol,
        "{}: bounds {a:?} vs {b:?}",
        path.display()
    );
    let worst = m
        .positions
        .iter()
        .zip(expect)
        .map(|(p, q)| (p - q).amax())
        .fold(0.0, f64::max);
    assert!(
        worst <= tol,
        "{}: worst point error {worst}",
        path.display()
    );
}

#[test]
fn committed_fixtures_hold_the_spot_sample() {
    let spot = read_mesh(&root().join("fixtures/spot.obj")).unwrap();
    let (pts, _) = voxel_grid(&spot.positions, None, 2000).unwrap();
    assert_eq!(pts.len(), 1981);
    assert_same_cloud(&root().join("fixtures/spot_2scans.e57"), &pts, 1e-9);
    assert_same_cloud(&root().join("fixtures/spot.las"), &pts, 1e-6);
    assert_same_cloud(&root().join("fixtures/spot.laz"), &pts, 1e-6);
    assert_eq!(
        scan_info(&root().join("fixtures/spot_2scans.e57")).unwrap(),
        Some(ScanInfo {
            scans: 2,
            declared_points: 1981
        })
    );
    assert_eq!(
        scan_info(&root().join("fixtures/spot.laz")).unwrap(),
        Some(ScanInfo {
            scans: 1,
            declared_points: 1981
        })
    );
    assert_eq!(scan_info(&root().join("fixtures/spot.obj")).unwrap(), None);
}

#[test]
fn bunny_points_through_e57_las_and_laz() {
    let Some(bunny_path) = support::shared_data("stanford-bunny.obj") else {
        eprintln!("skipping: no shared data");
        return;
    };
    let bunny = read_mesh(&bunny_path).unwrap();
    let pts = bunny.positions;
    assert!(pts.len() > 30_000);
    let dir = tempfile::tempdir().unwrap();
    let e57 = dir.path().join("bunny.e57");
    write_e57_two_scans(&e57, &pts).unwrap();
    assert_same_cloud(&e57, &pts, 1e-9);
    for name in ["bunny.las", "bunny.laz"] {
        let p = dir.path().join(name);
        write_las(&p, &pts).unwrap();
        assert_same_cloud(&p, &pts, 1e-6);
    }
    // --max-points on read: at most N points, spread over the whole bunny.
    let cloud = read_mesh(&dir.path().join("bunny.laz")).unwrap();
    let full = cloud.aabb().unwrap();
    let thin = limit_points(cloud, 5000).unwrap();
    assert!(thin.positions.len() <= 5000 && thin.positions.len() > 4000);
    let b = thin.aabb().unwrap();
    assert!((b.diagonal() - full.diagonal()).abs() < 0.05 * full.diagonal());
}
