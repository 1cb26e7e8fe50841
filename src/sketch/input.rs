//! Reading a drawing: SVG paths/polygons or a JSON list of closed polylines, in the z = 0 plane
//! (seed 001 section 3, the input of the contour analysis).
//!
//! SVG: `<path d="...">` with M/L/H/V/C/Z (absolute and relative; every subpath must be closed
//! by Z or end on its first point), `<polygon points="...">`. Cubic Béziers are flattened into
//! 16 segments. The y axis is flipped (SVG y points down) so the model is not mirrored. Depth
//! order of overlapping contours: a contour drawn later lies in front (painter's order), unless
//! a `data-over="i j ..."` attribute names the (0-based, document order) contours this element's
//! contours lie over; the order is then taken from that pair list, so cyclic overlaps (a knot)
//! can be drawn.
//!
//! JSON: `{"contours": [[[x, y], ...], ...], "over": [[front, back], ...]}`; each polyline must
//! end on its first point. `over` is optional (default: later contours in front).
//!
//! Hand-written on purpose: the subset needed is small and a full SVG/XML stack (usvg, roxmltree)
//! would be a large dependency for it.

use crate::error::{Error, Location, Result};
use nalgebra::Point2;
use std::path::Path;

/// A drawing: closed contours (first point not repeated at the end), depth pairs, and open
/// strokes whose two ends touch a closed contour (T-junctions: the rest of the stroke is
/// hidden behind it and is completed by [`super::completion`]).
#[derive(Debug, Clone, Default)]
pub struct Drawing {
    pub contours: Vec<Vec<Point2<f64>>>,
    /// (front, back) contour pairs given explicitly; pairs not listed follow document order.
    pub over: Vec<(usize, usize)>,
    /// Open strokes ending on closed contours (at least 2 points each).
    pub strokes: Vec<Vec<Point2<f64>>>,
    /// Open polylines met while parsing, with the error to give if they touch nothing.
    pub(crate) open: Vec<(Vec<Point2<f64>>, String)>,
}

/// How far (fraction of the drawing's diagonal) a stroke end may lie from a closed contour to
/// count as a T-junction on it.
pub const JUNCTION_TOLERANCE: f64 = 0.02;

/// Distance from `p` to the closed polyline `c`.
pub fn distance_to_loop(c: &[Point2<f64>], p: &Point2<f64>) -> f64 {
    let n = c.len();
    (0..n)
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % n]);
            let ab = b - a;
            let t = if ab.norm_squared() > 0.0 {
                ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + ab * t - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Reads an SVG or JSON drawing (by extension; content sniffing when the extension is neither).
pub fn read_drawing(path: &Path) -> Result<Drawing> {
    let bytes = crate::io::read_bytes(path)?;
    parse_drawing(path, bytes)
}

/// Parses a drawing from its bytes (`path` names it in errors and chooses SVG or JSON by
/// extension): the entry point of the SVG/JSON fuzz target.
pub fn parse_drawing(path: &Path, bytes: Vec<u8>) -> Result<Drawing> {
    let text = String::from_utf8(bytes)
        .map_err(|_| Error::content(path, "the drawing is not UTF-8 text"))?;
    if text.trim().is_empty() {
        return Err(Error::content(path, "the drawing file is empty"));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut d = if ext == "json" || (ext != "svg" && text.trim_start().starts_with('{')) {
        parse_json(path, &text)?
    } else {
        parse_svg(path, &text)?
    };
    // Open strokes are kept only where both ends touch a closed contour (T-junctions).
    let (open, messages): (Vec<_>, Vec<_>) = std::mem::take(&mut d.open).into_iter().unzip();
    let all: Vec<Point2<f64>> = d.contours.iter().chain(&open).flatten().copied().collect();
    let (lo, hi) = all.iter().fold(
        (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        ),
        |(a, b), p| (a.inf(p), b.sup(p)),
    );
    let tol = JUNCTION_TOLERANCE * (hi - lo).norm();
    for (s, msg) in open.into_iter().zip(messages) {
        if s.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(Error::content(
                path,
                "an open stroke has a non-finite coordinate",
            ));
        }
        let touches = |p: &Point2<f64>| d.contours.iter().any(|c| distance_to_loop(c, p) <= tol);
        match (s.first(), s.last()) {
            (Some(a), Some(b)) if s.len() >= 2 && touches(a) && touches(b) => d.strokes.push(s),
            _ => return Err(Error::content(path, msg)),
        }
    }
    if d.contours.is_empty() {
        return Err(Error::content(path, "the drawing has no closed contour"));
    }
    for (k, c) in d.contours.iter().enumerate() {
        if c.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(Error::content(
                path,
                format!("contour {k} has a non-finite coordinate"),
            ));
        }
    }
    for &(a, b) in &d.over {
        if a >= d.contours.len() || b >= d.contours.len() || a == b {
            return Err(Error::content(
                path,
                format!(
                    "depth pair ({a}, {b}) names a contour that does not exist (there are {})",
                    d.contours.len()
                ),
            ));
        }
    }
    Ok(d)
}

