//! Files of detected features for a viewer: the crease polylines and corners as a PLY of
//! vertices and `edge` elements (MeshLab, CloudCompare and Blender draw them as lines), and the
//! labelled points as a PLY coloured by region with an integer `region` property.

use super::detect::{Features, UNLABELLED};
use crate::Result;
use nalgebra::Point3;
use std::path::Path;

/// Colour of the creases in the PLY and in `render --features`.
pub const CREASE_COLOUR: [u8; 3] = [220, 30, 30];
/// Colour of the corners in the PLY and in `render --features`.
pub const CORNER_COLOUR: [u8; 3] = [30, 60, 230];

/// A distinct colour per index (golden-angle hues), grey for unlabelled.
pub fn region_colour(r: u32) -> [u8; 3] {
    if r == UNLABELLED {
        return [128, 128, 128];
    }
    let h = (r as f64 * 137.507_764) % 360.0;
    let (s, v) = (0.75, 0.95);
    let c = v * s;
    let x = c * (1.0 - ((h / 60.0) % 2.0 - 1.0).abs());
    let (r1, g1, b1) = match (h / 60.0) as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r1, g1, b1].map(|t| ((t + m) * 255.0).round() as u8)
}

/// Writes the creases (red polylines) and corners (blue points, no edges) as ASCII PLY.
pub fn write_lines_ply(path: &Path, f: &Features) -> Result<()> {
    let nv: usize = f.creases.iter().map(|c| c.points.len()).sum::<usize>() + f.corners.len();
    let ne: usize = f
        .creases
        .iter()
        .map(|c| c.points.len().saturating_sub(1))
        .sum();
    crate::io::write_atomic(path, |w| {
        writeln!(w, "ply\nformat ascii 1.0\ncomment scansurf features: creases (red polylines), corners (blue)")?;
        writeln!(
            w,
            "element vertex {nv}\nproperty double x\nproperty double y\nproperty double z"
        )?;
        writeln!(
            w,
            "property uchar red\nproperty uchar green\nproperty uchar blue"
        )?;
        writeln!(
            w,
            "element edge {ne}\nproperty int vertex1\nproperty int vertex2\nend_header"
        )?;
        for c in &f.creases {
            for p in &c.points {
                let [r, g, b] = CREASE_COLOUR;
                writeln!(w, "{} {} {} {r} {g} {b}", p[0], p[1], p[2])?;
            }
        }
        for p in &f.corners {
            let [r, g, b] = CORNER_COLOUR;
            writeln!(w, "{} {} {} {r} {g} {b}", p[0], p[1], p[2])?;
        }
        let mut base = 0;
        for c in &f.creases {
            for k in 1..c.points.len() {
                writeln!(w, "{} {}", base + k - 1, base + k)?;
            }
            base += c.points.len();
        }
        Ok(())
    })
}

/// Writes the labelled points, coloured by region, as binary little-endian PLY with an `int
/// region` property (-1 for unlabelled).
pub fn write_regions_ply(path: &Path, f: &Features) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment scansurf features: points by smooth region\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty int region\nend_header\n",
            f.points.len()
        )?;
        let mut buf = Vec::with_capacity(f.points.len() * 19);
        for (p, &l) in f.points.iter().zip(&f.label) {
            for x in [p.x, p.y, p.z] {
                buf.extend_from_slice(&(x as f32).to_le_bytes());
            }
            buf.extend_from_slice(&region_colour(l));
            let id = if l == UNLABELLED { -1 } else { l as i32 };
            buf.extend_from_slice(&id.to_le_bytes());
        }
        w.write_all(&buf)
    })
}

/// A polyline's vertices.
pub type Polyline = Vec<Point3<f64>>;

/// The crease polylines and corners of a `features` JSON file, for drawing.
pub fn read_lines_json(path: &Path) -> Result<(Vec<Polyline>, Vec<Point3<f64>>)> {
    #[derive(serde::Deserialize)]
    struct CreaseIn {
        points: Vec<[f64; 3]>,
    }
    #[derive(serde::Deserialize)]
    struct FeaturesIn {
        creases: Vec<CreaseIn>,
        #[serde(default)]
        corners: Vec<[f64; 3]>,
    }
    let bytes = crate::io::read_bytes(path)?;
    let f: FeaturesIn = serde_json::from_slice(&bytes).map_err(|e| {
        crate::Error::content(
            path,
            format!("is not a features file (scansurf features -o): {e}"),
        )
    })?;
    let finite = |p: &[f64; 3]| p.iter().all(|c| c.is_finite());
    if f.creases
        .iter()
        .flat_map(|c| &c.points)
        .chain(&f.corners)
        .any(|p| !finite(p))
    {
        return Err(crate::Error::content(path, "holds a non-finite coordinate"));
    }
    Ok((
        f.creases
            .into_iter()
            .map(|c| c.points.into_iter().map(Point3::from).collect())
            .collect(),
        f.corners.into_iter().map(Point3::from).collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_differ_for_neighbouring_ids_and_grey_marks_unlabelled() {
        for r in 0..20u32 {
            let (a, b) = (region_colour(r), region_colour(r + 1));
            let d: i32 = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (*x as i32 - *y as i32).abs())
                .sum();
            assert!(d > 60, "{r}: {a:?} {b:?}");
        }
        assert_eq!(region_colour(UNLABELLED), [128, 128, 128]);
    }
}
