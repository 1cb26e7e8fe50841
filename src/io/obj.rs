//! Wavefront OBJ: `v` positions (extra w or colour values ignored), `vn` normals, `f` faces
//! (`v`, `v/vt`, `v//vn`, `v/vt/vn`, negative relative indices, polygons fan-triangulated);
//! other statements (`vt`, `g`, `o`, `s`, `usemtl`, `mtllib`, `l`, `p`) are ignored.
//!
//! Hand-written rather than through tobj: tobj keeps only the vertices faces use (re-indexed per
//! model), so it cannot report a scan's unreferenced vertices nor read a `v`-only point cloud,
//! it parses in f32 by default, and its errors carry no line number.

use crate::error::{Error, Location, Result};
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use std::io::Write;
use std::path::Path;

/// Parses OBJ bytes.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let text = super::text::as_utf8(path, bytes)?;
    let mut mesh = Mesh::default();
    let mut vn: Vec<Vector3<f64>> = Vec::new();
    // Normal index per vertex as the faces assign them (first assignment wins).
    let mut vertex_normal: Vec<u32> = Vec::new();
    let mut poly: Vec<u32> = Vec::with_capacity(8);
    let mut faces_raw: Vec<(usize, Vec<i64>, Vec<Option<i64>>)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let line = line.split('#').next().unwrap_or("");
        let mut tok = line.split_whitespace();
        let Some(kw) = tok.next() else { continue };
        match kw {
            "v" | "vn" => {
                let mut c = [0.0; 3];
                for (k, ck) in c.iter_mut().enumerate() {
                    let t = tok.next().ok_or_else(|| {
                        Error::syntax(
                            path,
                            Location::Line(ln),
                            format!("'{kw}' needs 3 coordinates, found {k}"),
                        )
                    })?;
                    *ck = super::text::parse_f64(path, ln, t, "a coordinate")?;
                }
                if kw == "v" {
                    super::text::check_finite(
                        path,
                        ln,
                        c,
                        &format!("vertex {}", mesh.positions.len() + 1),
                    )?;
                    mesh.positions.push(Point3::from(c));
                } else {
                    // Found by fuzzing (tests/fuzz_regressions/obj): `vn 0.2E505` overflowed.
                    super::text::check_finite(path, ln, c, &format!("normal {}", vn.len() + 1))?;
                    vn.push(Vector3::from(c));
                }
            }
            "f" => {
                let mut vs = Vec::with_capacity(4);
                let mut ns = Vec::with_capacity(4);
                for t in tok {
                    let mut parts = t.split('/');
                    let v = parts.next().unwrap_or("");
                    let v = v.parse::<i64>().map_err(|_| {
                        Error::syntax(
                            path,
                            Location::Line(ln),
                            format!("bad face vertex '{}'", super::text::clip(t)),
                        )
                    })?;
                    let _vt = parts.next();
                    let n = match parts.next() {
                        Some(s) if !s.is_empty() => Some(s.parse::<i64>().map_err(|_| {
                            Error::syntax(
                                path,
                                Location::Line(ln),
                                format!("bad normal index in '{}'", super::text::clip(t)),
                            )
                        })?),
                        _ => None,
                    };
                    // Relative indices refer to the vertices read so far.
                    let abs = |x: i64, count: usize| -> Option<i64> {
                        if x > 0 {
                            Some(x - 1)
                        } else if x < 0 && (-x) as usize <= count {
                            Some(count as i64 + x)
                        } else {
                            None
                        }
                    };
                    let va = abs(v, mesh.positions.len()).ok_or_else(|| {
                        Error::syntax(
                            path,
                            Location::Line(ln),
                            format!(
                                "face uses vertex {v} but only {} vertices are defined before it",
                                mesh.positions.len()
                            ),
                        )
                    })?;
                    vs.push(va);
                    ns.push(n.and_then(|n| abs(n, vn.len())));
                }
                if vs.len() < 3 {
                    return Err(Error::syntax(
                        path,
                        Location::Line(ln),
                        format!("face with {} vertices (at least 3 needed)", vs.len()),
                    ));
                }
                faces_raw.push((ln, vs, ns));
            }
            _ => {}
        }
    }
    let nv = mesh.positions.len();
    if nv == 0 {
        return Err(Error::content(path, "no vertices ('v' lines) in the file"));
    }
    if !vn.is_empty() {
        vertex_normal = vec![u32::MAX; nv];
    }
    for (ln, vs, ns) in faces_raw {
        poly.clear();
        for (k, &v) in vs.iter().enumerate() {
            if v < 0 || v as usize >= nv {
                return Err(Error::syntax(
                    path,
                    Location::Line(ln),
                    format!("face uses vertex {} but the file has {nv}", v + 1),
                ));
            }
            if let (Some(n), false) = (ns[k], vertex_normal.is_empty()) {
                if vertex_normal[v as usize] == u32::MAX && (n as usize) < vn.len() {
                    vertex_normal[v as usize] = n as u32;
                }
            }
            poly.push(v as u32);
        }
        super::push_polygon(&mut mesh.faces, &poly);
    }
    // Normals: per vertex when the file pairs them one to one (`vn` count = `v` count and
    // faces without normal indices), or through the faces' `v//vn` references.
    if !vn.is_empty() {
        let all_assigned = vertex_normal.iter().all(|&n| n != u32::MAX);
        if vn.len() == nv && !all_assigned {
            mesh.normals = Some(vn);
        } else if all_assigned {
            mesh.normals = Some(vertex_normal.iter().map(|&n| vn[n as usize]).collect());
        }
    }
    Ok(mesh)
}

