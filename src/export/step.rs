//! STEP writer: ISO 10303-21 exchange file, AP214 (AUTOMOTIVE_DESIGN) schema.
//!
//! Layout (the entity names OpenCASCADE, FreeCAD and CATIA read as a B-rep):
//!
//! ```text
//! APPLICATION_PROTOCOL_DEFINITION -> APPLICATION_CONTEXT
//! SHAPE_DEFINITION_REPRESENTATION(PRODUCT_DEFINITION_SHAPE -> PRODUCT_DEFINITION -> PRODUCT,
//!                                 shape representation)
//! closed network: ADVANCED_BREP_SHAPE_REPRESENTATION(placement, MANIFOLD_SOLID_BREP(CLOSED_SHELL))
//! open network:   MANIFOLD_SURFACE_SHAPE_REPRESENTATION(placement,
//!                     SHELL_BASED_SURFACE_MODEL((OPEN_SHELL)))
//! shell faces:    ADVANCED_FACE((FACE_OUTER_BOUND(EDGE_LOOP((ORIENTED_EDGE x 4)))),
//!                               B_SPLINE_SURFACE_WITH_KNOTS, same_sense)
//! shared edges:   EDGE_CURVE(VERTEX_POINT, VERTEX_POINT,
//!                            SURFACE_CURVE(B_SPLINE_CURVE_WITH_KNOTS, (PCURVE x 2)), .T.)
//! pcurves:        PCURVE(face surface, DEFINITIONAL_REPRESENTATION((2D degree-1
//!                        B_SPLINE_CURVE_WITH_KNOTS), 2D parametric context))
//! context:        length unit (SI), radian, steradian, UNCERTAINTY_MEASURE_WITH_UNIT
//! ```
//!
//! Each network edge becomes one EDGE_CURVE referenced by the ORIENTED_EDGEs of both faces
//! that meet there, so a reader gets a sewn shell without a sewing tolerance. The face loop
//! runs counter-clockwise around `S_u × S_v` ([`Side::LOOP`](crate::nurbs::Side::LOOP)); when
//! that normal points inward (`same_sense == false`) the face and its bound are marked `.F.`.
//! Each edge carries its pcurve on both faces: the iso-line of the face's side, a straight
//! line in the face's parameter plane, parameterized like the 3D curve (the boundary curve
//! of a patch and its shared edge curve have the same knots). Pcurves are optional in
//! AP214, but a reader that has none projects the 3D curve onto the surface, and on the
//! extended surfaces below that projection can land on the apron (seen with OpenCASCADE: a
//! bunny face trimmed to [-0.66, 2.14] x [0, 1.54] instead of its unit square).
//!
//! Small patches (under about 0.03 mm, [`super::apron`]) are written on their surface
//! extended by a linear apron ([`crate::nurbs::extend`]): the face, bounded by the same shared
//! edge curves, is then a trimmed region of a larger B_SPLINE_SURFACE_WITH_KNOTS, which
//! OpenCASCADE's point projection handles where it fails on the bare patch.

use super::{fmt_real, push_real, software, ExportOptions};
use crate::nurbs::basis::multiplicities;
use crate::nurbs::{BSplineCurve, BSplineSurface, PatchNetwork};
use crate::{Error, Result};
use nalgebra::Point3;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// Writes the network as a STEP file to `out` (validating it first). I/O errors are reported
/// with `opts.name` as the path.
pub fn write_step<W: Write>(net: &PatchNetwork, opts: &ExportOptions, out: &mut W) -> Result<()> {
    let text = step_string(net, opts)?;
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| Error::io(Path::new(&opts.name), e))
}

