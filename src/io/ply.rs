//! PLY (Stanford polygon file format), ASCII and binary little/big endian.
//!
//! Reads the `vertex` element (x, y, z and, when all three are present, nx, ny, nz), the `face`
//! element (`vertex_indices` or `vertex_index` lists, polygons fan-triangulated) and the
//! `tristrips` element (lists with -1 restarting a strip, as the public Igea scan stores its
//! triangles). Any other element or property is skipped by its declared type. Hand-written
//! rather than through a PLY crate because none of them reads tristrips, reports byte offsets,
//! or refuses to pre-allocate a header's claimed counts before the data is there.

use crate::error::{Error, Location, Result};
use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use std::io::Write;
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn read(self, b: &[u8], be: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if be {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => rd!(i16, 2),
            Scalar::U16 => rd!(u16, 2),
            Scalar::I32 => rd!(i32, 4),
            Scalar::U32 => rd!(u32, 4),
            Scalar::F32 => rd!(f32, 4),
            Scalar::F64 => rd!(f64, 8),
        }
    }
}

#[derive(Debug, Clone)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    kind: PropKind,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// Number of header lines (for ASCII line numbers).
    lines: usize,
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    if !bytes.starts_with(b"ply") {
        return Err(Error::syntax(
            path,
            Location::Line(1),
            "not a PLY file: it must start with the line 'ply'",
        ));
    }
    // The header is ASCII text ending with the line "end_header".
    let limit = bytes.len().min(1 << 20);
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(nl) = bytes[pos..limit].iter().position(|&b| b == b'\n') else {
            return Err(Error::syntax(
                path,
                Location::Line(line_no + 1),
                "header never ends: no 'end_header' line",
            ));
        };
        line_no += 1;
        let raw = &bytes[pos..pos + nl];
        pos += nl + 1;
        let line = std::str::from_utf8(raw)
            .map_err(|_| Error::syntax(path, Location::Line(line_no), "header is not ASCII text"))?
            .trim_end_matches('\r')
            .trim();
        let tok: Vec<&str> = line.split_whitespace().collect();
        let err = |m: String| Error::syntax(path, Location::Line(line_no), m);
        match tok.first().copied() {
            None => {}
            Some("ply") if line_no == 1 => {}
            Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if tok.len() != 3 {
                    return Err(err(format!("bad format line '{line}'")));
                }
                encoding = Some(match tok[1] {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLe,
                    "binary_big_endian" => Encoding::BinaryBe,
                    other => return Err(err(format!("unknown PLY format '{other}'"))),
                });
                if tok[2] != "1.0" {
                    return Err(err(format!("unsupported PLY version '{}'", tok[2])));
                }
            }
            Some("element") => {
                if tok.len() != 3 {
                    return Err(err(format!("bad element line '{line}'")));
                }
                let count = tok[2].parse::<usize>().map_err(|_| {
                    err(format!(
                        "element count '{}' is not a non-negative integer",
                        tok[2]
                    ))
                })?;
                elements.push(Element {
                    name: tok[1].to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let Some(el) = elements.last_mut() else {
                    return Err(err("property before any element".into()));
                };
                let prop = if tok.get(1) == Some(&"list") {
                    if tok.len() != 5 {
                        return Err(err(format!("bad list property line '{line}'")));
                    }
                    let count = Scalar::parse(tok[2])
                        .ok_or_else(|| err(format!("unknown type '{}'", tok[2])))?;
                    let item = Scalar::parse(tok[3])
                        .ok_or_else(|| err(format!("unknown type '{}'", tok[3])))?;
                    if matches!(count, Scalar::F32 | Scalar::F64) {
                        return Err(err("a list count must be an integer type".into()));
                    }
                    Property {
                        name: tok[4].to_string(),
                        kind: PropKind::List { count, item },
                    }
                } else {
                    if tok.len() != 3 {
                        return Err(err(format!("bad property line '{line}'")));
                    }
                    let s = Scalar::parse(tok[1])
                        .ok_or_else(|| err(format!("unknown type '{}'", tok[1])))?;
                    Property {
                        name: tok[2].to_string(),
                        kind: PropKind::Scalar(s),
                    }
                };
                el.props.push(prop);
            }
            Some("end_header") => break,
            Some(other) => return Err(err(format!("unexpected header keyword '{other}'"))),
        }
    }
    let encoding = encoding
        .ok_or_else(|| Error::syntax(path, Location::Line(2), "header has no 'format' line"))?;
    Ok(Header {
        encoding,
        elements,
        data_start: pos,
        lines: line_no,
    })
}