/// Writes OBJ: `v` lines (full precision), `vn` when normals exist, `f` lines (1-based).
pub fn write(w: &mut dyn Write, mesh: &Mesh) -> std::io::Result<()> {
    writeln!(w, "# written by scansurf {}", env!("CARGO_PKG_VERSION"))?;
    for p in &mesh.positions {
        writeln!(w, "v {:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    if let Some(ns) = &mesh.normals {
        for n in ns {
            writeln!(w, "vn {:?} {:?} {:?}", n.x, n.y, n.z)?;
        }
    }
    let with_n = mesh.normals.is_some();
    for f in &mesh.faces {
        let (a, b, c) = (f[0] + 1, f[1] + 1, f[2] + 1);
        if with_n {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}

/// Writes a quad net as OBJ: a `#` line per entry of `comments`, `v` lines (full precision),
/// one `f` line of four (1-based) vertices per quad; with `regions`, the quads in groups by
/// region and the crease edges as lines ([`QuadRegions`]).
pub fn write_quads(
    w: &mut dyn Write,
    vertices: &[nalgebra::Point3<f64>],
    quads: &[[u32; 4]],
    comments: &[String],
    regions: Option<QuadRegions<'_>>,
) -> std::io::Result<()> {
    writeln!(w, "# written by scansurf {}", env!("CARGO_PKG_VERSION"))?;
    for c in comments {
        writeln!(w, "# {c}")?;
    }
    for p in vertices {
        writeln!(w, "v {:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    let mut group = None;
    for (k, q) in quads.iter().enumerate() {
        if let Some(r) = regions.and_then(|r| r.quad_region.get(k)) {
            if group != Some(*r) {
                if *r == crate::features::net_regions::NO_REGION {
                    writeln!(w, "g unlabelled")?;
                } else {
                    writeln!(w, "g region_{r}")?;
                }
                group = Some(*r);
            }
        }
        let [a, b, c, d] = q.map(|k| k + 1);
        writeln!(w, "f {a} {b} {c} {d}")?;
    }
    if let Some(r) = regions.filter(|r| !r.crease_edges.is_empty()) {
        writeln!(w, "g creases")?;
        for e in r.crease_edges {
            writeln!(w, "l {} {}", e[0] + 1, e[1] + 1)?;
        }
    }
    Ok(())
}

/// Region labels for [`write_quads`]: per quad
/// ([`crate::features::net_regions::NO_REGION`] for none, group `unlabelled`), written as OBJ
/// groups `g region_K` (the faces keep their order, so a group may open more than once), and the
/// crease edges between regions, written as lines `l a b` in the group `creases`.
#[derive(Debug, Clone, Copy)]
pub struct QuadRegions<'a> {
    pub quad_region: &'a [u32],
    pub crease_edges: &'a [[u32; 2]],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_unreferenced_and_relative_indices() {
        let s = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf -4 -3 -2\n";
        let m = parse(Path::new("t.obj"), s.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2]]);
    }

    #[test]
    fn slash_forms_and_quads() {
        let s = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\n";
        let m = parse(Path::new("t.obj"), s.as_bytes()).unwrap();
        assert_eq!(m.faces.len(), 2);
        assert_eq!(m.normals.unwrap()[2], Vector3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn bad_index_names_line() {
        let s = "v 0 0 0\nv 1 0 0\n\nf 1 2 9\n";
        let e = parse(Path::new("t.obj"), s.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 4"), "{e}");
    }
}
