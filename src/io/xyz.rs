//! Point lists: one point per line, `x y z` or `x y z nx ny nz`, separated by spaces, tabs,
//! commas or semicolons (`.xyz`, `.txt`, `.pts`, `.csv`). Lines starting with `#` or `//` are
//! comments; a first line that is not numeric is taken as a column header (CSV); a `.pts`
//! file's leading point-count line is skipped. Columns beyond six (colours, intensity) are
//! ignored; normals are read when every point has them.

use crate::error::{Error, Location, Result};
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use std::io::Write;
use std::path::Path;

/// Parses a point list.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let text = super::text::as_utf8(path, bytes)?;
    let mut pts = Vec::with_capacity(text.len() / 30);
    let mut nrm = Vec::with_capacity(text.len() / 30);
    let mut all_normals = true;
    let mut first_data = true;
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') || t.starts_with("//") {
            continue;
        }
        let fields: Vec<&str> = t
            .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
            .filter(|s| !s.is_empty())
            .collect();
        if first_data {
            first_data = false;
            let numeric = fields.iter().all(|f| f.parse::<f64>().is_ok());
            if !numeric {
                continue; // a column header
            }
            if fields.len() == 1 {
                continue; // a .pts point count
            }
        }
        if fields.len() < 3 {
            return Err(Error::syntax(
                path,
                Location::Line(ln),
                format!(
                    "expected 'x y z [nx ny nz]', found {} value(s)",
                    fields.len()
                ),
            ));
        }
        let mut v = [0.0; 6];
        let take = if fields.len() >= 6 { 6 } else { 3 };
        for k in 0..take {
            v[k] = super::text::parse_f64(path, ln, fields[k], "a coordinate")?;
        }
        super::text::check_finite(path, ln, [v[0], v[1], v[2]], "point")?;
        pts.push(Point3::new(v[0], v[1], v[2]));
        if take == 6 && v[3..6].iter().all(|c| c.is_finite()) {
            nrm.push(Vector3::new(v[3], v[4], v[5]));
        } else {
            all_normals = false;
        }
    }
    if pts.is_empty() {
        return Err(Error::content(path, "no points in the file"));
    }
    let normals = if all_normals && nrm.len() == pts.len() {
        Some(nrm)
    } else {
        None
    };
    Ok(Mesh::from_points(pts, normals))
}

/// Writes `x y z [nx ny nz]` per line, full precision. Faces, if any, are dropped: the format
/// holds points only.
pub fn write(w: &mut dyn Write, mesh: &Mesh) -> std::io::Result<()> {
    for (i, p) in mesh.positions.iter().enumerate() {
        match &mesh.normals {
            Some(n) => writeln!(
                w,
                "{:?} {:?} {:?} {:?} {:?} {:?}",
                p.x, p.y, p.z, n[i].x, n[i].y, n[i].z
            )?,
            None => writeln!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_header_and_normals() {
        let s = "x,y,z,nx,ny,nz\n1,2,3,0,0,1\n4,5,6,0,1,0\n";
        let m = parse(Path::new("t.csv"), s.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 2);
        assert_eq!(m.normals.unwrap()[1], Vector3::new(0.0, 1.0, 0.0));
    }

    #[test]
    fn short_line_names_line() {
        let s = "1 2 3\n4 5\n";
        let e = parse(Path::new("t.xyz"), s.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2"), "{e}");
    }
}
