//! IGES 5.3 writer: one rational B-spline surface entity (type 128, written as polynomial:
//! PROP3 = 1, all weights 1) per patch, untrimmed; a patch small enough to get an apron in
//! STEP ([`super::apron`]) is the same trimmed region of the same extended surface here:
//!
//! - 128, the extended surface (physically dependent);
//! - 126, the rectangle of the patch's own domain in the parameter plane (a closed planar
//!   degree-1 B-spline, entity use 05: 2D parametric);
//! - 142, curve on a parametric surface: that surface, that parameter curve, no model-space
//!   curve, the parameter curve preferred;
//! - 144, trimmed parametric surface: the surface, outer boundary the 142, no holes.
//!
//! Why: OpenCASCADE's point projection, which IGES readers built on it use to find a face's
//! normal at a point, fails on untrimmed surfaces this small (the bunny: cad_check's normal jump
//! p95 read 9.6 degrees on the IGES file against 0.26 on the STEP with aprons).
//!
//! File structure (fixed 80-column ASCII records, columns 73-80 = section letter + 7-digit
//! sequence number):
//!
//! - Start (S): free text.
//! - Global (G): parameter/record delimiters, Hollerith strings (`nH...`) for names and dates,
//!   integer/real precision, model space scale, unit flag and name, date, minimum resolution,
//!   maximum coordinate, author, organisation, version flag 11 (= IGES 5.3).
//! - Directory entry (D): two records per entity, nine 8-column fields each: type, pointer to
//!   the first parameter record, ..., status `00000000` (visible, independent, geometry);
//!   second record: type, line weight, colour, parameter record count, form 0, label, subscript.
//! - Parameter data (P): columns 1-64 data, 66-72 the back-pointer to the entity's first D
//!   record.
//! - Terminate (T): the record counts of S, G, D and P.
//!
//! Entity 128 parameters: `128, K1, K2, M1, M2, PROP1..5, knots u (K1+M1+2), knots v, weights
//! W(i,j), control points X,Y,Z (i along u varying fastest), U0, U1, V0, V1;`.
//!
//! IGES has no face orientation for an untrimmed surface, so a patch whose `S_u × S_v` points
//! inward (`same_sense == false`) is written with its u direction reversed: every surface in
//! the file then has its natural normal pointing out of the solid.

use super::{fmt_real, software, ExportOptions};
use crate::nurbs::{BSplineSurface, PatchNetwork};
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Writes the network as an IGES file to `out` (validating it first). I/O errors are reported
/// with `opts.name` as the path.
pub fn write_iges<W: Write>(net: &PatchNetwork, opts: &ExportOptions, out: &mut W) -> Result<()> {
    let text = iges_string(net, opts)?;
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| Error::io(Path::new(&opts.name), e))
}