fn parse_json(path: &Path, text: &str) -> Result<Drawing> {
    #[derive(serde::Deserialize)]
    struct Json {
        contours: Vec<Vec<[f64; 2]>>,
        #[serde(default)]
        over: Vec<[usize; 2]>,
    }
    let j: Json = serde_json::from_str(text)
        .map_err(|e| Error::syntax(path, Location::Line(e.line()), e.to_string()))?;
    let mut d = Drawing::default();
    for (k, c) in j.contours.iter().enumerate() {
        let pts: Vec<Point2<f64>> = c.iter().map(|p| Point2::new(p[0], p[1])).collect();
        add_polyline(&mut d, path, pts, &format!("contour {k}"), false)?;
    }
    d.over = j.over.iter().map(|p| (p[0], p[1])).collect();
    Ok(d)
}

/// A closed polyline goes to the contours; an open one is kept aside (a possible T-junction
/// stroke, checked once all contours are read) with the "open" error it gets otherwise.
fn add_polyline(
    d: &mut Drawing,
    path: &Path,
    pts: Vec<Point2<f64>>,
    what: &str,
    closed_by_z: bool,
) -> Result<()> {
    match close(path, pts.clone(), what, closed_by_z) {
        Ok(c) => d.contours.push(c),
        Err(Error::Content { message, .. }) if message.contains("is open") => {
            let mut p = pts;
            p.dedup_by(|a, b| (*a - *b).norm() == 0.0);
            d.open.push((p, message));
        }
        Err(e) => return Err(e),
    }
    Ok(())
}

/// Checks that a polyline ends on its first point (or was closed by Z) and drops the repeat.
fn close(
    path: &Path,
    mut pts: Vec<Point2<f64>>,
    what: &str,
    closed_by_z: bool,
) -> Result<Vec<Point2<f64>>> {
    pts.dedup_by(|a, b| (*a - *b).norm() == 0.0);
    let scale = pts
        .iter()
        .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()))
        .max(1e-300);
    if let (Some(f), Some(l)) = (pts.first().copied(), pts.last().copied()) {
        if pts.len() > 1 && (f - l).norm() <= 1e-9 * scale {
            pts.pop();
        } else if !closed_by_z {
            return Err(Error::content(
                path,
                format!(
                    "{what} is open: it ends at ({:.4}, {:.4}), not on its first point ({:.4}, {:.4}); close it (Z) to draw a region",
                    l.x, l.y, f.x, f.y
                ),
            ));
        }
    }
    if pts.len() < 3 {
        return Err(Error::content(
            path,
            format!("{what} has fewer than 3 distinct points"),
        ));
    }
    Ok(pts)
}

fn line_of(text: &str, offset: usize) -> Location {
    Location::Line(text[..offset.min(text.len())].matches('\n').count() + 1)
}