/// The STEP file's text.
pub fn step_string(net: &PatchNetwork, opts: &ExportOptions) -> Result<String> {
    opts.check()?;
    net.validate()?;
    let mut w = Entities::default();

    // Product structure.
    let app_ctx =
        w.add("APPLICATION_CONTEXT('core data for automotive mechanical design processes')");
    w.add(format!(
        "APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{app_ctx})"
    ));
    let prod_ctx = w.add(format!("PRODUCT_CONTEXT('',#{app_ctx},'mechanical')"));
    let name = step_string_literal(&opts.name);
    let product = w.add(format!("PRODUCT({name},{name},'',(#{prod_ctx}))"));
    w.add(format!(
        "PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#{product}))"
    ));
    let formation = w.add(format!("PRODUCT_DEFINITION_FORMATION('','',#{product})"));
    let pd_ctx = w.add(format!(
        "PRODUCT_DEFINITION_CONTEXT('part definition',#{app_ctx},'design')"
    ));
    let pd = w.add(format!(
        "PRODUCT_DEFINITION('design','',#{formation},#{pd_ctx})"
    ));
    let pds = w.add(format!("PRODUCT_DEFINITION_SHAPE('','',#{pd})"));
    let shape_rep = w.reserve();
    w.add(format!(
        "SHAPE_DEFINITION_REPRESENTATION(#{pds},#{shape_rep})"
    ));

    // Representation context: units and uncertainty.
    let length = w.add(format!(
        "( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT({},.METRE.) )",
        opts.unit.step_prefix()
    ));
    let angle = w.add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )");
    let solid = w.add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )");
    let uncertainty = w.add(format!(
        "UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{length},'distance_accuracy_value','confusion accuracy')",
        fmt_real(opts.tolerance)
    ));
    let ctx = w.add(format!(
        "( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{uncertainty})) GLOBAL_UNIT_ASSIGNED_CONTEXT((#{length},#{angle},#{solid})) REPRESENTATION_CONTEXT('Context #1','3D Context with UNIT and UNCERTAINTY') )"
    ));
    let origin = w.add("CARTESIAN_POINT('',(0.,0.,0.))");
    let z = w.add("DIRECTION('',(0.,0.,1.))");
    let x = w.add("DIRECTION('',(1.,0.,0.))");
    let placement = w.add(format!("AXIS2_PLACEMENT_3D('',#{origin},#{z},#{x})"));

    // Topology: vertices, shared edges, faces.
    let vertex_ids: Vec<usize> = net
        .vertices
        .iter()
        .map(|p| {
            let pt = w.add_point(p);
            w.add(format!("VERTEX_POINT('',#{pt})"))
        })
        .collect();
    // Surfaces first: the edges' pcurves refer to them.
    let surface_ids: Vec<usize> = net
        .faces
        .iter()
        .map(|f| {
            let extended = opts.extended_surface(&f.surface);
            write_surface(&mut w, extended.as_ref().unwrap_or(&f.surface))
        })
        .collect();
    // Per edge, the faces using it and at which loop position.
    let mut uses: Vec<Vec<(usize, usize, bool)>> = vec![Vec::new(); net.edges.len()];
    for (fi, f) in net.faces.iter().enumerate() {
        for (k, &(e, rev)) in f.edges.iter().enumerate() {
            uses[e as usize].push((fi, k, rev));
        }
    }
    let ctx2d = w.add(
        "( GEOMETRIC_REPRESENTATION_CONTEXT(2) PARAMETRIC_REPRESENTATION_CONTEXT() REPRESENTATION_CONTEXT('2D SPACE','') )",
    );
    let edge_ids: Vec<usize> = net
        .edges
        .iter()
        .enumerate()
        .map(|(ei, e)| {
            let curve = write_curve(&mut w, &e.curve);
            // The edge on each of its faces: the iso-line of the face's side, linear in the
            // edge curve's parameter (the same knots; module doc).
            let (t0, t1) = e.curve.domain();
            let pcurves: Vec<String> = uses[ei]
                .iter()
                .map(|&(fi, k, rev)| {
                    let (a, b) = (net.side_uv(fi, k, rev, 0.0), net.side_uv(fi, k, rev, 1.0));
                    let pa = w.add(format!("CARTESIAN_POINT('',({}))", reals([a.0, a.1])));
                    let pb = w.add(format!("CARTESIAN_POINT('',({}))", reals([b.0, b.1])));
                    let line = w.add(format!(
                        "B_SPLINE_CURVE_WITH_KNOTS('',1,(#{pa},#{pb}),.UNSPECIFIED.,.F.,.F.,(2,2),({}),.UNSPECIFIED.)",
                        reals([t0, t1])
                    ));
                    let rep = w.add(format!("DEFINITIONAL_REPRESENTATION('',(#{line}),#{ctx2d})"));
                    let pc = w.add(format!("PCURVE('',#{},#{rep})", surface_ids[fi]));
                    format!("#{pc}")
                })
                .collect();
            let geometry = w.add(format!(
                "SURFACE_CURVE('',#{curve},({}),.PCURVE_S1.)",
                pcurves.join(",")
            ));
            let (a, b) = (vertex_ids[e.v[0] as usize], vertex_ids[e.v[1] as usize]);
            w.add(format!("EDGE_CURVE('',#{a},#{b},#{geometry},.T.)"))
        })
        .collect();
    let face_ids: Vec<usize> = net
        .faces
        .iter()
        .zip(&surface_ids)
        .map(|(f, &surf)| {
            let oriented: Vec<String> = f
                .edges
                .iter()
                .map(|&(e, rev)| {
                    let id = w.add(format!(
                        "ORIENTED_EDGE('',*,*,#{},{})",
                        edge_ids[e as usize],
                        logical(!rev)
                    ));
                    format!("#{id}")
                })
                .collect();
            let lp = w.add(format!("EDGE_LOOP('',({}))", oriented.join(",")));
            let bound = w.add(format!(
                "FACE_OUTER_BOUND('',#{lp},{})",
                logical(f.same_sense)
            ));
            w.add(format!(
                "ADVANCED_FACE('',(#{bound}),#{surf},{})",
                logical(f.same_sense)
            ))
        })
        .collect();
    let faces = refs(&face_ids);
    if net.closed {
        let shell = w.add(format!("CLOSED_SHELL('',({faces}))"));
        let brep = w.add(format!("MANIFOLD_SOLID_BREP('',#{shell})"));
        w.set(
            shape_rep,
            format!("ADVANCED_BREP_SHAPE_REPRESENTATION({name},(#{placement},#{brep}),#{ctx})"),
        );
    } else {
        let shell = w.add(format!("OPEN_SHELL('',({faces}))"));
        let model = w.add(format!("SHELL_BASED_SURFACE_MODEL('',(#{shell}))"));
        w.set(
            shape_rep,
            format!("MANIFOLD_SURFACE_SHAPE_REPRESENTATION({name},(#{placement},#{model}),#{ctx})"),
        );
    }

    let time = opts.time().iso8601();
    let sw = step_string_literal(&software());
    let mut out = String::with_capacity(w.text.len() + 16 * w.len() + 1024);
    out.push_str("ISO-10303-21;\nHEADER;\n");
    out.push_str("FILE_DESCRIPTION(('scansurf B-spline patch network'),'2;1');\n");
    wrap_into(
        &mut out,
        &format!(
            "FILE_NAME({name},'{time}',({}),({}),{sw},{sw},{});",
            step_string_literal(&opts.author),
            step_string_literal(&opts.organization),
            step_string_literal(&opts.authorization),
        ),
    );
    out.push_str("FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n");
    let mut line = String::new();
    let mut num = itoa::Buffer::new();
    for id in 1..=w.len() {
        line.clear();
        line.push('#');
        line.push_str(num.format(id));
        line.push_str(" = ");
        line.push_str(w.body(id));
        line.push(';');
        wrap_into(&mut out, &line);
    }
    out.push_str("ENDSEC;\nEND-ISO-10303-21;\n");
    Ok(out)
}