/// The IGES file's text.
pub fn iges_string(net: &PatchNetwork, opts: &ExportOptions) -> Result<String> {
    opts.check()?;
    net.validate()?;
    let mut out = String::new();

    // Start section.
    let start = format!(
        "scansurf: {} bicubic B-spline patches (IGES entity 128; small ones trimmed, 144)",
        net.faces.len()
    );
    let n_s = push_records(&mut out, &[ascii(&start)], 72, 'S', None);

    // Global section.
    let max_coord = net
        .faces
        .iter()
        .flat_map(|f| f.surface.ctrl.iter().flatten())
        .chain(net.vertices.iter())
        .flat_map(|p| p.coords.iter().map(|c| c.abs()).collect::<Vec<_>>())
        .fold(0.0, f64::max);
    let (unit_flag, unit_name) = opts.unit.iges_flag_and_name();
    let date = opts.time().iges();
    let sw = software();
    let global = [
        hollerith(","),
        hollerith(";"),
        hollerith(&opts.name),
        hollerith(&opts.name),
        hollerith(&sw),
        hollerith(&sw),
        "32".into(),
        "38".into(),
        "6".into(),
        "308".into(),
        "15".into(),
        hollerith(&opts.name),
        fmt_real(1.0),
        unit_flag.to_string(),
        hollerith(unit_name),
        "1".into(),
        fmt_real(1.0),
        hollerith(&date),
        fmt_real(opts.tolerance),
        fmt_real(max_coord),
        hollerith(&opts.author),
        hollerith(&opts.organization),
        "11".into(),
        "0".into(),
        hollerith(&date),
    ];
    let n_g = push_records(&mut out, &params(&global), 72, 'G', None);

    // Entities in file order; a face on an extended surface is four of them.
    let mut entities: Vec<Entity> = Vec::new();
    for (k, f) in net.faces.iter().enumerate() {
        let surface = if f.same_sense {
            f.surface.clone()
        } else {
            reverse_u(&f.surface)
        };
        let subscript = k + 1;
        let Some(extended) = opts.extended_surface(&surface) else {
            entities.push(Entity::new(
                128,
                entity_128(&surface),
                INDEPENDENT,
                subscript,
            ));
            continue;
        };
        // DE numbers of the four entities about to be pushed (two records each).
        let de = |offset: usize| 2 * (entities.len() + offset) + 1;
        let (de_surface, de_pcurve, de_boundary) = (de(0), de(1), de(2));
        let (u0, u1) = surface.domain_u();
        let (v0, v1) = surface.domain_v();
        entities.push(Entity::new(
            128,
            entity_128(&extended),
            DEPENDENT,
            subscript,
        ));
        entities.push(Entity::new(
            126,
            rectangle_126([u0, u1, v0, v1]),
            DEPENDENT_PARAMETRIC,
            subscript,
        ));
        // 142: created unspecified (0), surface, parameter curve, no model-space curve,
        // the parameter curve preferred (1).
        let b = [142, 0, de_surface, de_pcurve, 0, 1].map(|v| v.to_string());
        entities.push(Entity::new(142, b.to_vec(), DEPENDENT, subscript));
        // 144: surface, outer boundary given (1), no inner boundaries, the boundary.
        let t = [144, de_surface, 1, 0, de_boundary].map(|v| v.to_string());
        entities.push(Entity::new(144, t.to_vec(), INDEPENDENT, subscript));
    }

    // Parameter data first (to know pointers and record counts), then D and P in file order.
    let mut p_text = String::new();
    let mut d_text = String::new();
    let mut p_line = 1usize;
    for (k, e) in entities.iter().enumerate() {
        let de = 2 * k + 1;
        let n = push_records(&mut p_text, &params(&e.params), 64, 'P', Some((de, p_line)));
        let kind = e.kind.to_string();
        let fields1 = [
            kind.clone(),
            p_line.to_string(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            e.status.into(),
        ];
        let fields2 = [
            kind,
            "0".into(),
            "0".into(),
            n.to_string(),
            "0".into(),
            String::new(),
            String::new(),
            e.label().into(),
            e.subscript.to_string(),
        ];
        for (r, fields) in [fields1, fields2].iter().enumerate() {
            for fld in fields {
                d_text.push_str(&format!("{fld:>8}"));
            }
            d_text.push_str(&format!("D{:07}\n", de + r));
        }
        p_line += n;
    }
    let n_d = 2 * entities.len();
    let n_p = p_line - 1;
    out.push_str(&d_text);
    out.push_str(&p_text);
    let term = format!("S{n_s:07}G{n_g:07}D{n_d:07}P{n_p:07}");
    out.push_str(&format!("{term:<72}T0000001\n"));
    Ok(out)
}

/// Status numbers (DE field 9): blank status, subordinate switch, entity use, hierarchy.
/// Visible, independent geometry.
const INDEPENDENT: &str = "00000000";
/// Visible, physically dependent (referenced by a trimmed surface) geometry.
const DEPENDENT: &str = "00010000";
/// Visible, physically dependent, 2D parametric (a curve in a surface's parameter plane).
const DEPENDENT_PARAMETRIC: &str = "00010500";

/// One entity: its type, parameter data (without the delimiters), DE status and subscript
/// (the patch number, 1-based).
struct Entity {
    kind: u32,
    params: Vec<String>,
    status: &'static str,
    subscript: usize,
}

impl Entity {
    fn new(kind: u32, params: Vec<String>, status: &'static str, subscript: usize) -> Entity {
        Entity {
            kind,
            params,
            status,
            subscript,
        }
    }

    /// DE entity label (8 characters at most).
    fn label(&self) -> &'static str {
        match self.kind {
            126 => "BOUNDUV",
            142 => "BOUNDARY",
            _ => "PATCH",
        }
    }
}