/// Where the vertex element keeps the fields scansurf reads.
struct VertexLayout {
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
}

fn vertex_layout(path: &Path, el: &Element) -> Result<VertexLayout> {
    let find = |n: &str| el.props.iter().position(|p| p.name == n);
    let (Some(x), Some(y), Some(z)) = (find("x"), find("y"), find("z")) else {
        return Err(Error::content(
            path,
            "the vertex element lacks x, y or z properties",
        ));
    };
    for &i in &[x, y, z] {
        if matches!(el.props[i].kind, PropKind::List { .. }) {
            return Err(Error::content(path, "vertex coordinates declared as lists"));
        }
    }
    let normal = match (find("nx"), find("ny"), find("nz")) {
        (Some(a), Some(b), Some(c))
            if [a, b, c]
                .iter()
                .all(|&i| matches!(el.props[i].kind, PropKind::Scalar(_))) =>
        {
            Some([a, b, c])
        }
        _ => None,
    };
    Ok(VertexLayout {
        xyz: [x, y, z],
        normal,
    })
}

fn face_list_index(el: &Element) -> Option<usize> {
    el.props.iter().position(|p| {
        matches!(p.kind, PropKind::List { .. })
            && (p.name == "vertex_indices" || p.name == "vertex_index")
    })
}

/// Appends the triangles of one strip (with -1 restarts) to `faces`, keeping orientation and
/// skipping the degenerate joining triangles strips use.
fn push_strip(faces: &mut Vec<[u32; 3]>, strip: &[i64]) {
    for run in strip.split(|&v| v < 0) {
        for k in 0..run.len().saturating_sub(2) {
            let (a, b, c) = (run[k] as u32, run[k + 1] as u32, run[k + 2] as u32);
            if a == b || b == c || a == c {
                continue;
            }
            faces.push(if k % 2 == 0 { [a, b, c] } else { [b, a, c] });
        }
    }
}

/// Parses a PLY file's bytes.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let h = parse_header(path, bytes)?;
    let mut mesh = Mesh::default();
    let mut normals: Vec<Vector3<f64>> = Vec::new();
    let mut saw_vertex = false;
    match h.encoding {
        Encoding::Ascii => parse_ascii(path, bytes, &h, &mut mesh, &mut normals, &mut saw_vertex)?,
        Encoding::BinaryLe | Encoding::BinaryBe => parse_binary(
            path,
            bytes,
            &h,
            h.encoding == Encoding::BinaryBe,
            &mut mesh,
            &mut normals,
            &mut saw_vertex,
        )?,
    }
    if !saw_vertex {
        return Err(Error::content(path, "the file has no 'vertex' element"));
    }
    if !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    if mesh.positions.is_empty() {
        return Err(Error::content(path, "the file has no vertices"));
    }
    Ok(mesh)
}

fn check_index(path: &Path, loc: Location, v: f64, nv: usize) -> Result<u32> {
    if v < 0.0 || v >= nv as f64 || v.fract() != 0.0 {
        return Err(Error::syntax(
            path,
            loc,
            format!("face uses vertex index {v} but the file has {nv} vertices"),
        ));
    }
    Ok(v as u32)
}