/// Entity instances in order; ids are 1-based positions. The bodies are kept back to back in
/// one string (700,000 of them for a 1,500-patch network: one allocation each was a fifth of
/// the writer's time); a body reserved early and set late (the shape representation, which
/// names the shell written last) is kept aside.
#[derive(Default)]
struct Entities {
    text: String,
    /// End of body k in `text`.
    ends: Vec<usize>,
    /// Bodies set after [`Entities::reserve`]: (id, body).
    late: Vec<(usize, String)>,
}

impl Entities {
    fn add(&mut self, body: impl AsRef<str>) -> usize {
        self.text.push_str(body.as_ref());
        self.close()
    }
    /// `CARTESIAN_POINT('',(x,y,z))`, formatted in place.
    fn add_point(&mut self, p: &Point3<f64>) -> usize {
        self.text.push_str("CARTESIAN_POINT('',(");
        push_reals(&mut self.text, [p.x, p.y, p.z]);
        self.text.push_str("))");
        self.close()
    }
    /// Ends the body written last; its id.
    fn close(&mut self) -> usize {
        self.ends.push(self.text.len());
        self.ends.len()
    }
    fn reserve(&mut self) -> usize {
        self.add("")
    }
    fn set(&mut self, id: usize, body: String) {
        self.late.push((id, body));
    }
    fn len(&self) -> usize {
        self.ends.len()
    }
    /// The body of entity `id` (1-based).
    fn body(&self, id: usize) -> &str {
        if let Some((_, b)) = self.late.iter().rev().find(|(i, _)| *i == id) {
            return b;
        }
        let start = if id > 1 { self.ends[id - 2] } else { 0 };
        &self.text[start..self.ends[id - 1]]
    }
}

