//! IGES 5.3 writer: one rational B-spline surface entity (type 128, written as polynomial:
//! PROP3 = 1, all weights 1) per patch, untrimmed.
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
        "scansurf: {} bicubic B-spline patches (IGES entity 128)",
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

    // Parameter data first (to know pointers and record counts), then D and P in file order.
    let mut p_text = String::new();
    let mut d_text = String::new();
    let mut p_line = 1usize;
    for (k, f) in net.faces.iter().enumerate() {
        let de = 2 * k + 1;
        let surface = if f.same_sense {
            f.surface.clone()
        } else {
            reverse_u(&f.surface)
        };
        let n = push_records(
            &mut p_text,
            &params(&entity_128(&surface)),
            64,
            'P',
            Some((de, p_line)),
        );
        let fields1 = [
            "128".to_string(),
            p_line.to_string(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "00000000".into(),
        ];
        let fields2 = [
            "128".to_string(),
            "0".into(),
            "0".into(),
            n.to_string(),
            "0".into(),
            String::new(),
            String::new(),
            "PATCH".into(),
            (k + 1).to_string(),
        ];
        for (r, fields) in [fields1, fields2].iter().enumerate() {
            for fld in fields {
                d_text.push_str(&format!("{fld:>8}"));
            }
            d_text.push_str(&format!("D{:07}\n", de + r));
        }
        p_line += n;
    }
    let n_d = 2 * net.faces.len();
    let n_p = p_line - 1;
    out.push_str(&d_text);
    out.push_str(&p_text);
    let term = format!("S{n_s:07}G{n_g:07}D{n_d:07}P{n_p:07}");
    out.push_str(&format!("{term:<72}T0000001\n"));
    Ok(out)
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
        let d: Vec<&str> = lines
            .iter()
            .copied()
            .filter(|l| &l[72..73] == "D")
            .collect();
        let p: Vec<&str> = lines
            .iter()
            .copied()
            .filter(|l| &l[72..73] == "P")
            .collect();
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