fn parse_binary(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    be: bool,
    mesh: &mut Mesh,
    normals: &mut Vec<Vector3<f64>>,
    saw_vertex: &mut bool,
) -> Result<()> {
    let mut pos = h.data_start;
    let truncated = |pos: usize, what: &str| {
        Error::syntax(
            path,
            Location::Byte(pos as u64),
            format!("file ends early, inside {what} (truncated?)"),
        )
    };
    for el in &h.elements {
        // Smallest possible row size, to refuse counts the remaining bytes cannot hold before
        // allocating anything for them.
        let min_row: usize = el
            .props
            .iter()
            .map(|p| match p.kind {
                PropKind::Scalar(s) => s.size(),
                PropKind::List { count, .. } => count.size(),
            })
            .sum();
        let remaining = bytes.len() - pos;
        if min_row > 0 && el.count > remaining / min_row {
            return Err(Error::syntax(
                path,
                Location::Byte(pos as u64),
                format!(
                    "header declares {} '{}' rows of at least {} bytes but only {} bytes follow (truncated?)",
                    el.count, el.name, min_row, remaining
                ),
            ));
        }
        let fixed = el
            .props
            .iter()
            .all(|p| matches!(p.kind, PropKind::Scalar(_)));
        let offsets: Vec<usize> = el
            .props
            .iter()
            .scan(0usize, |acc, p| {
                let o = *acc;
                if let PropKind::Scalar(s) = p.kind {
                    *acc += s.size();
                }
                Some(o)
            })
            .collect();
        if el.name == "vertex" {
            *saw_vertex = true;
            let layout = vertex_layout(path, el)?;
            if !fixed {
                return Err(Error::unsupported(
                    path,
                    "vertex element with list properties is not supported",
                ));
            }
            let scalar = |i: usize| match el.props[i].kind {
                PropKind::Scalar(s) => s,
                PropKind::List { .. } => Scalar::F32,
            };
            let row = min_row;
            mesh.positions.reserve(el.count);
            if layout.normal.is_some() {
                normals.reserve(el.count);
            }
            for r in 0..el.count {
                let base = pos + r * row;
                let rd = |i: usize| scalar(i).read(&bytes[base + offsets[i]..], be);
                let p = Point3::new(rd(layout.xyz[0]), rd(layout.xyz[1]), rd(layout.xyz[2]));
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(Error::syntax(
                        path,
                        Location::Byte(base as u64),
                        format!("vertex {} has a non-finite coordinate", r + 1),
                    ));
                }
                mesh.positions.push(p);
                if let Some(n) = layout.normal {
                    normals.push(Vector3::new(rd(n[0]), rd(n[1]), rd(n[2])));
                }
            }
            pos += el.count * row;
            continue;
        }
        if fixed {
            pos += el.count * min_row;
            continue;
        }
        let list_at = face_list_index(el);
        let is_face = el.name == "face" && list_at.is_some();
        let is_strip = el.name == "tristrips" && list_at.is_some();
        if is_face {
            mesh.faces.reserve(el.count.min(remaining / 4));
        }
        let nv = mesh.positions.len();
        let mut poly: Vec<u32> = Vec::new();
        let mut strip: Vec<i64> = Vec::new();
        for _ in 0..el.count {
            let row_start = pos;
            for (pi, p) in el.props.iter().enumerate() {
                match p.kind {
                    PropKind::Scalar(s) => {
                        if pos + s.size() > bytes.len() {
                            return Err(truncated(pos, &el.name));
                        }
                        pos += s.size();
                    }
                    PropKind::List { count, item } => {
                        if pos + count.size() > bytes.len() {
                            return Err(truncated(pos, &el.name));
                        }
                        let n = count.read(&bytes[pos..], be);
                        if n < 0.0 {
                            return Err(Error::syntax(
                                path,
                                Location::Byte(pos as u64),
                                format!("negative list length {n}"),
                            ));
                        }
                        let n = n as usize;
                        pos += count.size();
                        if n > (bytes.len() - pos) / item.size() {
                            return Err(truncated(pos, &el.name));
                        }
                        let wanted = Some(pi) == list_at && (is_face || is_strip);
                        if wanted && is_face {
                            if n < 3 {
                                return Err(Error::syntax(
                                    path,
                                    Location::Byte(row_start as u64),
                                    format!("face with {n} vertices (at least 3 needed)"),
                                ));
                            }
                            poly.clear();
                            for k in 0..n {
                                let v = item.read(&bytes[pos + k * item.size()..], be);
                                poly.push(check_index(
                                    path,
                                    Location::Byte((pos + k * item.size()) as u64),
                                    v,
                                    nv,
                                )?);
                            }
                            super::push_polygon(&mut mesh.faces, &poly);
                        } else if wanted && is_strip {
                            strip.clear();
                            for k in 0..n {
                                let at = pos + k * item.size();
                                let v = item.read(&bytes[at..], be);
                                // -1 restarts; with an unsigned item type it reads as the max.
                                let restart =
                                    v < 0.0 || (item == Scalar::U32 && v == u32::MAX as f64);
                                if restart {
                                    strip.push(-1);
                                } else {
                                    strip
                                        .push(check_index(path, Location::Byte(at as u64), v, nv)?
                                            as i64);
                                }
                            }
                            push_strip(&mut mesh.faces, &strip);
                        }
                        pos += n * item.size();
                    }
                }
            }
        }
    }
    Ok(())
}

