//! Writers of small scanner files, with the `e57` and `las` crates' own writers, shared by
//! `examples/make_scanner_fixtures.rs` and the round-trip tests. scansurf itself only reads
//! these formats.

#![allow(dead_code)]

use e57::{E57Writer, Record, RecordValue};
use las::{Builder, Point, Writer};
use nalgebra::{Point3, UnitQuaternion, Vector3};
use std::path::Path;

type Pose = (UnitQuaternion<f64>, Vector3<f64>);

fn e57_transform((q, t): &Pose) -> e57::Transform {
    e57::Transform {
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
    }
}

/// Writes `points` as an E57 file of two scans with different poses: the first half as
/// Cartesian doubles with an intensity channel, the second half as spherical coordinates
/// (range, azimuth, elevation). Each scan stores its points in its own frame, so reading the
/// file with poses applied gives `points` back, in order.
pub fn write_e57_two_scans(path: &Path, points: &[Point3<f64>]) -> Result<(), e57::Error> {
    let mut w = E57Writer::from_file(path, "scansurf-fixture")?;
    let half = points.len() / 2;
    let pose_a: Pose = (
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.7),
        Vector3::new(1.0, -2.0, 0.5),
    );
    let pose_b: Pose = (
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -0.4),
        Vector3::new(-3.0, 0.25, 2.0),
    );
    {
        let proto = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
            Record::INTENSITY_UNIT_F32,
        ];
        let mut pc = w.add_pointcloud("scan-cartesian", proto)?;
        pc.set_name(Some("cartesian scan".into()));
        pc.set_transform(Some(e57_transform(&pose_a)));
        for (i, p) in points[..half].iter().enumerate() {
            let l = pose_a.0.inverse() * (p - pose_a.1);
            pc.add_point(vec![
                RecordValue::Double(l.x),
                RecordValue::Double(l.y),
                RecordValue::Double(l.z),
                RecordValue::Single((i % 11) as f32 / 11.0),
            ])?;
        }
        pc.finalize()?;
    }
    {
        let proto = vec![
            Record::SPHERICAL_RANGE_F64,
            Record::SPHERICAL_AZIMUTH_F64,
            Record::SPHERICAL_ELEVATION_F64,
        ];
        let mut pc = w.add_pointcloud("scan-spherical", proto)?;
        pc.set_name(Some("spherical scan".into()));
        pc.set_transform(Some(e57_transform(&pose_b)));
        for p in &points[half..] {
            let l = pose_b.0.inverse() * (p - pose_b.1);
            let r = l.coords.norm();
            pc.add_point(vec![
                RecordValue::Double(r),
                RecordValue::Double(l.y.atan2(l.x)),
                RecordValue::Double((l.z / r).asin()),
            ])?;
        }
        pc.finalize()?;
    }
    w.finalize()
}

/// Writes `points` as LAS 1.2, point format 1 (xyz, intensity, GPS time) on a 1e-6 grid with
/// the offset at the minimum corner; a `.laz` path is LASzip-compressed.
pub fn write_las(path: &Path, points: &[Point3<f64>]) -> Result<(), las::Error> {
    let mut b = Builder::from((1, 2));
    b.point_format = las::point::Format::new(1)?;
    let min = points
        .iter()
        .fold(Point3::new(f64::MAX, f64::MAX, f64::MAX), |m, p| m.inf(p));
    let t = |offset: f64| las::Transform {
        scale: 1e-6,
        offset,
    };
    b.transforms = las::Vector {
        x: t(min.x),
        y: t(min.y),
        z: t(min.z),
    };
    let mut w = Writer::from_path(path, b.into_header()?)?;
    for (i, p) in points.iter().enumerate() {
        w.write_point(Point {
            x: p.x,
            y: p.y,
            z: p.z,
            intensity: (i % 1000) as u16,
            gps_time: Some(i as f64 * 1e-3),
            ..Default::default()
        })?;
    }
    w.close()
}