/// Parameters of entity 126 for the closed rectangle `[u0, u1, v0, v1]` of a parameter plane,
/// counter-clockwise from (u0, v0): a planar, closed, polynomial B-spline of degree 1 with five
/// control points (u, v, 0), parameter 0..4, normal +z.
fn rectangle_126([u0, u1, v0, v1]: [f64; 4]) -> Vec<String> {
    let mut p: Vec<String> = [126, 4, 1, 1, 1, 1, 0]
        .iter()
        .map(|v| v.to_string())
        .collect();
    p.extend([0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 4.0].map(fmt_real));
    p.extend(std::iter::repeat_n(fmt_real(1.0), 5));
    for (u, v) in [(u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0)] {
        p.extend([u, v, 0.0].map(fmt_real));
    }
    p.extend([0.0, 4.0, 0.0, 0.0, 1.0].map(fmt_real));
    p
}

/// Parameters of entity 128 for a polynomial surface.
fn entity_128(s: &BSplineSurface) -> Vec<String> {
    let (nu, nv) = s.ctrl_dims();
    let mut p: Vec<String> = [
        128,
        nu - 1,
        nv - 1,
        s.degree_u,
        s.degree_v,
        0, // PROP1: not closed in u
        0, // PROP2: not closed in v
        1, // PROP3: polynomial
        0, // PROP4: not periodic in u
        0, // PROP5: not periodic in v
    ]
    .iter()
    .map(|v| v.to_string())
    .collect();
    p.extend(s.knots_u.iter().map(|&k| fmt_real(k)));
    p.extend(s.knots_v.iter().map(|&k| fmt_real(k)));
    p.extend(std::iter::repeat_n(fmt_real(1.0), nu * nv));
    for j in 0..nv {
        for row in &s.ctrl {
            let c = row[j];
            p.extend([fmt_real(c.x), fmt_real(c.y), fmt_real(c.z)]);
        }
    }
    let (u0, u1) = s.domain_u();
    let (v0, v1) = s.domain_v();
    p.extend([u0, u1, v0, v1].map(fmt_real));
    p
}

/// The surface with its u direction reversed (normal flipped, same point set).
fn reverse_u(s: &BSplineSurface) -> BSplineSurface {
    let (a, b) = s.domain_u();
    BSplineSurface {
        degree_u: s.degree_u,
        degree_v: s.degree_v,
        knots_u: s.knots_u.iter().rev().map(|k| (a + b) - k).collect(),
        knots_v: s.knots_v.clone(),
        ctrl: s.ctrl.iter().rev().cloned().collect(),
    }
}

/// Printable ASCII only (IGES is an ASCII format): other characters become '?'.
fn ascii(s: &str) -> String {
    s.chars()
        .map(|c| if (' '..='~').contains(&c) { c } else { '?' })
        .collect()
}

/// A Hollerith string `nH...`, empty (a defaulted parameter) for an empty string. Limited to
/// 60 characters so that a global parameter always fits one record.
fn hollerith(s: &str) -> String {
    let a: String = ascii(s).chars().take(60).collect();
    if a.is_empty() {
        String::new()
    } else {
        format!("{}H{a}", a.len())
    }
}

/// Parameters joined by ',' and terminated by ';', as separate tokens (each carrying its
/// delimiter) for record filling.
fn params(items: &[String]) -> Vec<String> {
    let n = items.len();
    items
        .iter()
        .enumerate()
        .map(|(k, s)| format!("{s}{}", if k + 1 == n { ';' } else { ',' }))
        .collect()
}