/// Attributes of one element tag `<name a="..." b='...'>`; `start` is the offset of `<`.
fn attributes(path: &Path, text: &str, start: usize) -> Result<(Vec<(String, String)>, usize)> {
    let bytes = text.as_bytes();
    let mut i = start + 1;
    while i < bytes.len() && !bytes[i].is_ascii_whitespace() && bytes[i] != b'>' && bytes[i] != b'/'
    {
        i += 1;
    }
    let mut attrs = Vec::new();
    loop {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= bytes.len() {
            return Err(Error::syntax(
                path,
                line_of(text, start),
                "element not terminated by '>'",
            ));
        }
        if bytes[i] == b'>' {
            return Ok((attrs, i + 1));
        }
        if bytes[i] == b'/' {
            i += 1;
            continue;
        }
        let ns = i;
        while i < bytes.len()
            && bytes[i] != b'='
            && !bytes[i].is_ascii_whitespace()
            && bytes[i] != b'>'
        {
            i += 1;
        }
        let name = text[ns..i].to_string();
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= bytes.len() || bytes[i] != b'=' {
            return Err(Error::syntax(
                path,
                line_of(text, i),
                format!("attribute '{name}' has no value"),
            ));
        }
        i += 1;
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let q = bytes.get(i).copied().unwrap_or(0);
        if q != b'"' && q != b'\'' {
            return Err(Error::syntax(
                path,
                line_of(text, i),
                format!("value of attribute '{name}' is not quoted"),
            ));
        }
        let vs = i + 1;
        let Some(len) = text[vs..].find(q as char) else {
            return Err(Error::syntax(
                path,
                line_of(text, i),
                format!("value of attribute '{name}' has no closing quote"),
            ));
        };
        attrs.push((name, text[vs..vs + len].to_string()));
        i = vs + len + 1;
    }
}

fn parse_svg(path: &Path, text: &str) -> Result<Drawing> {
    if !text.contains("<svg") {
        return Err(Error::syntax(
            path,
            Location::Line(1),
            "not an SVG document (no <svg> element) and not a JSON drawing",
        ));
    }
    if !text.contains("</svg>") {
        return Err(Error::syntax(
            path,
            line_of(text, text.len()),
            "the <svg> element is not closed (no </svg>)",
        ));
    }
    let mut d = Drawing::default();
    let mut overs: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
    let mut pos = 0;
    while let Some(k) = text[pos..].find('<') {
        let start = pos + k;
        let rest = &text[start + 1..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == ':' || *c == '-')
            .collect();
        if rest.starts_with("!--") {
            pos = match rest.find("-->") {
                Some(e) => start + 1 + e + 3,
                None => {
                    return Err(Error::syntax(
                        path,
                        line_of(text, start),
                        "comment not closed",
                    ))
                }
            };
            continue;
        }
        if name.is_empty() {
            pos = start + 1;
            continue;
        }
        let (attrs, end) = attributes(path, text, start)?;
        pos = end;
        let get = |n: &str| attrs.iter().find(|(a, _)| a == n).map(|(_, v)| v.as_str());
        if matches!(name.as_str(), "path" | "polygon" | "polyline" | "g")
            && get("transform").is_some()
        {
            return Err(Error::unsupported(
                path,
                format!(
                    "{}: transform attributes are not supported; flatten the drawing first",
                    match line_of(text, start) {
                        Location::Line(l) => format!("line {l}"),
                        Location::Byte(b) => format!("byte {b}"),
                    }
                ),
            ));
        }
        let first = d.contours.len();
        match name.as_str() {
            "path" => {
                let dattr = get("d").ok_or_else(|| {
                    Error::syntax(path, line_of(text, start), "<path> without a d attribute")
                })?;
                let subs = parse_path_data(path, dattr, line_of(text, start))?;
                let what = format!("<path> at {}", line_of(text, start));
                for (i, (pts, z)) in subs.into_iter().enumerate() {
                    add_polyline(&mut d, path, pts, &format!("subpath {i} of {what}"), z)?;
                }
            }
            "polygon" | "polyline" => {
                let p = get("points").ok_or_else(|| {
                    Error::syntax(
                        path,
                        line_of(text, start),
                        format!("<{name}> without a points attribute"),
                    )
                })?;
                let nums = numbers(path, p, line_of(text, start))?;
                if nums.len() % 2 != 0 {
                    return Err(Error::syntax(
                        path,
                        line_of(text, start),
                        format!("<{name}> points has an odd count of numbers"),
                    ));
                }
                let pts: Vec<Point2<f64>> =
                    nums.chunks(2).map(|c| Point2::new(c[0], -c[1])).collect();
                let what = format!("<{name}> at {}", line_of(text, start));
                add_polyline(&mut d, path, pts, &what, name == "polygon")?;
            }
            _ => {}
        }
        if let Some(o) = get("data-over") {
            let backs = numbers(path, o, line_of(text, start))?
                .into_iter()
                .map(|x| x.max(0.0) as usize)
                .collect();
            overs.push(((first..d.contours.len()).collect(), backs));
        }
    }
    for (fronts, backs) in overs {
        for &f in &fronts {
            for &b in &backs {
                d.over.push((f, b));
            }
        }
    }
    Ok(d)
}

