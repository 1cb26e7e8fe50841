//! STL, ASCII and binary. STL stores each triangle with its own three corners; the reader
//! merges corners at bitwise-identical positions into shared vertices so that the mesh has
//! adjacency (boundary loops, manifoldness) like any indexed format.

use crate::error::{Error, Location, Result};
use crate::mesh::Mesh;
use nalgebra::Point3;
use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

struct Welder {
    map: HashMap<[u64; 3], u32>,
    mesh: Mesh,
}

impl Welder {
    fn new(cap: usize) -> Self {
        Welder {
            map: HashMap::with_capacity(cap),
            mesh: Mesh::default(),
        }
    }
    fn vertex(&mut self, p: [f64; 3]) -> u32 {
        let key = [
            (p[0] + 0.0).to_bits(),
            (p[1] + 0.0).to_bits(),
            (p[2] + 0.0).to_bits(),
        ];
        let positions = &mut self.mesh.positions;
        *self.map.entry(key).or_insert_with(|| {
            positions.push(Point3::from(p));
            (positions.len() - 1) as u32
        })
    }
}

/// True when the bytes look like a binary STL: the triangle count matches the size exactly.
fn is_binary(bytes: &[u8]) -> bool {
    if bytes.len() < 84 {
        return false;
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    84 + 50 * n == bytes.len() as u64
}

/// Parses STL bytes, binary or ASCII.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    if is_binary(bytes) {
        return parse_binary(path, bytes);
    }
    let head = &bytes[..bytes.len().min(512)];
    let starts_solid = head
        .iter()
        .skip_while(|b| b.is_ascii_whitespace())
        .take(5)
        .eq(b"solid".iter());
    if starts_solid && std::str::from_utf8(head).is_ok() {
        return parse_ascii(path, bytes);
    }
    if bytes.len() < 84 {
        return Err(Error::syntax(
            path,
            Location::Byte(bytes.len() as u64),
            "too short for a binary STL (84-byte header) and not ASCII STL ('solid ...')",
        ));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    Err(Error::syntax(
        path,
        Location::Byte(84 + 50 * (((bytes.len() as u64).saturating_sub(84)) / 50)),
        format!(
            "binary STL header declares {n} triangles ({} bytes) but the file has {} bytes (truncated or not STL)",
            84 + 50 * n,
            bytes.len()
        ),
    ))
}

fn parse_binary(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let n = (bytes.len() - 84) / 50;
    let mut w = Welder::new(n / 2 + 16);
    w.mesh.faces.reserve(n);
    for t in 0..n {
        let base = 84 + 50 * t;
        let mut f = [0u32; 3];
        for (k, slot) in f.iter_mut().enumerate() {
            let o = base + 12 + 12 * k;
            let mut p = [0f64; 3];
            for (c, pc) in p.iter_mut().enumerate() {
                let b = &bytes[o + 4 * c..o + 4 * c + 4];
                *pc = f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
            }
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::syntax(
                    path,
                    Location::Byte(o as u64),
                    format!("triangle {} has a non-finite coordinate", t + 1),
                ));
            }
            *slot = w.vertex(p);
        }
        w.mesh.faces.push(f);
    }
    if w.mesh.faces.is_empty() {
        return Err(Error::content(path, "binary STL with no triangles"));
    }
    Ok(w.mesh)
}

fn parse_ascii(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let text = super::text::as_utf8(path, bytes)?;
    let mut w = Welder::new(1024);
    let mut corners: Vec<u32> = Vec::with_capacity(3);
    let mut in_loop = false;
    let mut ended = false;
    let mut last_line = 0;
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        last_line = ln;
        let mut tok = line.split_whitespace();
        let Some(kw) = tok.next() else { continue };
        let err = |m: String| Error::syntax(path, Location::Line(ln), m);
        match kw {
            "solid" | "facet" => {}
            "outer" => {
                in_loop = true;
                corners.clear();
            }
            "vertex" => {
                if !in_loop {
                    return Err(err("'vertex' outside 'outer loop'".into()));
                }
                let mut p = [0.0; 3];
                for (c, pc) in p.iter_mut().enumerate() {
                    let t = tok
                        .next()
                        .ok_or_else(|| err(format!("vertex needs 3 coordinates, found {c}")))?;
                    *pc = super::text::parse_f64(path, ln, t, "a vertex coordinate")?;
                }
                super::text::check_finite(path, ln, p, "vertex")?;
                if corners.len() >= 3 {
                    return Err(err("more than 3 vertices in a facet".into()));
                }
                corners.push(w.vertex(p));
            }
            "endloop" => {
                if corners.len() != 3 {
                    return Err(err(format!(
                        "facet has {} vertices, STL needs 3",
                        corners.len()
                    )));
                }
                w.mesh.faces.push([corners[0], corners[1], corners[2]]);
                in_loop = false;
            }
            "endfacet" => {}
            "endsolid" => ended = true,
            other => {
                return Err(err(format!(
                    "unexpected keyword '{}'",
                    super::text::clip(other)
                )))
            }
        }
    }
    if in_loop || !ended {
        return Err(Error::syntax(
            path,
            Location::Line(last_line),
            "file ends before 'endsolid' (truncated?)",
        ));
    }
    if w.mesh.faces.is_empty() {
        return Err(Error::content(path, "ASCII STL with no facets"));
    }
    Ok(w.mesh)
}

/// Writes STL, binary (default) or ASCII, with face normals.
pub fn write(w: &mut dyn Write, mesh: &Mesh, ascii: bool) -> std::io::Result<()> {
    let normal = |fi: usize| {
        let c = mesh.face_cross(fi);
        let l = c.norm();
        if l > 0.0 {
            c / l
        } else {
            c
        }
    };
    if ascii {
        writeln!(w, "solid scansurf")?;
        for (fi, f) in mesh.faces.iter().enumerate() {
            let n = normal(fi);
            writeln!(w, "  facet normal {:e} {:e} {:e}", n.x, n.y, n.z)?;
            writeln!(w, "    outer loop")?;
            for &v in f {
                let p = mesh.positions[v as usize];
                writeln!(w, "      vertex {:e} {:e} {:e}", p.x, p.y, p.z)?;
            }
            writeln!(w, "    endloop")?;
            writeln!(w, "  endfacet")?;
        }
        writeln!(w, "endsolid scansurf")?;
    } else {
        let mut header = [b' '; 80];
        let tag = b"binary STL written by scansurf";
        header[..tag.len()].copy_from_slice(tag);
        w.write_all(&header)?;
        w.write_all(&(mesh.faces.len() as u32).to_le_bytes())?;
        for (fi, f) in mesh.faces.iter().enumerate() {
            for c in normal(fi).iter() {
                w.write_all(&(*c as f32).to_le_bytes())?;
            }
            for &v in f {
                for c in mesh.positions[v as usize].iter() {
                    w.write_all(&(*c as f32).to_le_bytes())?;
                }
            }
            w.write_all(&[0u8, 0u8])?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_welds_shared_corners() {
        let s = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let m = parse(Path::new("t.stl"), s.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces.len(), 2);
    }

    #[test]
    fn truncated_ascii() {
        let s = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
        let e = parse(Path::new("t.stl"), s.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated") && e.contains("line 4"), "{e}");
    }

    #[test]
    fn truncated_binary_names_sizes() {
        let mut b = vec![0u8; 80];
        b.extend_from_slice(&10u32.to_le_bytes());
        b.extend_from_slice(&[0u8; 120]);
        let e = parse(Path::new("t.stl"), &b).unwrap_err().to_string();
        assert!(e.contains("10 triangles") && e.contains("byte"), "{e}");
    }
}
