//! ASPRS LAS point clouds and their LASzip-compressed form LAZ, read with the `las` crate (its
//! `laz` feature decompresses). Only the coordinates are kept: `x = X * scale_x + offset_x`
//! (likewise y, z) from the 32-bit integer records; intensity, classification, returns, GPS
//! time, colour and waveforms are ignored. Compression is read from the header, so a LAZ file
//! named `.las` (or the reverse) still reads.

use crate::error::{Error, Result};
use crate::mesh::{Aabb, Mesh};
use las::{PointDataBuilder, Reader};
use nalgebra::Point3;
use std::path::Path;

/// What a LAS/LAZ header declares (no point data read).
#[derive(Debug, Clone, PartialEq)]
pub struct LasInfo {
    /// Number of point records.
    pub points: u64,
    /// The header's bounding box.
    pub bounds: Aabb,
    /// LAS version, e.g. "1.2".
    pub version: String,
    /// Point data record format (0-10).
    pub point_format: u8,
    /// LASzip-compressed.
    pub compressed: bool,
}

/// Maps the crate's errors to ours, naming the file: variants of the format this build cannot
/// read are "unsupported", everything else means a damaged or non-LAS file.
fn convert(path: &Path, e: las::Error) -> Error {
    use las::Error as L;
    match e {
        L::Io(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => Error::io(path, io),
        L::InvalidFileSignature(sig) => Error::content(
            path,
            format!(
                "not a LAS/LAZ file: it starts with {:?} instead of \"LASF\"",
                String::from_utf8_lossy(&sig)
            ),
        ),
        e @ (L::InvalidPointFormatNumber(_)
        | L::InvalidPointFormat(_)
        | L::UnsupportedFeature { .. }
        | L::UnsupportedFormat { .. }
        | L::LaszipNotEnabled
        | L::LasZipVlrNotFound
        | L::LasZipError(_)) => {
            Error::unsupported(path, format!("unsupported LAS/LAZ variant: {e}"))
        }
        other => Error::content(path, format!("unreadable LAS/LAZ file: {other}")),
    }
}

fn open(path: &Path) -> Result<Reader> {
    super::check_nonempty_file(path)?;
    Reader::from_path(path).map_err(|e| convert(path, e))
}

/// Reads the header only.
pub fn info(path: &Path) -> Result<LasInfo> {
    let r = open(path)?;
    let h = r.header();
    let b = h.bounds();
    let v = h.version();
    Ok(LasInfo {
        points: h.number_of_points(),
        bounds: Aabb {
            min: Point3::new(b.min.x, b.min.y, b.min.z),
            max: Point3::new(b.max.x, b.max.y, b.max.z),
        },
        version: format!("{}.{}", v.major, v.minor),
        point_format: h.point_format().to_u8().unwrap_or(255),
        compressed: h.point_format().is_compressed,
    })
}

/// Points decoded per chunk: bounds the decoder's buffer on large files.
const CHUNK: u64 = 1 << 20;

/// Reads every point's coordinates into a point cloud.
pub fn read(path: &Path) -> Result<Mesh> {
    let mut r = open(path)?;
    let declared = r.header().number_of_points();
    super::e57::declared_fits(path, declared)?;
    let mut pts: Vec<Point3<f64>> = Vec::with_capacity(super::e57::capacity_hint(path, declared));
    let mut pd = PointDataBuilder::new().for_header(r.header()).build();
    loop {
        let n = r
            .fill_points(CHUNK, &mut pd)
            .map_err(|e| convert(path, e))?;
        if n == 0 {
            break;
        }
        for ((x, y), z) in pd.x().zip(pd.y()).zip(pd.z()) {
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                return Err(Error::content(
                    path,
                    format!(
                        "point {} has a non-finite coordinate ({x}, {y}, {z})",
                        pts.len() + 1
                    ),
                ));
            }
            pts.push(Point3::new(x, y, z));
        }
    }
    if pts.is_empty() {
        return Err(Error::content(path, "the LAS/LAZ file holds no points"));
    }
    if (pts.len() as u64) < declared {
        return Err(Error::content(
            path,
            format!(
                "the header declares {declared} points but only {} could be read (truncated?)",
                pts.len()
            ),
        ));
    }
    Ok(Mesh::from_points(pts, None))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use las::{Builder, Point, Writer};

    /// Writes `points` as LAS 1.2 format 1 (xyz, intensity, GPS time) with a 1e-6 grid; `.laz`
    /// paths are compressed.
    pub(crate) fn write_points(path: &Path, points: &[Point3<f64>]) {
        let mut b = Builder::from((1, 2));
        b.point_format = las::point::Format::new(1).unwrap();
        let bb = Aabb::of(points).unwrap();
        b.transforms = las::Vector {
            x: las::Transform {
                scale: 1e-6,
                offset: bb.min.x,
            },
            y: las::Transform {
                scale: 1e-6,
                offset: bb.min.y,
            },
            z: las::Transform {
                scale: 1e-6,
                offset: bb.min.z,
            },
        };
        let mut w = Writer::from_path(path, b.into_header().unwrap()).unwrap();
        for (i, p) in points.iter().enumerate() {
            w.write_point(Point {
                x: p.x,
                y: p.y,
                z: p.z,
                intensity: (i % 1000) as u16,
                gps_time: Some(i as f64),
                ..Default::default()
            })
            .unwrap();
        }
        w.close().unwrap();
    }

    fn helix() -> Vec<Point3<f64>> {
        (0..5000)
            .map(|i| {
                let t = i as f64 * 0.01;
                Point3::new(100.0 + t.cos(), -20.0 + t.sin(), 0.3 * t)
            })
            .collect()
    }

    #[test]
    fn las_and_laz_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let pts = helix();
        for name in ["h.las", "h.laz"] {
            let p = dir.path().join(name);
            write_points(&p, &pts);
            let m = read(&p).unwrap();
            assert_eq!(m.positions.len(), pts.len());
            for (a, b) in m.positions.iter().zip(&pts) {
                assert!((a - b).norm() < 2e-6, "{a} vs {b}");
            }
            let i = info(&p).unwrap();
            assert_eq!(i.points, pts.len() as u64);
            assert_eq!(i.compressed, name.ends_with(".laz"));
            let exact = Aabb::of(&pts).unwrap();
            assert!((i.bounds.min - exact.min).norm() < 2e-6);
            assert!((i.bounds.max - exact.max).norm() < 2e-6);
        }
        let las = std::fs::metadata(dir.path().join("h.las")).unwrap().len();
        let laz = std::fs::metadata(dir.path().join("h.laz")).unwrap().len();
        assert!(laz < las / 2, "LAZ {laz} bytes vs LAS {las}");
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.las");
        std::fs::write(
            &p,
            b"PLY\nthis is not a las file at all, but long enough to have a header? no",
        )
        .unwrap();
        let e = read(&p).unwrap_err();
        assert!(e.to_string().contains("bad.las"), "{e}");
        std::fs::write(&p, vec![0u8; 400]).unwrap();
        let e = read(&p).unwrap_err();
        assert!(e.to_string().contains("LASF"), "{e}");
        std::fs::write(&p, b"").unwrap();
        assert!(read(&p).unwrap_err().to_string().contains("empty"));
        // Truncated point data.
        let good = dir.path().join("good.las");
        write_points(&good, &helix());
        let bytes = std::fs::read(&good).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() - 1000]).unwrap();
        assert!(read(&p).is_err());
        // An unknown point format number is an unsupported variant.
        let mut bytes = bytes;
        bytes[104] = 42;
        std::fs::write(&p, &bytes).unwrap();
        let e = read(&p).unwrap_err();
        assert!(matches!(e, Error::Unsupported { .. }), "{e}");
    }
}