fn parse_ascii(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    mesh: &mut Mesh,
    normals: &mut Vec<Vector3<f64>>,
    saw_vertex: &mut bool,
) -> Result<()> {
    let text =
        super::text::as_utf8(path, &bytes[h.data_start..]).map_err(|e| shift_line(e, h.lines))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1 + h.lines, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    for el in &h.elements {
        let is_vertex = el.name == "vertex";
        let layout = if is_vertex {
            *saw_vertex = true;
            Some(vertex_layout(path, el)?)
        } else {
            None
        };
        let list_at = face_list_index(el);
        let is_face = el.name == "face" && list_at.is_some();
        let is_strip = el.name == "tristrips" && list_at.is_some();
        if is_vertex {
            mesh.positions.reserve(el.count.min(text.len() / 6));
        }
        let nv = mesh.positions.len();
        for r in 0..el.count {
            let Some((ln, line)) = lines.next() else {
                return Err(Error::syntax(
                    path,
                    Location::Line(h.lines + text.lines().count() + 1),
                    format!(
                        "file ends after {r} of {} '{}' rows (truncated?)",
                        el.count, el.name
                    ),
                ));
            };
            let mut tok = line.split_whitespace();
            let mut vals: Vec<f64> = Vec::with_capacity(el.props.len());
            let mut list: Vec<f64> = Vec::new();
            for (pi, p) in el.props.iter().enumerate() {
                let mut next = |what: &str| -> Result<f64> {
                    let t = tok.next().ok_or_else(|| {
                        Error::syntax(
                            path,
                            Location::Line(ln),
                            format!("missing value for {what}"),
                        )
                    })?;
                    super::text::parse_f64(path, ln, t, what)
                };
                match p.kind {
                    PropKind::Scalar(_) => vals.push(next(&p.name)?),
                    PropKind::List { .. } => {
                        let n = next(&p.name)?;
                        if !(0.0..=1e7).contains(&n) || n.fract() != 0.0 {
                            return Err(Error::syntax(
                                path,
                                Location::Line(ln),
                                format!("bad list length {n}"),
                            ));
                        }
                        let mut items = Vec::with_capacity(n as usize);
                        for _ in 0..n as usize {
                            items.push(next(&p.name)?);
                        }
                        if Some(pi) == list_at {
                            list = items;
                        }
                        vals.push(f64::NAN);
                    }
                }
            }
            if let Some(l) = &layout {
                let v = [vals[l.xyz[0]], vals[l.xyz[1]], vals[l.xyz[2]]];
                super::text::check_finite(path, ln, v, &format!("vertex {}", r + 1))?;
                mesh.positions.push(Point3::from(v));
                if let Some(n) = l.normal {
                    normals.push(Vector3::new(vals[n[0]], vals[n[1]], vals[n[2]]));
                }
            } else if is_face {
                if list.len() < 3 {
                    return Err(Error::syntax(
                        path,
                        Location::Line(ln),
                        format!("face with {} vertices (at least 3 needed)", list.len()),
                    ));
                }
                let poly = list
                    .iter()
                    .map(|&v| check_index(path, Location::Line(ln), v, nv))
                    .collect::<Result<Vec<u32>>>()?;
                super::push_polygon(&mut mesh.faces, &poly);
            } else if is_strip {
                let strip = list
                    .iter()
                    .map(|&v| {
                        if v < 0.0 {
                            Ok(-1)
                        } else {
                            check_index(path, Location::Line(ln), v, nv).map(|x| x as i64)
                        }
                    })
                    .collect::<Result<Vec<i64>>>()?;
                push_strip(&mut mesh.faces, &strip);
            }
        }
    }
    Ok(())
}

fn shift_line(e: Error, by: usize) -> Error {
    match e {
        Error::Syntax {
            path,
            location: Location::Line(l),
            message,
        } => Error::Syntax {
            path,
            location: Location::Line(l + by),
            message,
        },
        other => other,
    }
}