fn logical(b: bool) -> &'static str {
    if b {
        ".T."
    } else {
        ".F."
    }
}

fn refs(ids: &[usize]) -> String {
    let mut s = String::with_capacity(8 * ids.len());
    let mut num = itoa::Buffer::new();
    for (k, &id) in ids.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        s.push('#');
        s.push_str(num.format(id));
    }
    s
}

/// Appends the reals `xs` separated by commas.
fn push_reals(out: &mut String, xs: impl IntoIterator<Item = f64>) {
    for (k, x) in xs.into_iter().enumerate() {
        if k > 0 {
            out.push(',');
        }
        push_real(out, x);
    }
}

fn reals(xs: impl IntoIterator<Item = f64>) -> String {
    let mut s = String::new();
    push_reals(&mut s, xs);
    s
}

/// `(multiplicities),(distinct knots)` of a knot vector.
fn knot_lists(knots: &[f64]) -> (String, String) {
    let m = multiplicities(knots);
    let mults = m
        .iter()
        .map(|(_, k)| k.to_string())
        .collect::<Vec<_>>()
        .join(",");
    (mults, reals(m.iter().map(|(v, _)| *v)))
}

fn write_curve(w: &mut Entities, c: &BSplineCurve) -> usize {
    let pts: Vec<usize> = c.ctrl.iter().map(|p| w.add_point(p)).collect();
    let (mults, knots) = knot_lists(&c.knots);
    w.add(format!(
        "B_SPLINE_CURVE_WITH_KNOTS('',{},({}),.UNSPECIFIED.,.F.,.F.,({mults}),({knots}),.UNSPECIFIED.)",
        c.degree,
        refs(&pts)
    ))
}

fn write_surface(w: &mut Entities, s: &BSplineSurface) -> usize {
    let rows: Vec<String> = s
        .ctrl
        .iter()
        .map(|row| {
            let ids: Vec<usize> = row.iter().map(|p| w.add_point(p)).collect();
            format!("({})", refs(&ids))
        })
        .collect();
    let (mu, ku) = knot_lists(&s.knots_u);
    let (mv, kv) = knot_lists(&s.knots_v);
    w.add(format!(
        "B_SPLINE_SURFACE_WITH_KNOTS('',{},{},({}),.UNSPECIFIED.,.F.,.F.,.F.,({mu}),({mv}),({ku}),({kv}),.UNSPECIFIED.)",
        s.degree_u,
        s.degree_v,
        rows.join(",")
    ))
}

/// A STEP string literal (ISO 10303-21 §6.4.3): apostrophes and backslashes doubled, printable
/// ASCII kept, every other character as a `\X2\...\X0\` (UCS-2) or `\X4\...\X0\` (UCS-4) hex
/// escape.
fn step_string_literal(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('\'');
    for ch in s.chars() {
        match ch {
            '\'' => out.push_str("''"),
            '\\' => out.push_str("\\\\"),
            ' '..='~' => out.push(ch),
            c if (c as u32) <= 0xFFFF => {
                let _ = write!(out, "\\X2\\{:04X}\\X0\\", c as u32);
            }
            c => {
                let _ = write!(out, "\\X4\\{:08X}\\X0\\", c as u32);
            }
        }
    }
    out.push('\'');
    out
}