/// Numbers in an SVG list ("1,2 3-4 .5.5 1e-3").
fn numbers(path: &Path, s: &str, loc: Location) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    let mut lex = Lexer {
        s: s.as_bytes(),
        i: 0,
    };
    loop {
        lex.skip_sep();
        if lex.i >= lex.s.len() {
            return Ok(out);
        }
        match lex.number() {
            Some(x) => out.push(x),
            None => {
                return Err(Error::syntax(
                    path,
                    loc,
                    format!("bad number in '{}'", truncate(s)),
                ))
            }
        }
    }
}

fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
}

struct Lexer<'a> {
    s: &'a [u8],
    i: usize,
}

impl Lexer<'_> {
    fn skip_sep(&mut self) {
        while self.i < self.s.len()
            && (self.s[self.i].is_ascii_whitespace() || self.s[self.i] == b',')
        {
            self.i += 1;
        }
    }
    fn number(&mut self) -> Option<f64> {
        let st = self.i;
        let s = self.s;
        let mut i = self.i;
        if i < s.len() && (s[i] == b'+' || s[i] == b'-') {
            i += 1;
        }
        let mut digits = 0;
        while i < s.len() && s[i].is_ascii_digit() {
            i += 1;
            digits += 1;
        }
        if i < s.len() && s[i] == b'.' {
            i += 1;
            while i < s.len() && s[i].is_ascii_digit() {
                i += 1;
                digits += 1;
            }
        }
        if digits == 0 {
            return None;
        }
        if i < s.len() && (s[i] == b'e' || s[i] == b'E') {
            let mut j = i + 1;
            if j < s.len() && (s[j] == b'+' || s[j] == b'-') {
                j += 1;
            }
            if j < s.len() && s[j].is_ascii_digit() {
                while j < s.len() && s[j].is_ascii_digit() {
                    j += 1;
                }
                i = j;
            }
        }
        let v = std::str::from_utf8(&s[st..i]).ok()?.parse().ok()?;
        self.i = i;
        Some(v)
    }
}