/// Writes PLY: binary little endian (default) or ASCII; double coordinates, float normals,
/// `uchar int vertex_indices` faces.
pub fn write(w: &mut dyn Write, mesh: &Mesh, ascii: bool) -> std::io::Result<()> {
    writeln!(w, "ply")?;
    writeln!(
        w,
        "format {} 1.0",
        if ascii {
            "ascii"
        } else {
            "binary_little_endian"
        }
    )?;
    writeln!(
        w,
        "comment written by scansurf {}",
        env!("CARGO_PKG_VERSION")
    )?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    for c in ["x", "y", "z"] {
        writeln!(w, "property double {c}")?;
    }
    if mesh.normals.is_some() {
        for c in ["nx", "ny", "nz"] {
            writeln!(w, "property float {c}")?;
        }
    }
    if !mesh.faces.is_empty() {
        writeln!(w, "element face {}", mesh.faces.len())?;
        writeln!(w, "property list uchar int vertex_indices")?;
    }
    writeln!(w, "end_header")?;
    for (i, p) in mesh.positions.iter().enumerate() {
        let n = mesh.normals.as_ref().map(|n| n[i]);
        if ascii {
            write!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
            if let Some(n) = n {
                write!(w, " {:?} {:?} {:?}", n.x as f32, n.y as f32, n.z as f32)?;
            }
            writeln!(w)?;
        } else {
            for c in p.iter() {
                w.write_all(&c.to_le_bytes())?;
            }
            if let Some(n) = n {
                for c in n.iter() {
                    w.write_all(&(*c as f32).to_le_bytes())?;
                }
            }
        }
    }
    for f in &mesh.faces {
        if ascii {
            writeln!(w, "3 {} {} {}", f[0], f[1], f[2])?;
        } else {
            w.write_all(&[3u8])?;
            for &v in f {
                w.write_all(&(v as i32).to_le_bytes())?;
            }
        }
    }
    Ok(())
}

/// Writes points with a scalar per point (e.g. deviation) as binary little-endian PLY: double
/// x y z, float `quality` (the name MeshLab and CloudCompare show as a scalar field) and uchar
/// red green blue from `colors`, for viewing the scalar in those tools.
pub fn write_scalar_cloud(
    w: &mut dyn Write,
    points: &[Point3<f64>],
    values: &[f64],
    colors: &[[u8; 3]],
) -> std::io::Result<()> {
    if values.len() != points.len() || colors.len() != points.len() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "one value and one colour per point needed",
        ));
    }
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by scansurf {}\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nproperty float quality\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        env!("CARGO_PKG_VERSION"),
        points.len()
    )?;
    for ((p, v), c) in points.iter().zip(values).zip(colors) {
        for x in p.iter() {
            w.write_all(&x.to_le_bytes())?;
        }
        w.write_all(&(*v as f32).to_le_bytes())?;
        w.write_all(c)?;
    }
    Ok(())
}

/// Reads back points with a scalar per point, as [`write_scalar_cloud`] writes them (a
/// `fit --deviation-ply` file): a binary PLY whose first element is `vertex`, of scalar
/// properties only, with `x`, `y`, `z` and the scalar property `name` (e.g. `quality`). Other
/// properties are skipped; ASCII files, list properties or a missing property are refused.
pub fn read_scalar_cloud(path: &Path, name: &str) -> Result<(Vec<Point3<f64>>, Vec<f64>)> {
    let bytes = super::read_bytes(path)?;
    let h = parse_header(path, &bytes)?;
    let be =
        match h.encoding {
            Encoding::BinaryLe => false,
            Encoding::BinaryBe => true,
            Encoding::Ascii => return Err(Error::unsupported(
                path,
                "a per-point scalar is read from binary PLY only (as `fit --deviation-ply` writes)",
            )),
        };
    let el = match h.elements.first() {
        Some(el) if el.name == "vertex" => el,
        _ => return Err(Error::content(path, "the first element is not 'vertex'")),
    };
    let mut offsets = Vec::with_capacity(el.props.len());
    let mut row = 0usize;
    for p in &el.props {
        let PropKind::Scalar(t) = p.kind else {
            return Err(Error::unsupported(
                path,
                "vertex element with list properties",
            ));
        };
        offsets.push((p.name.as_str(), row, t));
        row += t.size();
    }
    let find = |want: &str| {
        offsets
            .iter()
            .find(|(n, _, _)| *n == want)
            .map(|&(_, o, t)| (o, t))
            .ok_or_else(|| Error::content(path, format!("the vertices have no '{want}' property")))
    };
    let (x, y, z, q) = (find("x")?, find("y")?, find("z")?, find(name)?);
    let data = &bytes[h.data_start..];
    if row == 0 || el.count > data.len() / row {
        return Err(Error::syntax(
            path,
            Location::Byte(h.data_start as u64),
            format!(
                "header declares {} vertices of {} bytes but only {} bytes follow (truncated?)",
                el.count,
                row,
                data.len()
            ),
        ));
    }
    let mut points = Vec::with_capacity(el.count);
    let mut values = Vec::with_capacity(el.count);
    for (i, r) in data.chunks_exact(row).take(el.count).enumerate() {
        let get = |(o, t): (usize, Scalar)| t.read(&r[o..], be);
        let p = Point3::new(get(x), get(y), get(z));
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::syntax(
                path,
                Location::Byte((h.data_start + i * row) as u64),
                format!("vertex {i} has a non-finite coordinate"),
            ));
        }
        points.push(p);
        values.push(get(q));
    }
    Ok((points, values))
}

