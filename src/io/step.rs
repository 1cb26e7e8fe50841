//! STEP reader (ISO 10303-21 exchange structure) for B-spline patch models: enough of Part 21
//! to read the files scansurf's own writer ([`crate::export::step`]) produces, and the same
//! entity forms written by other CAD systems.
//!
//! Two layers:
//! 1. [`parse`]: the exchange structure itself. A lexer for Part 21 tokens (entity names,
//!    `#n` instance names, integers and reals with exponents, `'strings'` with doubled
//!    apostrophes, enumerations `.T.`, `$` unset, `*` derived, `/* comments */`) and a
//!    recursive parser for `#n = NAME(args);` simple instances and
//!    `#n = ( A(args) B(args) ... );` complex instances. Malformed files give
//!    [`Error::Syntax`] with the line number.
//! 2. [`read_step`] / [`StepFile::faces`]: every ADVANCED_FACE resolved to a
//!    [`BSplineSurface`] (B_SPLINE_SURFACE_WITH_KNOTS, or the complex-entity form
//!    `( BOUNDED_SURFACE() B_SPLINE_SURFACE(...) B_SPLINE_SURFACE_WITH_KNOTS(...) ... )`,
//!    rational only with unit weights) and its sense. A face must be bounded by a parameter
//!    rectangle of its surface (one loop whose edge ends lie at the corners of a rectangle
//!    [u_a, u_b] x [v_a, v_b] and whose edge curves run along its sides: the whole domain, or
//!    a sub-rectangle as scansurf writes for small patches, whose surface is then restricted
//!    to it); anything else (trimmed faces with other bounds, holes, analytic surfaces such
//!    as PLANE or CYLINDRICAL_SURFACE, rational weights) is an [`Error::Unsupported`] that
//!    names the entity and the line.
//!
//! Hand-written: no crate of the Rust ecosystem parses Part 21 and resolves B-rep faces into
//! our surface type without pulling in a whole CAD kernel; the subset needed is small.

use crate::error::{Error, Location, Result};
use crate::nurbs::basis::multiplicities;
use crate::nurbs::BSplineSurface;
use nalgebra::Point3;
use std::collections::HashMap;
use std::path::Path;

/// A parameter value of an entity instance.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// `#n`: reference to an instance.
    Ref(usize),
    Int(i64),
    Real(f64),
    Str(String),
    /// `.NAME.` (booleans are `.T.` / `.F.`, logicals also `.U.`).
    Enum(String),
    /// `$`.
    Unset,
    /// `*`.
    Derived,
    List(Vec<Value>),
    /// `NAME(value)`: a typed parameter such as `LENGTH_MEASURE(1.E-05)`.
    Typed(String, Vec<Value>),
}

/// One `NAME(args)` record; a simple instance has one, a complex instance several.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    pub name: String,
    pub args: Vec<Value>,
}

/// An entity instance and the line where it starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Instance {
    pub line: usize,
    pub records: Vec<Record>,
}

impl Instance {
    /// The record called `name` (simple or a part of a complex instance).
    pub fn record(&self, name: &str) -> Option<&Record> {
        self.records.iter().find(|r| r.name == name)
    }
    /// The entity name of a simple instance, or the record names joined by `+`.
    pub fn type_name(&self) -> String {
        self.records
            .iter()
            .map(|r| r.name.as_str())
            .collect::<Vec<_>>()
            .join("+")
    }
}

/// A parsed exchange file: its data-section instances by number.
#[derive(Debug, Clone, Default)]
pub struct StepFile {
    pub instances: HashMap<usize, Instance>,
}

/// A face of the model: an untrimmed B-spline surface and whether its normal `S_u × S_v` is
/// the face normal (`same_sense`).
#[derive(Debug, Clone, PartialEq)]
pub struct StepFace {
    /// Instance number of the ADVANCED_FACE.
    pub id: usize,
    pub surface: BSplineSurface,
    pub same_sense: bool,
}

/// The faces of a STEP file and its shells.
#[derive(Debug, Clone, PartialEq)]
pub struct StepModel {
    pub faces: Vec<StepFace>,
    pub closed_shells: usize,
    pub open_shells: usize,
}

/// Reads a STEP file's B-spline faces.
pub fn read_step(path: &Path) -> Result<StepModel> {
    let bytes = super::read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    let file = parse(&text, path)?;
    file.model(path)
}

// ---------------------------------------------------------------------------------------------
// Lexer.

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Keyword(String),
    Inst(usize),
    Int(i64),
    Real(f64),
    Str(String),
    Enum(String),
    Dollar,
    Star,
    Open,
    Close,
    Comma,
    Eq,
    Semi,
}

struct Lexer<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
    path: &'a Path,
}

impl<'a> Lexer<'a> {
    fn err(&self, line: usize, msg: impl Into<String>) -> Error {
        Error::syntax(self.path, Location::Line(line), msg)
    }

