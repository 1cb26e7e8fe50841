//! E57 scanner files (ASTM E2807), read with the `e57` crate.
//!
//! Every point cloud ("scan") in the file is read and merged into one cloud in the file's
//! coordinate system: each scan's pose (a unit quaternion rotation and a translation) is applied
//! to its points, `p_file = R p_scan + t`. Scans that store spherical coordinates (range,
//! azimuth, elevation) are converted to Cartesian, `x = r cos(el) cos(az)`,
//! `y = r cos(el) sin(az)`, `z = r sin(el)`, before the pose. Points whose coordinates are
//! flagged invalid are skipped; intensity, colour, row/column and time stamps are ignored.
//! Points that only carry a direction (no range: the beam hit nothing) cannot be placed in
//! space, so a scan made only of those is reported as unsupported.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use e57::{CartesianCoordinate, E57Reader};
use nalgebra::Point3;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

/// What an E57 file holds, from its XML section (no point data read).
#[derive(Debug, Clone, PartialEq)]
pub struct E57Info {
    /// Number of point clouds (scans).
    pub scans: usize,
    /// Points over all scans, as the file declares them (invalid ones included).
    pub points: u64,
}

/// Opens the file (streamed through a buffer: scans can be gigabytes) and parses its header
/// and XML section.
fn open(path: &Path) -> Result<E57Reader<BufReader<File>>> {
    super::check_nonempty_file(path)?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    E57Reader::new(BufReader::with_capacity(1 << 20, file)).map_err(|e| convert(path, e))
}

/// Maps the crate's errors to ours: features the crate lacks are "unsupported", the rest are
/// content errors (a damaged or non-E57 file), all naming the file.
fn convert(path: &Path, e: e57::Error) -> Error {
    match e {
        e57::Error::NotImplemented { desc } => {
            Error::unsupported(path, format!("E57 feature not supported: {desc}"))
        }
        other => Error::content(path, format!("not a readable E57 file: {other}")),
    }
}

/// Counts the scans and their declared points.
pub fn info(path: &Path) -> Result<E57Info> {
    let reader = open(path)?;
    let pcs = reader.pointclouds();
    Ok(E57Info {
        scans: pcs.len(),
        points: pcs.iter().map(|pc| pc.records).sum(),
    })
}

/// Checks a scanner file's declared point count (24 bytes per point in memory) against the
/// memory budget before anything is allocated.
pub(crate) fn declared_fits(path: &Path, declared: u64) -> Result<()> {
    crate::limits::check(
        &format!("the {declared} points the header declares"),
        24.0 * declared as f64,
        "subsample the scan in its own software or raise --max-memory",
    )
    .map_err(|e| Error::content(path, e.to_string()))
}

/// Initial capacity for `declared` points: never more than the file has bytes (a header can
/// claim billions of points that are not there; a compressed point takes at least a byte, and
/// the vector grows past the hint if it must).
pub(crate) fn capacity_hint(path: &Path, declared: u64) -> usize {
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    declared.min(len).min(1 << 28) as usize
}