/// Writes a binary PLY whose triangles are stored as one `tristrips` element (each triangle a
/// strip of three, separated by -1), as some scanners' software does. For fixtures and tests.
pub fn write_tristrips(w: &mut dyn Write, mesh: &Mesh, big_endian: bool) -> std::io::Result<()> {
    let enc = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    write!(
        w,
        "ply\nformat {enc} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n",
        mesh.positions.len()
    )?;
    let put_f = |w: &mut dyn Write, x: f32| {
        w.write_all(&if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    let put_i = |w: &mut dyn Write, x: i32| {
        w.write_all(&if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    for p in &mesh.positions {
        for c in p.iter() {
            put_f(w, *c as f32)?;
        }
    }
    let n = if mesh.faces.is_empty() {
        0
    } else {
        4 * mesh.faces.len() - 1
    };
    put_i(w, n as i32)?;
    for (i, f) in mesh.faces.iter().enumerate() {
        if i > 0 {
            put_i(w, -1)?;
        }
        for &v in f {
            put_i(w, v as i32)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalar_cloud_round_trip_and_refusals() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("d.ply");
        let pts = vec![Point3::new(1.0, -2.0, 0.5), Point3::new(0.25, 3.0, -1.0)];
        let mut buf = Vec::new();
        write_scalar_cloud(&mut buf, &pts, &[1e-3, 0.5], &[[1, 2, 3], [4, 5, 6]]).unwrap();
        std::fs::write(&f, &buf).unwrap();
        let (p, v) = read_scalar_cloud(&f, "quality").unwrap();
        assert_eq!(p, pts);
        assert_eq!(v, vec![1e-3f32 as f64, 0.5]);
        // A missing property, a truncated body, ASCII: errors that name the file.
        let e = read_scalar_cloud(&f, "confidence").unwrap_err().to_string();
        assert!(e.contains("d.ply") && e.contains("confidence"), "{e}");
        std::fs::write(&f, &buf[..buf.len() - 5]).unwrap();
        let e = read_scalar_cloud(&f, "quality").unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        std::fs::write(
            &f,
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
        )
        .unwrap();
        assert!(read_scalar_cloud(&f, "quality").is_err());
    }

    fn p() -> &'static Path {
        Path::new("t.ply")
    }

    #[test]
    fn strip_orientation_and_restart() {
        let mut f = Vec::new();
        push_strip(&mut f, &[0, 1, 2, 3, -1, 4, 5, 6, 6, 7]);
        assert_eq!(f, vec![[0, 1, 2], [2, 1, 3], [4, 5, 6]]);
    }

    #[test]
    fn ascii_with_extra_elements_and_properties() {
        let s = "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty float x\nproperty float y\nproperty uchar red\nproperty float z\nelement edge 1\nproperty int a\nproperty int b\nelement face 1\nproperty uchar flags\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n0 0 9 0\n1 0 9 0\n1 1 9 0\n0 1 9 0\n0 1\n7 4 0 1 2 3 2 0.5 0.5\n";
        let m = parse(p(), s.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(m.normals.is_none());
    }

    #[test]
    fn truncated_binary_names_byte() {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
        b.extend_from_slice(&[0u8; 20]);
        let e = parse(p(), &b).unwrap_err().to_string();
        assert!(e.contains("byte") && e.contains("truncated"), "{e}");
    }

    #[test]
    fn huge_claimed_count_is_refused_without_allocating() {
        let b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0";
        let e = parse(p(), b).unwrap_err().to_string();
        assert!(e.contains("4000000000"), "{e}");
    }

    #[test]
    fn wrong_magic() {
        let e = parse(p(), b"solid x\n").unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("not a PLY"), "{e}");
    }

    #[test]
    fn face_index_past_vertices() {
        let s = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n";
        let e = parse(p(), s.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("line 13") && e.contains("index 5"), "{e}");
    }

    #[test]
    fn nan_vertex() {
        let s = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\nnan 1 0\n";
        let e = parse(p(), s.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("line 9") && e.contains("non-finite"), "{e}");
    }
}