/// Appends `line` and a newline, breaking it after commas (outside string literals) so lines
/// stay near 80 columns: Part 21 ignores line breaks between tokens, and short lines keep the
/// file friendly to line-oriented tools and older readers.
fn wrap_into(out: &mut String, line: &str) {
    const WIDTH: usize = 76;
    // Byte-wise (every break follows an ASCII comma, so slices stay on char boundaries);
    // columns count chars, i.e. bytes that do not continue a UTF-8 sequence.
    let mut col = 0;
    let mut in_str = false;
    let mut start = 0;
    for (i, &b) in line.as_bytes().iter().enumerate() {
        if b & 0xC0 != 0x80 {
            col += 1;
        }
        if b == b'\'' {
            in_str = !in_str;
        } else if b == b',' && !in_str && col >= WIDTH {
            out.push_str(&line[start..=i]);
            out.push_str("\n  ");
            col = 2;
            start = i + 1;
        }
    }
    out.push_str(&line[start..]);
    out.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{LengthUnit, Timestamp};
    use crate::nurbs::network::PatchInput;
    use crate::nurbs::Params;

    fn flat_patch() -> PatchNetwork {
        let k = Params::uniform(2).unwrap().cubic_knots();
        let ctrl = (0..5)
            .map(|i| {
                (0..5)
                    .map(|j| Point3::new(i as f64 * 0.25, j as f64 * 0.25, 0.1 * (i * j) as f64))
                    .collect()
            })
            .collect();
        let s = BSplineSurface::new(3, 3, k.clone(), k, ctrl).unwrap();
        let v = vec![
            s.evaluate(0.0, 0.0),
            s.evaluate(1.0, 0.0),
            s.evaluate(1.0, 1.0),
            s.evaluate(0.0, 1.0),
        ];
        PatchNetwork::from_patches(
            v,
            vec![PatchInput {
                surface: s,
                corners: [0, 1, 2, 3],
                same_sense: true,
            }],
        )
        .unwrap()
    }

    #[test]
    fn open_patch_layout() {
        let net = flat_patch();
        let opts = ExportOptions {
            name: "o'neil \\ patch é".into(),
            timestamp: Some(Timestamp::from_unix_seconds(1_700_000_000)),
            unit: LengthUnit::Metre,
            ..Default::default()
        };
        let s = step_string(&net, &opts).unwrap();
        assert!(s.starts_with("ISO-10303-21;\nHEADER;\n"));
        assert!(s.ends_with("ENDSEC;\nEND-ISO-10303-21;\n"));
        assert!(s.contains("'o''neil \\\\ patch \\X2\\00E9\\X0\\'"));
        assert!(s.contains("'2023-11-14T22:13:20'"));
        assert!(s.contains("SI_UNIT($,.METRE.)"));
        let count = |pat: &str| s.matches(pat).count();
        assert_eq!(count("ADVANCED_FACE("), 1);
        assert_eq!(count("EDGE_CURVE("), 4);
        assert_eq!(count("ORIENTED_EDGE("), 4);
        assert_eq!(count("VERTEX_POINT("), 4);
        assert_eq!(count("OPEN_SHELL("), 1);
        assert_eq!(count("CLOSED_SHELL("), 0);
        assert_eq!(count("MANIFOLD_SURFACE_SHAPE_REPRESENTATION("), 1);
        // 25 surface + 4 x 5 curve + 4 vertex + 1 origin control points, and the two 2D
        // points of each edge's pcurve on the face.
        assert_eq!(count("CARTESIAN_POINT("), 25 + 20 + 4 + 1 + 8);
        assert_eq!(count("SURFACE_CURVE("), 4);
        assert_eq!(count("PCURVE("), 4);
        assert!(s.contains("(4,1,4),(4,1,4),(0.,0.5,1.),(0.,0.5,1.)"));
        // Every referenced id exists exactly once.
        let defined = count("\n#");
        let max_ref = s
            .split('#')
            .skip(1)
            .filter_map(|t| {
                t.split(|c: char| !c.is_ascii_digit())
                    .next()
                    .and_then(|d| d.parse::<usize>().ok())
            })
            .max()
            .unwrap();
        assert_eq!(max_ref, defined);
        // Deterministic.
        assert_eq!(s, step_string(&net, &opts).unwrap());
    }

    #[test]
    fn invalid_inputs_are_errors() {
        let net = flat_patch();
        let bad_tol = ExportOptions {
            tolerance: 0.0,
            ..Default::default()
        };
        assert!(step_string(&net, &bad_tol).is_err());
        let mut broken = net.clone();
        broken.faces[0].surface.ctrl[2][2].x = f64::NAN;
        assert!(step_string(&broken, &ExportOptions::default()).is_err());
        let empty = PatchNetwork::default();
        assert!(step_string(&empty, &ExportOptions::default()).is_err());
    }

    #[test]
    fn wrapping_keeps_strings_whole() {
        let mut out = String::new();
        let long = format!("X('{}',{})", "a,".repeat(60), "1.,".repeat(40));
        wrap_into(&mut out, &long);
        assert!(out.lines().next().unwrap().contains(&"a,".repeat(60)));
        assert_eq!(out.replace("\n  ", ""), format!("{long}\n"));
    }
}