/// Parses SVG path data into subpaths (points with y flipped, closed-by-Z flag).
fn parse_path_data(path: &Path, d: &str, loc: Location) -> Result<Vec<(Vec<Point2<f64>>, bool)>> {
    let err = |m: String| Error::syntax(path, loc, m);
    let mut lex = Lexer {
        s: d.as_bytes(),
        i: 0,
    };
    let mut subs: Vec<(Vec<Point2<f64>>, bool)> = Vec::new();
    let mut cur: Vec<Point2<f64>> = Vec::new();
    let mut closed = false;
    let mut p = Point2::new(0.0, 0.0);
    let mut start = p;
    let mut cmd: u8 = 0;
    // Points in SVG coordinates (y down) until the end.
    loop {
        lex.skip_sep();
        if lex.i >= lex.s.len() {
            break;
        }
        let c = lex.s[lex.i];
        if c.is_ascii_alphabetic() {
            cmd = c;
            lex.i += 1;
            if cmd == b'Z' || cmd == b'z' {
                closed = true;
                p = start;
                if !cur.is_empty() {
                    subs.push((std::mem::take(&mut cur), true));
                }
                continue;
            }
        } else if cmd == 0 {
            return Err(err(format!(
                "path data does not start with a command: '{}'",
                truncate(d)
            )));
        }
        let rel = cmd.is_ascii_lowercase();
        let base = if rel {
            p.coords
        } else {
            nalgebra::Vector2::zeros()
        };
        let num = |lex: &mut Lexer| -> Result<f64> {
            lex.skip_sep();
            lex.number().ok_or_else(|| {
                err(format!(
                    "command '{}' is missing a number in '{}'",
                    cmd as char,
                    truncate(d)
                ))
            })
        };
        match cmd.to_ascii_uppercase() {
            b'M' => {
                let q = Point2::new(num(&mut lex)?, num(&mut lex)?) + base;
                if !cur.is_empty() {
                    subs.push((std::mem::take(&mut cur), closed));
                }
                cur.push(q);
                p = q;
                start = q;
                cmd = if rel { b'l' } else { b'L' };
            }
            b'L' => {
                let q = Point2::new(num(&mut lex)?, num(&mut lex)?) + base;
                if cur.is_empty() {
                    cur.push(p);
                }
                cur.push(q);
                p = q;
            }
            b'H' => {
                let x = num(&mut lex)? + base.x;
                if cur.is_empty() {
                    cur.push(p);
                }
                p = Point2::new(x, p.y);
                cur.push(p);
            }
            b'V' => {
                let y = num(&mut lex)? + base.y;
                if cur.is_empty() {
                    cur.push(p);
                }
                p = Point2::new(p.x, y);
                cur.push(p);
            }
            b'C' => {
                let c1 = Point2::new(num(&mut lex)?, num(&mut lex)?) + base;
                let c2 = Point2::new(num(&mut lex)?, num(&mut lex)?) + base;
                let q = Point2::new(num(&mut lex)?, num(&mut lex)?) + base;
                if cur.is_empty() {
                    cur.push(p);
                }
                for k in 1..=16 {
                    let t = k as f64 / 16.0;
                    let u = 1.0 - t;
                    let b = p.coords * (u * u * u)
                        + c1.coords * (3.0 * u * u * t)
                        + c2.coords * (3.0 * u * t * t)
                        + q.coords * (t * t * t);
                    cur.push(Point2::from(b));
                }
                p = q;
            }
            other => {
                return Err(Error::unsupported(
                    path,
                    format!(
                        "{loc}: path command '{}' is not supported (use M, L, H, V, C, Z)",
                        other as char
                    ),
                ))
            }
        }
        closed = false;
    }
    if !cur.is_empty() {
        subs.push((cur, closed));
    }
    Ok(subs
        .into_iter()
        .map(|(pts, z)| (pts.into_iter().map(|q| Point2::new(q.x, -q.y)).collect(), z))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn svg(body: &str) -> Result<Drawing> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("d.svg");
        std::fs::write(
            &p,
            format!("<svg xmlns=\"http://www.w3.org/2000/svg\">\n{body}\n</svg>\n"),
        )
        .unwrap();
        read_drawing(&p)
    }

    #[test]
    fn relative_and_absolute_commands_give_the_same_square() {
        let a = svg(r#"<path d="M0,0 L10,0 L10,10 L0,10 Z"/>"#).unwrap();
        let b = svg(r#"<path d="m0 0 h10 v10 h-10 z"/>"#).unwrap();
        assert_eq!(a.contours.len(), 1);
        assert_eq!(a.contours[0].len(), 4);
        for (p, q) in a.contours[0].iter().zip(&b.contours[0]) {
            assert!((p - q).norm() < 1e-12);
        }
        assert_eq!(a.contours[0][2], Point2::new(10.0, -10.0));
    }

    #[test]
    fn cubic_is_flattened_and_polygon_read() {
        let d = svg(r#"<path d="M0 0 C 0 -10 10 -10 10 0 z"/><polygon points="20,0 30,0 25,5" data-over="0"/>"#)
            .unwrap();
        assert_eq!(d.contours.len(), 2);
        assert_eq!(d.contours[0].len(), 17);
        assert_eq!(d.over, vec![(1, 0)]);
    }

    #[test]
    fn open_stroke_ending_on_a_contour_is_a_t_junction_stroke() {
        let d = svg(r#"<path d="M0 0 L10 0 L10 10 L0 10 Z"/><polyline points="5,0 5,-20 15,-20 15,5 10,5"/>"#)
            .unwrap();
        assert_eq!(d.contours.len(), 1);
        assert_eq!(d.strokes.len(), 1);
        assert_eq!(d.strokes[0].len(), 5);
        // An open stroke with a free end is still an error.
        let e =
            svg(r#"<path d="M0 0 L10 0 L10 10 L0 10 Z"/><polyline points="5,0 5,-20 15,-20"/>"#)
                .unwrap_err();
        assert!(e.to_string().contains("open"), "{e}");
    }

    #[test]
    fn open_and_malformed_inputs_are_errors() {
        let e = svg(r#"<path d="M0 0 L10 0 L10 10"/>"#).unwrap_err();
        assert!(e.to_string().contains("open"), "{e}");
        let e = svg(r#"<path d="M0 0 L10 0 L10"/>"#).unwrap_err();
        assert!(e.to_string().contains("missing a number"), "{e}");
        let e = svg(r#"<path d="M0 0 A 1 1 0 0 0 5 5 Z"/>"#).unwrap_err();
        assert!(e.to_string().contains("not supported"), "{e}");
        let e = svg(r#"<path d="M0 0 L1 0 L0 1 Z"#).unwrap_err();
        assert!(e.to_string().contains("quote"), "{e}");
    }
}