    fn skip_space(&mut self) -> Result<()> {
        loop {
            match self.b.get(self.pos) {
                Some(b'\n') => {
                    self.line += 1;
                    self.pos += 1;
                }
                Some(c) if c.is_ascii_whitespace() => self.pos += 1,
                Some(b'/') if self.b.get(self.pos + 1) == Some(&b'*') => {
                    let start = self.line;
                    self.pos += 2;
                    loop {
                        match self.b.get(self.pos) {
                            None => return Err(self.err(start, "comment is never closed (*/)")),
                            Some(b'*') if self.b.get(self.pos + 1) == Some(&b'/') => {
                                self.pos += 2;
                                break;
                            }
                            Some(b'\n') => {
                                self.line += 1;
                                self.pos += 1;
                            }
                            _ => self.pos += 1,
                        }
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    /// The next token and its line, `None` at the end of input.
    fn next(&mut self) -> Result<Option<(Tok, usize)>> {
        self.skip_space()?;
        let line = self.line;
        let Some(&c) = self.b.get(self.pos) else {
            return Ok(None);
        };
        let tok = match c {
            b'(' | b')' | b',' | b'=' | b';' | b'$' | b'*' => {
                self.pos += 1;
                match c {
                    b'(' => Tok::Open,
                    b')' => Tok::Close,
                    b',' => Tok::Comma,
                    b'=' => Tok::Eq,
                    b';' => Tok::Semi,
                    b'$' => Tok::Dollar,
                    _ => Tok::Star,
                }
            }
            b'#' => {
                self.pos += 1;
                let s = self.take_while(|c| c.is_ascii_digit());
                if s.is_empty() {
                    return Err(self.err(line, "'#' without an instance number"));
                }
                Tok::Inst(
                    s.parse()
                        .map_err(|_| self.err(line, format!("instance number #{s} too large")))?,
                )
            }
            b'\'' => {
                self.pos += 1;
                let mut s = Vec::new();
                loop {
                    match self.b.get(self.pos) {
                        None => return Err(self.err(line, "string is never closed (')")),
                        Some(b'\'') if self.b.get(self.pos + 1) == Some(&b'\'') => {
                            s.push(b'\'');
                            self.pos += 2;
                        }
                        Some(b'\'') => {
                            self.pos += 1;
                            break;
                        }
                        Some(&ch) => {
                            if ch == b'\n' {
                                self.line += 1;
                            }
                            s.push(ch);
                            self.pos += 1;
                        }
                    }
                }
                Tok::Str(String::from_utf8_lossy(&s).into_owned())
            }
            b'"' => {
                // Binary value: kept as its hex text.
                self.pos += 1;
                let s = self.take_while(|c| c != b'"');
                if self.b.get(self.pos) != Some(&b'"') {
                    return Err(self.err(line, "binary value is never closed (\")"));
                }
                self.pos += 1;
                Tok::Str(s)
            }
            b'.' if self
                .b
                .get(self.pos + 1)
                .is_some_and(|c| c.is_ascii_alphabetic()) =>
            {
                self.pos += 1;
                let s = self.take_while(|c| c.is_ascii_alphanumeric() || c == b'_');
                if self.b.get(self.pos) != Some(&b'.') {
                    return Err(self.err(line, format!("enumeration .{s} is not closed by '.'")));
                }
                self.pos += 1;
                Tok::Enum(s.to_ascii_uppercase())
            }
            b'+' | b'-' | b'0'..=b'9' => self.number(line)?,
            c if c.is_ascii_alphabetic() || c == b'_' || c == b'!' => {
                let s = self.take_while(|c| {
                    c.is_ascii_alphanumeric() || c == b'_' || c == b'-' || c == b'!'
                });
                Tok::Keyword(s.to_ascii_uppercase())
            }
            other => {
                return Err(self.err(
                    line,
                    format!(
                        "unexpected character '{}'",
                        (other as char).escape_default()
                    ),
                ))
            }
        };
        Ok(Some((tok, line)))
    }

    fn take_while(&mut self, f: impl Fn(u8) -> bool) -> String {
        let start = self.pos;
        while self.b.get(self.pos).is_some_and(|&c| f(c)) {
            self.pos += 1;
        }
        String::from_utf8_lossy(&self.b[start..self.pos]).into_owned()
    }

    /// `[+-] digits [. digits] [E [+-] digits]`: an integer without a point, else a real.
    fn number(&mut self, line: usize) -> Result<Tok> {
        let start = self.pos;
        if matches!(self.b.get(self.pos), Some(b'+' | b'-')) {
            self.pos += 1;
        }
        let digits = self.take_while(|c| c.is_ascii_digit());
        if digits.is_empty() {
            return Err(self.err(line, "sign without a number"));
        }
        let mut real = false;
        if self.b.get(self.pos) == Some(&b'.') {
            real = true;
            self.pos += 1;
            self.take_while(|c| c.is_ascii_digit());
        }
        if matches!(self.b.get(self.pos), Some(b'E' | b'e')) {
            real = true;
            self.pos += 1;
            if matches!(self.b.get(self.pos), Some(b'+' | b'-')) {
                self.pos += 1;
            }
            if self.take_while(|c| c.is_ascii_digit()).is_empty() {
                return Err(self.err(line, "exponent without digits"));
            }
        }
        let s = String::from_utf8_lossy(&self.b[start..self.pos]).into_owned();
        if real {
            let x: f64 = s
                .parse()
                .map_err(|_| self.err(line, format!("bad real '{s}'")))?;
            if !x.is_finite() {
                return Err(self.err(line, format!("real '{s}' is out of range")));
            }
            Ok(Tok::Real(x))
        } else {
            s.parse()
                .map(Tok::Int)
                .map_err(|_| self.err(line, format!("integer '{s}' is out of range")))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Parser.

struct Parser<'a> {
    lex: Lexer<'a>,
    peeked: Option<(Tok, usize)>,
    /// Line of the last token taken (for errors at the end of input).
    last_line: usize,
}

/// Lists nested deeper than this are rejected (a guard against stack exhaustion on hostile
/// input; STEP data nests 3 deep at most).
const MAX_DEPTH: usize = 64;

impl<'a> Parser<'a> {
    fn peek(&mut self) -> Result<Option<&Tok>> {
        if self.peeked.is_none() {
            self.peeked = self.lex.next()?;
        }
        Ok(self.peeked.as_ref().map(|(t, _)| t))
    }

    fn take(&mut self, what: &str) -> Result<(Tok, usize)> {
        self.peek()?;
        match self.peeked.take() {
            Some((t, l)) => {
                self.last_line = l;
                Ok((t, l))
            }
            None => Err(self.lex.err(
                self.lex.line,
                format!("file ends where {what} was expected (truncated file?)"),
            )),
        }
    }

    fn expect(&mut self, tok: Tok, what: &str) -> Result<usize> {
        let (t, l) = self.take(what)?;
        if t == tok {
            Ok(l)
        } else {
            Err(self
                .lex
                .err(l, format!("expected {what}, found {}", describe(&t))))
        }
    }

    fn keyword(&mut self, what: &str) -> Result<(String, usize)> {
        match self.take(what)? {
            (Tok::Keyword(k), l) => Ok((k, l)),
            (t, l) => Err(self
                .lex
                .err(l, format!("expected {what}, found {}", describe(&t)))),
        }
    }

    /// `( value, value, ... )` after the opening parenthesis was taken.
    fn list_rest(&mut self, depth: usize) -> Result<Vec<Value>> {
        if depth > MAX_DEPTH {
            return Err(self.lex.err(self.last_line, "lists nested too deeply"));
        }
        let mut out = Vec::new();
        if self.peek()? == Some(&Tok::Close) {
            self.take("')'")?;
            return Ok(out);
        }
        loop {
            out.push(self.value(depth)?);
            match self.take("',' or ')'")? {
                (Tok::Comma, _) => {}
                (Tok::Close, _) => return Ok(out),
                (t, l) => {
                    return Err(self
                        .lex
                        .err(l, format!("expected ',' or ')', found {}", describe(&t))))
                }
            }
        }
    }

    fn value(&mut self, depth: usize) -> Result<Value> {
        let (t, l) = self.take("a parameter")?;
        Ok(match t {
            Tok::Inst(n) => Value::Ref(n),
            Tok::Int(i) => Value::Int(i),
            Tok::Real(x) => Value::Real(x),
            Tok::Str(s) => Value::Str(s),
            Tok::Enum(e) => Value::Enum(e),
            Tok::Dollar => Value::Unset,
            Tok::Star => Value::Derived,
            Tok::Open => Value::List(self.list_rest(depth + 1)?),
            Tok::Keyword(k) => {
                self.expect(Tok::Open, "'(' after a typed parameter")?;
                Value::Typed(k, self.list_rest(depth + 1)?)
            }
            t => {
                return Err(self
                    .lex
                    .err(l, format!("expected a parameter, found {}", describe(&t))))
            }
        })
    }

    /// `NAME(args)`.
    fn record(&mut self) -> Result<Record> {
        let (name, _) = self.keyword("an entity name")?;
        self.expect(Tok::Open, "'(' after the entity name")?;
        let args = self.list_rest(1)?;
        Ok(Record { name, args })
    }
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Keyword(k) => format!("'{k}'"),
        Tok::Inst(n) => format!("'#{n}'"),
        Tok::Int(i) => format!("the number {i}"),
        Tok::Real(x) => format!("the number {x}"),
        Tok::Str(_) => "a string".into(),
        Tok::Enum(e) => format!("'.{e}.'"),
        Tok::Dollar => "'$'".into(),
        Tok::Star => "'*'".into(),
        Tok::Open => "'('".into(),
        Tok::Close => "')'".into(),
        Tok::Comma => "','".into(),
        Tok::Eq => "'='".into(),
        Tok::Semi => "';'".into(),
    }
}

/// Parses an exchange file (`path` only names it in errors).
pub fn parse(text: &str, path: &Path) -> Result<StepFile> {
    let mut p = Parser {
        lex: Lexer {
            b: text.as_bytes(),
            pos: 0,
            line: 1,
            path,
        },
        peeked: None,
        last_line: 1,
    };
    let (magic, l) = p.keyword("ISO-10303-21;")?;
    if magic != "ISO-10303-21" {
        return Err(p.lex.err(
            l,
            format!("not a STEP file: starts with '{magic}' instead of ISO-10303-21"),
        ));
    }
    p.expect(Tok::Semi, "';'")?;
    let mut file = StepFile::default();
    let mut saw_data = false;
    loop {
        let (section, l) = p.keyword("HEADER, DATA or END-ISO-10303-21")?;
        match section.as_str() {
            "HEADER" => {
                p.expect(Tok::Semi, "';' after HEADER")?;
                loop {
                    if p.peek()? == Some(&Tok::Keyword("ENDSEC".into())) {
                        p.take("ENDSEC")?;
                        p.expect(Tok::Semi, "';' after ENDSEC")?;
                        break;
                    }
                    p.record()?;
                    p.expect(Tok::Semi, "';' after a header entity")?;
                }
            }
            "DATA" => {
                saw_data = true;
                if p.peek()? == Some(&Tok::Open) {
                    p.take("'('")?;
                    p.list_rest(1)?;
                }
                p.expect(Tok::Semi, "';' after DATA")?;
                loop {
                    let (t, l) = p.take("an instance or ENDSEC")?;
                    let id = match t {
                        Tok::Inst(id) => id,
                        Tok::Keyword(k) if k == "ENDSEC" => {
                            p.expect(Tok::Semi, "';' after ENDSEC")?;
                            break;
                        }
                        t => {
                            return Err(p.lex.err(
                                l,
                                format!("expected '#n =' or ENDSEC, found {}", describe(&t)),
                            ))
                        }
                    };
                    p.expect(Tok::Eq, "'=' after the instance number")?;
                    let records = if p.peek()? == Some(&Tok::Open) {
                        p.take("'('")?;
                        let mut rs = Vec::new();
                        while p.peek()? != Some(&Tok::Close) {
                            rs.push(p.record()?);
                        }
                        p.take("')'")?;
                        if rs.is_empty() {
                            return Err(p.lex.err(l, format!("#{id}: empty complex instance")));
                        }
                        rs
                    } else {
                        vec![p.record()?]
                    };
                    p.expect(Tok::Semi, "';' at the end of the instance")?;
                    if file
                        .instances
                        .insert(id, Instance { line: l, records })
                        .is_some()
                    {
                        return Err(p.lex.err(l, format!("#{id} is defined twice")));
                    }
                }
            }
            "END-ISO-10303-21" => {
                p.expect(Tok::Semi, "';' after END-ISO-10303-21")?;
                break;
            }
            other => {
                return Err(p.lex.err(
                    l,
                    format!("expected HEADER, DATA or END-ISO-10303-21, found '{other}'"),
                ))
            }
        }
    }
    if !saw_data {
        return Err(Error::content(path, "STEP file has no DATA section"));
    }
    Ok(file)
}

// ---------------------------------------------------------------------------------------------
// Resolution of B-rep faces.

impl StepFile {
    fn get(&self, id: usize, path: &Path, from: &Instance) -> Result<&Instance> {
        self.instances.get(&id).ok_or_else(|| {
            Error::syntax(
                path,
                Location::Line(from.line),
                format!("reference to #{id}, which is not defined"),
            )
        })
    }

    /// Every ADVANCED_FACE (in instance-number order) as an untrimmed B-spline face, and the
    /// shell counts.
    pub fn model(&self, path: &Path) -> Result<StepModel> {
        let mut ids: Vec<usize> = self
            .instances
            .iter()
            .filter(|(_, i)| i.records.len() == 1 && i.records[0].name == "ADVANCED_FACE")
            .map(|(&id, _)| id)
            .collect();
        ids.sort_unstable();
        let count = |name: &str| {
            self.instances
                .values()
                .filter(|i| i.record(name).is_some())
                .count()
        };
        if ids.is_empty() {
            let other: Vec<&str> = ["FACE_SURFACE", "TRIMMED_CURVE", "MANIFOLD_SOLID_BREP"]
                .into_iter()
                .filter(|n| count(n) > 0)
                .collect();
            return Err(Error::unsupported(
                path,
                if other.is_empty() {
                    "no ADVANCED_FACE in the file: scansurf reads B-rep models of B-spline faces"
                        .to_string()
                } else {
                    format!(
                        "no ADVANCED_FACE in the file (it has {}): scansurf reads B-rep models of \
                         B-spline faces",
                        other.join(", ")
                    )
                },
            ));
        }
        let faces = ids
            .iter()
            .map(|&id| self.face(id, path))
            .collect::<Result<Vec<_>>>()?;
        Ok(StepModel {
            faces,
            closed_shells: count("CLOSED_SHELL"),
            open_shells: count("OPEN_SHELL"),
        })
    }

    fn face(&self, id: usize, path: &Path) -> Result<StepFace> {
        let inst = &self.instances[&id];
        let at = |msg: String| Error::syntax(path, Location::Line(inst.line), msg);
        let args = &inst.records[0].args;
        let (bounds, surf, sense) = match args.as_slice() {
            [_, Value::List(b), Value::Ref(s), Value::Enum(e)] => (b, *s, e),
            _ => {
                return Err(at(format!(
                    "#{id}: ADVANCED_FACE needs (name, (bounds), #surface, .T./.F.)"
                )))
            }
        };
        let same_sense =
            bool_enum(sense).ok_or_else(|| at(format!("#{id}: bad sense .{sense}.")))?;
        let surface = self.surface(surf, path, inst)?;
        if bounds.len() != 1 {
            return Err(Error::unsupported(
                path,
                format!(
                    "face #{id} (line {}) has {} bounds: faces with holes or trimmed faces are \
                     not supported, only faces bounded by their parameter rectangle",
                    inst.line,
                    bounds.len()
                ),
            ));
        }
        let (u, v) = self.face_rectangle(id, inst, &bounds[0], &surface, path)?;
        let surface = surface.restricted(u, v).map_err(|e| {
            Error::unsupported(path, format!("face #{id} (line {}): {e}", inst.line))
        })?;
        Ok(StepFace {
            id,
            surface,
            same_sense,
        })
    }

    /// The B-spline surface of instance `id` (simple or complex form).
    fn surface(&self, id: usize, path: &Path, from: &Instance) -> Result<BSplineSurface> {
        let inst = self.get(id, path, from)?;
        let at = |msg: String| Error::syntax(path, Location::Line(inst.line), msg);
        let (deg_u, deg_v, ctrl, knots) = if let Some(r) = inst
            .record("B_SPLINE_SURFACE_WITH_KNOTS")
            .filter(|_| inst.records.len() == 1)
        {
            match r.args.as_slice() {
                [_, du, dv, Value::List(ctrl), _, _, _, _, mu, mv, ku, kv, _] => {
                    (du, dv, ctrl, [mu, mv, ku, kv])
                }
                _ => {
                    return Err(at(format!(
                        "#{id}: B_SPLINE_SURFACE_WITH_KNOTS needs 13 parameters, has {}",
                        r.args.len()
                    )))
                }
            }
        } else if let (Some(b), Some(k)) = (
            inst.record("B_SPLINE_SURFACE"),
            inst.record("B_SPLINE_SURFACE_WITH_KNOTS"),
        ) {
            if let Some(r) = inst.record("RATIONAL_B_SPLINE_SURFACE") {
                let unit = matches!(r.args.as_slice(), [Value::List(rows)]
                    if rows.iter().all(|row| matches!(row, Value::List(ws)
                        if ws.iter().all(|w| real(w).is_some_and(|w| (w - 1.0).abs() < 1e-12)))));
                if !unit {
                    return Err(Error::unsupported(
                        path,
                        format!(
                            "surface #{id} (line {}) is rational with weights other than 1: \
                             NURBS weights are not supported",
                            inst.line
                        ),
                    ));
                }
            }
            match (b.args.as_slice(), k.args.as_slice()) {
                ([du, dv, Value::List(ctrl), _, _, _, _], [mu, mv, ku, kv, _]) => {
                    (du, dv, ctrl, [mu, mv, ku, kv])
                }
                _ => {
                    return Err(at(format!(
                        "#{id}: B_SPLINE_SURFACE needs 7 and B_SPLINE_SURFACE_WITH_KNOTS 5 \
                         parameters in the complex form"
                    )))
                }
            }
        } else {
            return Err(Error::unsupported(
                path,
                format!(
                    "surface #{id} (line {}) is a {}: only B-spline surfaces \
                     (B_SPLINE_SURFACE_WITH_KNOTS) are supported",
                    inst.line,
                    inst.type_name()
                ),
            ));
        };
        let degree = |v: &Value| match v {
            Value::Int(d) if (1..=30).contains(d) => Ok(*d as usize),
            _ => Err(at(format!("#{id}: bad degree {v:?}"))),
        };
        let (du, dv) = (degree(deg_u)?, degree(deg_v)?);
        let rows = ctrl
            .iter()
            .map(|row| match row {
                Value::List(ps) => ps
                    .iter()
                    .map(|p| match p {
                        Value::Ref(r) => self.point(*r, path, inst),
                        _ => Err(at(format!("#{id}: control point is not a reference"))),
                    })
                    .collect::<Result<Vec<_>>>(),
                _ => Err(at(format!("#{id}: control points are not a list of lists"))),
            })
            .collect::<Result<Vec<_>>>()?;
        let kn_u =
            expand_knots(knots[0], knots[2]).ok_or_else(|| at(format!("#{id}: bad u knots")))?;
        let kn_v =
            expand_knots(knots[1], knots[3]).ok_or_else(|| at(format!("#{id}: bad v knots")))?;
        BSplineSurface::new(du, dv, kn_u, kn_v, rows).map_err(|e| {
            Error::unsupported(
                path,
                format!(
                    "surface #{id} (line {}): {e} (only clamped, non-periodic knot vectors are \
                     supported)",
                    inst.line
                ),
            )
        })
    }

    fn point(&self, id: usize, path: &Path, from: &Instance) -> Result<Point3<f64>> {
        let inst = self.get(id, path, from)?;
        let coords = match inst.record("CARTESIAN_POINT").map(|r| r.args.as_slice()) {
            Some([_, Value::List(c)]) => c.iter().map(real).collect::<Option<Vec<f64>>>(),
            _ => None,
        };
        match coords.as_deref() {
            Some(&[x, y, z]) => Ok(Point3::new(x, y, z)),
            _ => Err(Error::syntax(
                path,
                Location::Line(inst.line),
                format!(
                    "#{id}: expected a 3D CARTESIAN_POINT, found {}",
                    inst.type_name()
                ),
            )),
        }
    }

    /// The parameter rectangle the bound encloses: the bound must be one loop of edges that
    /// run along iso-curves u = const or v = const of the surface, with every edge end at a
    /// corner of one rectangle [u_a, u_b] x [v_a, v_b] of the domain (the whole domain for an
    /// untrimmed face; a sub-rectangle for a face on an extended surface,
    /// [`crate::nurbs::extend`]). Vertices are inverted on the surface (global search) and must
    /// lie on it, and every B-spline edge curve's midpoint on the rectangle's boundary, within
    /// 1e-3 of the patch size; corner parameters within 1e-9 of the domain width of a knot are
    /// snapped to it.
    fn face_rectangle(
        &self,
        face_id: usize,
        face: &Instance,
        bound: &Value,
        s: &BSplineSurface,
        path: &Path,
    ) -> Result<((f64, f64), (f64, f64))> {
        let trimmed = |why: String| {
            Error::unsupported(
                path,
                format!(
                    "face #{face_id} (line {}) is trimmed ({why}): only faces bounded by \
                     iso-curves of their surface (a parameter rectangle) are supported",
                    face.line
                ),
            )
        };
        let bad = |inst: &Instance, what: &str| {
            Error::syntax(
                path,
                Location::Line(inst.line),
                format!("expected {what}, found {}", inst.type_name()),
            )
        };
        let Value::Ref(b) = bound else {
            return Err(bad(face, "a reference to a FACE_BOUND"));
        };
        let b = self.get(*b, path, face)?;
        let lp = match b
            .record("FACE_OUTER_BOUND")
            .or(b.record("FACE_BOUND"))
            .map(|r| r.args.as_slice())
        {
            Some([_, Value::Ref(l), _]) => self.get(*l, path, b)?,
            _ => return Err(bad(b, "FACE_OUTER_BOUND(name, #loop, sense)")),
        };
        let edges = match lp.record("EDGE_LOOP").map(|r| r.args.as_slice()) {
            Some([_, Value::List(es)]) => es,
            _ if lp.record("VERTEX_LOOP").is_some() => {
                return Err(trimmed("its bound is a single vertex".into()))
            }
            _ => return Err(bad(lp, "an EDGE_LOOP")),
        };
        // Every edge: its two end vertices (id, point) and its curve's midpoint.
        let mut ends: Vec<[(usize, Point3<f64>); 2]> = Vec::with_capacity(edges.len());
        let mut mids: Vec<(usize, Option<Point3<f64>>)> = Vec::with_capacity(edges.len());
        for e in edges {
            let Value::Ref(oe) = e else {
                return Err(bad(lp, "references to ORIENTED_EDGEs"));
            };
            let oe = self.get(*oe, path, lp)?;
            let ec = match oe.record("ORIENTED_EDGE").map(|r| r.args.as_slice()) {
                Some([_, _, _, Value::Ref(ec), _]) => self.get(*ec, path, oe)?,
                _ => return Err(bad(oe, "ORIENTED_EDGE(name, *, *, #edge, sense)")),
            };
            let (va, vb, geom) = match ec.record("EDGE_CURVE").map(|r| r.args.as_slice()) {
                Some([_, Value::Ref(a), Value::Ref(b), Value::Ref(g), _]) => (*a, *b, *g),
                _ => return Err(bad(ec, "EDGE_CURVE(name, #v1, #v2, #curve, sense)")),
            };
            let mut pair = [(0usize, Point3::origin()); 2];
            for (k, v) in [va, vb].into_iter().enumerate() {
                let vi = self.get(v, path, ec)?;
                let p = match vi.record("VERTEX_POINT").map(|r| r.args.as_slice()) {
                    Some([_, Value::Ref(p)]) => self.point(*p, path, vi)?,
                    _ => return Err(bad(vi, "VERTEX_POINT(name, #point)")),
                };
                pair[k] = (v, p);
            }
            ends.push(pair);
            mids.push((ec_id(oe), self.curve_midpoint(geom)));
        }
        let (u0, u1) = s.domain_u();
        let (v0, v1) = s.domain_v();
        let tol = 1e-3 * s.ctrl_extent().max(f64::MIN_POSITIVE);
        // Vertex parameters: the nearest crossing of two knot lines of full multiplicity
        // (the domain corners, and the trim lines of extended surfaces) where the surface
        // point is the vertex, else a global inversion (whose parameters are snapped to the
        // nearest knots when the surface point there is still the vertex).
        let (wu, wv) = (u1 - u0, v1 - v0);
        let full = |knots: &[f64], p: usize| -> Vec<f64> {
            multiplicities(knots)
                .into_iter()
                .filter(|&(_, m)| m >= p)
                .map(|(k, _)| k)
                .collect()
        };
        let (lines_u, lines_v) = (full(&s.knots_u, s.degree_u), full(&s.knots_v, s.degree_v));
        let snap = |x: f64, knots: &[f64], width: f64| {
            knots
                .iter()
                .copied()
                .min_by(|a, b| (a - x).abs().total_cmp(&(b - x).abs()))
                .filter(|k| (k - x).abs() <= 1e-3 * width)
                .unwrap_or(x)
        };
        let locate = |p: &Point3<f64>| -> Option<(f64, f64)> {
            let crossing = lines_u
                .iter()
                .flat_map(|&u| lines_v.iter().map(move |&v| (u, v)))
                .map(|(u, v)| ((s.evaluate(u, v) - p).norm(), (u, v)))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .filter(|(d, _)| *d <= tol);
            if let Some((_, uv)) = crossing {
                return Some(uv);
            }
            let c = s.closest_point_global(p, 4);
            if c.distance > tol {
                return None;
            }
            let snapped = (snap(c.u, &s.knots_u, wu), snap(c.v, &s.knots_v, wv));
            if (s.evaluate(snapped.0, snapped.1) - p).norm() <= tol {
                Some(snapped)
            } else {
                Some((c.u, c.v))
            }
        };
        let mut uvs: Vec<(usize, (f64, f64))> = Vec::new();
        for &(id, p) in ends.iter().flatten() {
            if uvs.iter().any(|(v, _)| *v == id) {
                continue;
            }
            let uv =
                locate(&p).ok_or_else(|| trimmed(format!("vertex #{id} is not on the surface")))?;
            uvs.push((id, uv));
        }
        let (mut lo_u, mut hi_u) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut lo_v, mut hi_v) = (f64::INFINITY, f64::NEG_INFINITY);
        for &(_, (u, v)) in &uvs {
            (lo_u, hi_u) = (lo_u.min(u), hi_u.max(u));
            (lo_v, hi_v) = (lo_v.min(v), hi_v.max(v));
        }
        if !(hi_u - lo_u > 1e-9 * wu && hi_v - lo_v > 1e-9 * wv) {
            return Err(trimmed(
                "its vertices do not span a parameter rectangle".into(),
            ));
        }
        // Each vertex at a corner of the rectangle (within 1e-6 of the domain).
        let near = |a: f64, b: f64, w: f64| (a - b).abs() <= 1e-6 * w;
        for (id, (u, v)) in &uvs {
            let at_u = near(*u, lo_u, wu) || near(*u, hi_u, wu);
            let at_v = near(*v, lo_v, wv) || near(*v, hi_v, wv);
            if !(at_u && at_v) {
                return Err(trimmed(format!(
                    "vertex #{id} is not at a corner of a parameter rectangle"
                )));
            }
        }
        // Each edge's midpoint on a side of the rectangle.
        let uv_of = |id: usize| uvs.iter().find(|(v, _)| *v == id).map(|(_, uv)| *uv);
        for (pair, (edge, mid)) in ends.iter().zip(&mids) {
            let Some(mid) = mid else { continue };
            let (Some(a), Some(b)) = (uv_of(pair[0].0), uv_of(pair[1].0)) else {
                continue;
            };
            let guess = (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1));
            let cp = s.closest_point(mid, guess);
            let on_side = near(cp.u, lo_u, wu * 1e3)
                || near(cp.u, hi_u, wu * 1e3)
                || near(cp.v, lo_v, wv * 1e3)
                || near(cp.v, hi_v, wv * 1e3);
            if cp.distance > tol || !on_side {
                return Err(trimmed(format!(
                    "edge #{edge} runs inside the parameter rectangle"
                )));
            }
        }
        Ok(((lo_u, hi_u), (lo_v, hi_v)))
    }

    /// The midpoint (in parameter) of a B_SPLINE_CURVE_WITH_KNOTS, `None` for other curves
    /// or malformed data (then only the edge ends are checked).
    fn curve_midpoint(&self, id: usize) -> Option<Point3<f64>> {
        let inst = self.instances.get(&id)?;
        // A SURFACE_CURVE (or SEAM_CURVE) wraps the 3D curve with its pcurves.
        if let Some(r) = inst
            .record("SURFACE_CURVE")
            .or(inst.record("SEAM_CURVE"))
            .filter(|_| inst.records.len() == 1)
        {
            return match r.args.get(1) {
                Some(Value::Ref(c)) if *c != id => self.curve_midpoint(*c),
                _ => None,
            };
        }
        let r = inst.record("B_SPLINE_CURVE_WITH_KNOTS")?;
        if inst.records.len() != 1 {
            return None;
        }
        let [_, Value::Int(d), Value::List(ps), _, _, _, m, k, _] = r.args.as_slice() else {
            return None;
        };
        let ctrl = ps
            .iter()
            .map(|p| match p {
                Value::Ref(p) => self.point(*p, Path::new(""), inst).ok(),
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        let knots = expand_knots(m, k)?;
        let c = crate::nurbs::BSplineCurve::new(usize::try_from(*d).ok()?, knots, ctrl).ok()?;
        let (t0, t1) = c.domain();
        Some(c.evaluate(0.5 * (t0 + t1)))
    }
}

fn ec_id(oe: &Instance) -> usize {
    match oe.records[0].args.get(3) {
        Some(Value::Ref(r)) => *r,
        _ => 0,
    }
}

fn bool_enum(e: &str) -> Option<bool> {
    match e {
        "T" | "TRUE" => Some(true),
        "F" | "FALSE" => Some(false),
        _ => None,
    }
}

fn real(v: &Value) -> Option<f64> {
    match v {
        Value::Real(x) => Some(*x),
        Value::Int(i) => Some(*i as f64),
        _ => None,
    }
}

/// Knot vector from `(multiplicities)` and `(distinct knots)`.
fn expand_knots(mults: &Value, knots: &Value) -> Option<Vec<f64>> {
    let (Value::List(m), Value::List(k)) = (mults, knots) else {
        return None;
    };
    if m.len() != k.len() || m.is_empty() {
        return None;
    }
    let mut out = Vec::new();
    for (m, k) in m.iter().zip(k) {
        let Value::Int(m) = m else { return None };
        if !(1..=64).contains(m) {
            return None;
        }
        let k = real(k)?;
        out.extend(std::iter::repeat_n(k, *m as usize));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{step_string, ExportOptions};
    use crate::nurbs::network::two_patch_network;
    use crate::nurbs::PatchNetwork;

    fn net() -> PatchNetwork {
        // Two patches side by side sharing the edge x = 1.
        two_patch_network(|x, y| 0.2 * (x * 2.0).sin() * y)
    }

    fn p() -> &'static Path {
        Path::new("t.step")
    }

    #[test]
    fn reads_back_what_the_writer_wrote() {
        let n = net();
        let text = step_string(&n, &ExportOptions::default()).unwrap();
        let m = parse(&text, p()).unwrap().model(p()).unwrap();
        assert_eq!(m.faces.len(), 2);
        assert_eq!((m.open_shells, m.closed_shells), (1, 0));
        for (f, g) in m.faces.iter().zip(&n.faces) {
            assert_eq!(f.same_sense, g.same_sense);
            let s = &f.surface;
            assert_eq!((s.degree_u, s.degree_v), (3, 3));
            assert_eq!(s.knots_u, g.surface.knots_u);
            assert_eq!(s.knots_v, g.surface.knots_v);
            for (r, q) in s.ctrl.iter().flatten().zip(g.surface.ctrl.iter().flatten()) {
                assert!((r - q).norm() < 1e-12, "{r} vs {q}");
            }
        }
    }

    /// `n` scaled about the origin.
    fn scaled(mut n: PatchNetwork, k: f64) -> PatchNetwork {
        let sc = |p: &mut Point3<f64>| *p = Point3::from(p.coords * k);
        n.vertices.iter_mut().for_each(sc);
        for e in &mut n.edges {
            e.curve.ctrl.iter_mut().for_each(sc);
        }
        for f in &mut n.faces {
            f.surface.ctrl.iter_mut().flatten().for_each(sc);
        }
        n
    }

    #[test]
    fn faces_on_extended_surfaces_read_back_as_the_patches() {
        // 0.005 mm patches: the writer extends their surfaces (export::apron).
        let n = scaled(net(), 0.005);
        let opts = ExportOptions::default();
        let (eu, ev) = opts.apron_widths(&n.faces[0].surface);
        assert!(eu > 1.0 && ev > 1.0, "{eu} {ev}");
        let text = step_string(&n, &opts).unwrap();
        let m = parse(&text, p()).unwrap().model(p()).unwrap();
        assert_eq!(m.faces.len(), 2);
        for (f, g) in m.faces.iter().zip(&n.faces) {
            let s = &f.surface;
            assert_eq!(s.knots_u, g.surface.knots_u);
            assert_eq!(s.knots_v, g.surface.knots_v);
            for (r, q) in s.ctrl.iter().flatten().zip(g.surface.ctrl.iter().flatten()) {
                assert!((r - q).norm() < 1e-15, "{r} vs {q}");
            }
        }
        // Without extension the surfaces are written as they are, with fewer control points.
        let plain = ExportOptions {
            extend_surfaces: crate::export::ExtendSurfaces::Never,
            ..ExportOptions::default()
        };
        let count = |t: &str| t.matches("CARTESIAN_POINT").count();
        let text2 = step_string(&n, &plain).unwrap();
        assert_eq!(count(&text) - count(&text2), 2 * (11 * 11 - 5 * 5));
        // A face whose vertices are not at the corners of a parameter rectangle is still
        // refused: move one vertex along its side (it stays on the surface).
        let flat = text2.replace("\n  ", "");
        let vp = flat
            .lines()
            .find_map(|l| l.split_once("VERTEX_POINT('',#"))
            .map(|(_, r)| r.trim_end_matches(");").to_string())
            .unwrap();
        let q = n.faces[0].surface.evaluate(0.5, 0.0);
        let moved: String = flat
            .lines()
            .map(|l| {
                if l.starts_with(&format!("#{vp} = ")) {
                    format!(
                        "#{vp} = CARTESIAN_POINT('',({},{},{}));\n",
                        crate::export::fmt_real(q.x),
                        crate::export::fmt_real(q.y),
                        crate::export::fmt_real(q.z)
                    )
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        let e = parse(&moved, p()).unwrap().model(p()).unwrap_err();
        assert!(e.to_string().contains("trimmed"), "{e}");
    }

    #[test]
    fn lexes_all_token_kinds() {
        let text = "ISO-10303-21; /* c\n */ HEADER; FILE_NAME('a''b',$); ENDSEC;\nDATA;\n\
            #1=X(-1.5E+02,+3,.T.,*,$,(1,(2.)),LENGTH_MEASURE(1.E-5),'s',\"0F\");\n\
            ENDSEC; END-ISO-10303-21;";
        let f = parse(text, p()).unwrap();
        let r = &f.instances[&1].records[0];
        assert_eq!(f.instances[&1].line, 4);
        assert_eq!(
            r.args,
            vec![
                Value::Real(-150.0),
                Value::Int(3),
                Value::Enum("T".into()),
                Value::Derived,
                Value::Unset,
                Value::List(vec![Value::Int(1), Value::List(vec![Value::Real(2.0)])]),
                Value::Typed("LENGTH_MEASURE".into(), vec![Value::Real(1e-5)]),
                Value::Str("s".into()),
                Value::Str("0F".into()),
            ]
        );
    }

    #[test]
    fn complex_entity_surface_form() {
        let n = net();
        let text = step_string(&n, &ExportOptions::default()).unwrap();
        // Rewrite every simple B_SPLINE_SURFACE_WITH_KNOTS('',3,3,(..),.UNSPECIFIED.,.F.,.F.,.F.,
        // mults..,.UNSPECIFIED.) into the complex form.
        let flat = text.replace("\n  ", "");
        let mut out = String::new();
        for line in flat.lines() {
            if let Some(pos) = line.find("B_SPLINE_SURFACE_WITH_KNOTS('',") {
                let body = &line[pos + "B_SPLINE_SURFACE_WITH_KNOTS('',".len()..line.len() - 2];
                let split = body.find(",.UNSPECIFIED.,.F.,.F.,.F.,").unwrap();
                let (head, tail) = body.split_at(split);
                let tail = &tail[",.UNSPECIFIED.,.F.,.F.,.F.,".len()..];
                let weights = "((1.,1.,1.,1.,1.),(1.,1.,1.,1.,1.),(1.,1.,1.,1.,1.),(1.,1.,1.,1.,1.),(1.,1.,1.,1.,1.))";
                out.push_str(&format!(
                    "{}( BOUNDED_SURFACE() B_SPLINE_SURFACE({head},.UNSPECIFIED.,.F.,.F.,.F.) \
                     B_SPLINE_SURFACE_WITH_KNOTS({tail}) GEOMETRIC_REPRESENTATION_ITEM() \
                     RATIONAL_B_SPLINE_SURFACE({weights}) REPRESENTATION_ITEM('') SURFACE() );\n",
                    &line[..pos]
                ));
            } else {
                out.push_str(line);
                out.push('\n');
            }
        }
        assert!(out.contains("BOUNDED_SURFACE()"));
        let m = parse(&out, p()).unwrap().model(p()).unwrap();
        assert_eq!(m.faces.len(), 2);
        assert_eq!(m.faces[0].surface, n.faces[0].surface);
        // Non-unit weights are unsupported.
        let w = out.replacen("((1.,1.,1.,1.,1.),", "((2.,1.,1.,1.,1.),", 1);
        let e = parse(&w, p()).unwrap().model(p()).unwrap_err();
        assert!(matches!(e, Error::Unsupported { .. }), "{e}");
        assert!(e.to_string().contains("weights"), "{e}");
    }

    #[test]
    fn malformed_files_name_the_line() {
        let n = net();
        let text = step_string(&n, &ExportOptions::default()).unwrap();
        let cases: Vec<(String, &str)> = vec![
            (text.replacen("#30 =", "#30 ", 1), "expected '='"),
            (
                text.replacen(
                    "CARTESIAN_POINT('',(0.,0.,0.))",
                    "CARTESIAN_POINT('',(0.,0.,0.)",
                    1,
                ),
                "expected ','",
            ),
            (text[..text.len() / 2].to_string(), "truncated"),
            (
                text.replacen("DIRECTION('',(0.,0.,1.))", "DIRECTION('',(0.,0.,1e))", 1),
                "exponent",
            ),
            (text.replacen("#5 =", "#4 =", 1), "defined twice"),
            ("hello".to_string(), "not a STEP file"),
            (text.replacen("'',(", "'',(@", 1), "unexpected character"),
        ];
        for (t, want) in cases {
            let e = parse(&t, p()).unwrap_err();
            let msg = e.to_string();
            assert!(
                matches!(
                    e,
                    Error::Syntax {
                        location: Location::Line(_),
                        ..
                    }
                ),
                "{msg}"
            );
            assert!(msg.contains(want), "{msg} (want {want})");
        }
        // The line number is the line of the damage.
        let bad = text.replacen("#30 =", "#30 ", 1);
        let line = bad.lines().position(|l| l.starts_with("#30 ")).unwrap() + 1;
        let msg = parse(&bad, p()).unwrap_err().to_string();
        assert!(msg.contains(&format!("line {line}:")), "{msg}");
        // A dangling reference.
        let dangling = text.replacen("ADVANCED_FACE('',(#", "ADVANCED_FACE('',(#9999", 1);
        let e = parse(&dangling, p()).unwrap().model(p()).unwrap_err();
        assert!(e.to_string().contains("#9999"), "{e}");
    }

    #[test]
    fn unsupported_geometry_is_named() {
        let n = net();
        let text = step_string(&n, &ExportOptions::default()).unwrap();
        let flat = text.replace("\n  ", "");
        // A plane instead of the first surface.
        let id = flat
            .lines()
            .find(|l| l.contains("B_SPLINE_SURFACE_WITH_KNOTS"))
            .and_then(|l| l.split_once(" = "))
            .map(|(a, _)| a.to_string())
            .unwrap();
        let plane: String = flat
            .lines()
            .map(|l| {
                if l.starts_with(&format!("{id} = ")) {
                    format!("{id} = PLANE('',#4);\n")
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        let e = parse(&plane, p()).unwrap().model(p()).unwrap_err();
        assert!(matches!(e, Error::Unsupported { .. }), "{e}");
        assert!(e.to_string().contains("PLANE"), "{e}");
        // A face with a second (inner) bound.
        let holed = flat.replacen("ADVANCED_FACE('',(#", "ADVANCED_FACE('',(#1,#", 1);
        let e = parse(&holed, p()).unwrap().model(p()).unwrap_err();
        assert!(e.to_string().contains("2 bounds"), "{e}");
        // A vertex moved off the corner: trimmed.
        let vp = flat
            .lines()
            .find_map(|l| l.split_once("VERTEX_POINT('',#"))
            .map(|(_, r)| r.trim_end_matches(");").to_string())
            .unwrap();
        let moved: String = flat
            .lines()
            .map(|l| {
                if l.starts_with(&format!("#{vp} = ")) {
                    format!("#{vp} = CARTESIAN_POINT('',(0.5,0.5,3.));\n")
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        let e = parse(&moved, p()).unwrap().model(p()).unwrap_err();
        assert!(matches!(e, Error::Unsupported { .. }), "{e}");
        assert!(e.to_string().contains("trimmed"), "{e}");
        // No faces at all.
        let none = "ISO-10303-21;HEADER;ENDSEC;DATA;#1=CARTESIAN_POINT('',(0.,0.,0.));ENDSEC;END-ISO-10303-21;";
        let e = parse(none, p()).unwrap().model(p()).unwrap_err();
        assert!(e.to_string().contains("no ADVANCED_FACE"), "{e}");
    }
}