/// Reads all scans, poses applied, merged into one point cloud.
pub fn read(path: &Path) -> Result<Mesh> {
    let mut reader = open(path)?;
    let pcs = reader.pointclouds();
    if pcs.is_empty() {
        return Err(Error::content(
            path,
            "the E57 file holds no point clouds (images only?)",
        ));
    }
    let total: u64 = pcs.iter().map(|pc| pc.records).sum();
    declared_fits(path, total)?;
    let mut pts: Vec<Point3<f64>> = Vec::with_capacity(capacity_hint(path, total));
    let mut direction_only = 0u64;
    for (si, pc) in pcs.iter().enumerate() {
        if !pc.has_cartesian() && !pc.has_spherical() {
            return Err(Error::unsupported(
                path,
                format!(
                    "scan {} has neither Cartesian nor spherical coordinates",
                    si + 1
                ),
            ));
        }
        let mut it = reader.pointcloud_simple(pc).map_err(|e| convert(path, e))?;
        it.spherical_to_cartesian(true);
        it.apply_pose(true);
        it.intensity_to_color(false);
        for p in it {
            let p = p.map_err(|e| convert(path, e))?;
            match p.cartesian {
                CartesianCoordinate::Valid { x, y, z } => {
                    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                        return Err(Error::content(
                            path,
                            format!(
                                "scan {}, point {}: non-finite coordinate ({x}, {y}, {z})",
                                si + 1,
                                pts.len() + 1
                            ),
                        ));
                    }
                    pts.push(Point3::new(x, y, z));
                }
                CartesianCoordinate::Direction { .. } => direction_only += 1,
                CartesianCoordinate::Invalid => {}
            }
        }
    }
    if pts.is_empty() {
        return Err(if direction_only > 0 {
            Error::unsupported(
                path,
                format!(
                    "all {direction_only} points are directions without a range; \
                     they cannot be placed in space"
                ),
            )
        } else {
            Error::content(path, "no valid points in any scan")
        });
    }
    Ok(Mesh::from_points(pts, None))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use e57::{E57Writer, Record, RecordValue};
    use nalgebra::{UnitQuaternion, Vector3};

    /// Writes `points` as an E57 file of two scans with different poses: the even-indexed
    /// points as Cartesian doubles (with an intensity channel), the odd-indexed ones as
    /// spherical coordinates. Reading it back must give the points again.
    pub(crate) fn write_two_scans(path: &Path, points: &[Point3<f64>]) {
        let mut w = E57Writer::from_file(path, "scansurf-test").unwrap();
        let pose_a = (
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.7),
            Vector3::new(1.0, -2.0, 0.5),
        );
        let pose_b = (
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -0.4),
            Vector3::new(-3.0, 0.25, 2.0),
        );
        let to_e57 = |(q, t): &(UnitQuaternion<f64>, Vector3<f64>)| e57::Transform {
            rotation: e57::Quaternion {
                w: q.w,
                x: q.i,
                y: q.j,
                z: q.k,
            },
            translation: e57::Translation {
                x: t.x,
                y: t.y,
                z: t.z,
            },
        };
        {
            let proto = vec![
                Record::CARTESIAN_X_F64,
                Record::CARTESIAN_Y_F64,
                Record::CARTESIAN_Z_F64,
                Record::INTENSITY_UNIT_F32,
            ];
            let mut pc = w.add_pointcloud("scan-a", proto).unwrap();
            pc.set_transform(Some(to_e57(&pose_a)));
            for (i, p) in points.iter().enumerate().step_by(2) {
                let l = pose_a.0.inverse() * (p - pose_a.1);
                pc.add_point(vec![
                    RecordValue::Double(l.x),
                    RecordValue::Double(l.y),
                    RecordValue::Double(l.z),
                    RecordValue::Single((i % 7) as f32 / 7.0),
                ])
                .unwrap();
            }
            pc.finalize().unwrap();
        }
        {
            let proto = vec![
                Record::SPHERICAL_RANGE_F64,
                Record::SPHERICAL_AZIMUTH_F64,
                Record::SPHERICAL_ELEVATION_F64,
            ];
            let mut pc = w.add_pointcloud("scan-b", proto).unwrap();
            pc.set_transform(Some(to_e57(&pose_b)));
            for p in points.iter().skip(1).step_by(2) {
                let l = pose_b.0.inverse() * (p - pose_b.1);
                let r = l.coords.norm();
                pc.add_point(vec![
                    RecordValue::Double(r),
                    RecordValue::Double(l.y.atan2(l.x)),
                    RecordValue::Double((l.z / r).asin()),
                ])
                .unwrap();
            }
            pc.finalize().unwrap();
        }
        w.finalize().unwrap();
    }

    fn sample() -> Vec<Point3<f64>> {
        (0..301)
            .map(|i| {
                let t = i as f64 * 0.1;
                Point3::new(t.cos() * 2.0, t.sin(), 0.05 * t)
            })
            .collect()
    }

    #[test]
    fn two_scans_with_poses_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.e57");
        let pts = sample();
        write_two_scans(&path, &pts);
        let m = read(&path).unwrap();
        assert_eq!(m.positions.len(), pts.len());
        // Scan A holds the even points, scan B the odd ones, in order.
        let expect: Vec<Point3<f64>> = pts
            .iter()
            .step_by(2)
            .chain(pts.iter().skip(1).step_by(2))
            .copied()
            .collect();
        for (a, b) in m.positions.iter().zip(&expect) {
            assert!((a - b).norm() < 1e-9, "{a} vs {b}");
        }
        let i = info(&path).unwrap();
        assert_eq!(
            i,
            E57Info {
                scans: 2,
                points: pts.len() as u64
            }
        );
    }

    #[test]
    fn garbage_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("scan.e57");
        std::fs::write(&p, b"ASTM-E57 but not really, just some bytes").unwrap();
        let e = read(&p).unwrap_err();
        assert!(e.to_string().contains("scan.e57"), "{e}");
        std::fs::write(&p, [0u8; 4096]).unwrap();
        assert!(read(&p).is_err());
        std::fs::write(&p, b"").unwrap();
        assert!(read(&p).unwrap_err().to_string().contains("empty"));
    }

    #[test]
    fn direction_only_points_are_unsupported() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("dir.e57");
        let mut w = E57Writer::from_file(&path, "dir-only").unwrap();
        let proto = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
            Record::CARTESIAN_INVALID_STATE,
        ];
        let mut pc = w.add_pointcloud("d", proto).unwrap();
        for i in 0..10 {
            pc.add_point(vec![
                RecordValue::Double(1.0),
                RecordValue::Double(i as f64),
                RecordValue::Double(0.0),
                RecordValue::Integer(1),
            ])
            .unwrap();
        }
        pc.finalize().unwrap();
        w.finalize().unwrap();
        let e = read(&path).unwrap_err();
        assert!(matches!(e, Error::Unsupported { .. }), "{e}");
        assert!(e.to_string().contains("directions"), "{e}");
    }
}