/// Fills records of `width` data columns with whole tokens, then the section letter and
/// sequence number (P records also carry the DE back-pointer in columns 66-72). Returns the
/// number of records written. `p_info` = (DE pointer, first sequence number) for P records.
fn push_records(
    out: &mut String,
    tokens: &[String],
    width: usize,
    section: char,
    p_info: Option<(usize, usize)>,
) -> usize {
    let first_seq = p_info.map_or(1, |(_, s)| s);
    let mut lines: Vec<String> = vec![String::new()];
    for t in tokens {
        // Start text longer than a record is split anywhere (it has no syntax).
        let mut t = t.as_str();
        while !t.is_empty() {
            let cur = lines.last_mut().map_or(0, |l| l.len());
            let room = width - cur;
            if t.len() <= room {
                if let Some(l) = lines.last_mut() {
                    l.push_str(t);
                }
                break;
            }
            if cur > 0 {
                lines.push(String::new());
                continue;
            }
            let (head, tail) = t.split_at(width);
            if let Some(l) = lines.last_mut() {
                l.push_str(head);
            }
            lines.push(String::new());
            t = tail;
        }
    }
    if lines.len() > 1 && lines.last().is_some_and(String::is_empty) {
        lines.pop();
    }
    for (k, l) in lines.iter().enumerate() {
        let seq = first_seq + k;
        match p_info {
            Some((de, _)) => out.push_str(&format!("{l:<64} {de:07}{section}{seq:07}\n")),
            None => out.push_str(&format!("{l:<72}{section}{seq:07}\n")),
        }
    }
    lines.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nurbs::network::two_patch_network;

    fn two_patches() -> PatchNetwork {
        two_patch_network(|x, _| 0.1 * x * x * 1e5)
    }

    /// The records of one section.
    fn section<'a>(lines: &[&'a str], letter: char) -> Vec<&'a str> {
        lines
            .iter()
            .copied()
            .filter(|l| l.as_bytes()[72] as char == letter)
            .collect()
    }

    #[test]
    fn records_are_80_columns_with_consistent_pointers() {
        let net = two_patches();
        assert_eq!(net.edges.len(), 7);
        let s = iges_string(&net, &ExportOptions::default()).unwrap();
        let lines: Vec<&str> = s.lines().collect();
        let mut counts = std::collections::HashMap::new();
        for l in &lines {
            assert_eq!(l.len(), 80, "{l:?}");
            let sec = l.as_bytes()[72] as char;
            let c = counts.entry(sec).or_insert(0usize);
            *c += 1;
            assert_eq!(l[73..].parse::<usize>().unwrap(), *c, "sequence in {l:?}");
        }
        let term = lines.last().unwrap();
        assert_eq!(
            &term[..32],
            format!(
                "S{:07}G{:07}D{:07}P{:07}",
                counts[&'S'], counts[&'G'], counts[&'D'], counts[&'P']
            )
        );
        assert_eq!(counts[&'D'], 4);
        // DE records point at their parameter data and P records point back.
        let (d, p) = (section(&lines, 'D'), section(&lines, 'P'));
        for e in 0..2 {
            let first: usize = d[2 * e][8..16].trim().parse().unwrap();
            let n: usize = d[2 * e + 1][24..32].trim().parse().unwrap();
            assert!(p[first - 1].starts_with("128,"));
            for l in &p[first - 1..first - 1 + n] {
                assert_eq!(l[65..72].parse::<usize>().unwrap(), 2 * e + 1);
            }
            assert!(p[first - 1 + n - 1][..64].trim_end().ends_with(';'));
        }
        // Parameter data: 10 header ints, 9 + 9 knots, 25 weights, 75 coordinates, 4 bounds.
        let data: String = p[..p.len() / 2]
            .iter()
            .map(|l| l[..64].trim_end())
            .collect();
        let toks: Vec<&str> = data.trim_end_matches(';').split(',').collect();
        assert_eq!(toks.len(), 10 + 18 + 25 + 75 + 4);
        // Global section: Hollerith counts and the version flag.
        let g: String = lines
            .iter()
            .filter(|l| &l[72..73] == "G")
            .map(|l| l[..72].trim_end())
            .collect();
        assert!(g.starts_with("1H,,1H;,8Hscansurf,8Hscansurf,"));
        assert!(g.contains(",2,2HMM,"));
        assert!(g.contains(",15H19700101.000000,"));
        assert!(g.contains(",11,0,15H19700101.000000;"));
        assert_eq!(s, iges_string(&net, &ExportOptions::default()).unwrap());
    }

    #[test]
    fn reversed_patches_are_flipped_in_u() {
        let mut net = two_patches();
        let before = net.faces[0].surface.clone();
        for f in &mut net.faces {
            f.same_sense = false;
        }
        let r = reverse_u(&before);
        let (a, b) = (0.3, 0.6);
        assert!((r.evaluate(1.0 - a, b) - before.evaluate(a, b)).norm() < 1e-12);
        let n0 = before.normal(a, b).unwrap();
        let n1 = r.normal(1.0 - a, b).unwrap();
        assert!((n0 + n1).norm() < 1e-12);
        assert!(iges_string(&net, &ExportOptions::default()).is_ok());
    }

    /// In micrometres the two unit patches are far under OpenCASCADE's projection grid, so each
    /// becomes a trimmed surface: 128 (extended), 126 (its domain), 142 and 144, pointing at
    /// each other; `--extend-surfaces never` writes the bare 128s.
    #[test]
    fn small_patches_are_trimmed_extended_surfaces() {
        let net = two_patches();
        let opts = ExportOptions {
            unit: crate::export::LengthUnit::Micrometre,
            ..ExportOptions::default()
        };
        let s = iges_string(&net, &opts).unwrap();
        let lines: Vec<&str> = s.lines().collect();
        let (d, p) = (section(&lines, 'D'), section(&lines, 'P'));
        let kinds: Vec<&str> = d.iter().step_by(2).map(|l| l[..8].trim()).collect();
        assert_eq!(
            kinds,
            ["128", "126", "142", "144", "128", "126", "142", "144"]
        );
        // The parameter data of the entity at DE record `de` (1-based), as tokens.
        let data = |de: usize| -> Vec<String> {
            p.iter()
                .filter(|l| l[65..72].parse::<usize>().unwrap() == de)
                .map(|l| l[..64].trim_end())
                .collect::<String>()
                .trim_end_matches(';')
                .split(',')
                .map(str::to_string)
                .collect()
        };
        for face in 0..2 {
            let de = 8 * face + 1;
            assert_eq!(&d[de - 1][64..72], "00010000");
            assert_eq!(&d[de + 1][64..72], "00010500");
            assert_eq!(&d[de + 5][64..72], "00000000");
            let bound = data(de + 4);
            assert_eq!(bound, [142, 0, de, de + 2, 0, 1].map(|v| v.to_string()));
            let trim = data(de + 6);
            assert_eq!(trim, [144, de, 1, 0, de + 4].map(|v| v.to_string()));
            // The rectangle is the patch's own domain, inside the extended surface's.
            let (u0, u1) = net.faces[face].surface.domain_u();
            let rect = data(de + 2);
            let uv: Vec<f64> = rect[19..34].iter().map(|t| t.parse().unwrap()).collect();
            assert_eq!((uv[0], uv[3]), (u0, u1));
            // The surface is the extended one: more control points than the patch's own.
            let surf = data(de);
            let count = |t: &[String]| {
                (t[1].parse::<usize>().unwrap() + 1) * (t[2].parse::<usize>().unwrap() + 1)
            };
            let own = entity_128(&net.faces[face].surface);
            assert!(count(&surf) > count(&own), "{} {}", surf[1], surf[2]);
        }
        let never = ExportOptions {
            extend_surfaces: crate::export::ExtendSurfaces::Never,
            ..opts
        };
        let s = iges_string(&net, &never).unwrap();
        assert_eq!(s.lines().filter(|l| &l[72..73] == "D").count(), 4);
    }

    #[test]
    fn hollerith_and_record_filling() {
        assert_eq!(hollerith("MM"), "2HMM");
        assert_eq!(hollerith(""), "");
        assert_eq!(hollerith("é"), "1H?");
        let mut out = String::new();
        let toks: Vec<String> = (0..40).map(|k| format!("{k}.5,")).collect();
        let n = push_records(&mut out, &toks, 64, 'P', Some((3, 10)));
        assert_eq!(out.lines().count(), n);
        for l in out.lines() {
            assert_eq!(l.len(), 80);
            assert_eq!(&l[64..73], " 0000003P");
        }
        assert!(out.lines().next().unwrap().ends_with("P0000010"));
    }
}
