//! CAD exchange writers for a [`PatchNetwork`](crate::nurbs::PatchNetwork): STEP (ISO 10303-21,
//! AP214 B-rep of B-spline faces) and IGES 5.3 (entity 128 per patch).
//!
//! Both writers validate the network first and render the whole file in memory, so they either
//! write a complete file or return an error before writing anything (an I/O error mid-write can
//! still leave a partial stream; the caller writes to a temporary file and renames it). The
//! output is deterministic: the same network and options give the same bytes. Reals are written
//! with the shortest representation that reads back to the same `f64` ([`fmt_real`]).

pub mod apron;
pub mod iges;
pub mod step;

pub use iges::{iges_string, write_iges};
pub use step::{step_string, write_step};

use crate::{Error, Result};

/// A length unit both formats can declare.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LengthUnit {
    #[default]
    Millimetre,
    Centimetre,
    Metre,
    Micrometre,
}

impl LengthUnit {
    /// STEP SI_UNIT prefix (`$` for none).
    pub(crate) fn step_prefix(self) -> &'static str {
        match self {
            LengthUnit::Millimetre => ".MILLI.",
            LengthUnit::Centimetre => ".CENTI.",
            LengthUnit::Metre => "$",
            LengthUnit::Micrometre => ".MICRO.",
        }
    }
    /// IGES global-section unit flag and unit name (IGES 5.3 §2.2.4.3, parameters 14-15).
    pub(crate) fn iges_flag_and_name(self) -> (u32, &'static str) {
        match self {
            LengthUnit::Millimetre => (2, "MM"),
            LengthUnit::Centimetre => (10, "CM"),
            LengthUnit::Metre => (6, "M"),
            LengthUnit::Micrometre => (9, "UM"),
        }
    }
}

impl std::str::FromStr for LengthUnit {
    type Err = Error;
    /// `mm`, `cm`, `m` or `um` (also `µm` and the full names).
    fn from_str(s: &str) -> Result<LengthUnit> {
        match s.to_ascii_lowercase().as_str() {
            "mm" | "millimetre" | "millimeter" => Ok(LengthUnit::Millimetre),
            "cm" | "centimetre" | "centimeter" => Ok(LengthUnit::Centimetre),
            "m" | "metre" | "meter" => Ok(LengthUnit::Metre),
            "um" | "µm" | "micrometre" | "micrometer" => Ok(LengthUnit::Micrometre),
            other => Err(Error::InvalidOption(format!(
                "unknown unit '{other}': expected mm, cm, m or um"
            ))),
        }
    }
}

/// A UTC date and time for file headers. Writers never read the clock: the caller passes the
/// time (e.g. [`Timestamp::from_unix_seconds`] of `SystemTime::now()`), and without one the
/// files carry the fixed [`Timestamp::EPOCH`], so output is reproducible.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timestamp {
    pub year: u16,
    pub month: u8,
    pub day: u8,
    pub hour: u8,
    pub minute: u8,
    pub second: u8,
}

impl Timestamp {
    /// 1970-01-01T00:00:00, used when no time is given.
    pub const EPOCH: Timestamp = Timestamp {
        year: 1970,
        month: 1,
        day: 1,
        hour: 0,
        minute: 0,
        second: 0,
    };

    /// The UTC calendar time of a Unix time in seconds (proleptic Gregorian; H. Hinnant's
    /// days-to-civil algorithm). Years outside 1970..=9999 are clamped to that range's ends.
    pub fn from_unix_seconds(secs: u64) -> Timestamp {
        const MAX: u64 = 253_402_300_799; // 9999-12-31T23:59:59
        let secs = secs.min(MAX);
        let days = (secs / 86_400) as i64;
        let rem = secs % 86_400;
        let z = days + 719_468;
        let era = z.div_euclid(146_097);
        let doe = z - era * 146_097;
        let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
        let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
        let mp = (5 * doy + 2) / 153;
        let day = (doy - (153 * mp + 2) / 5 + 1) as u8;
        let month = if mp < 10 { mp + 3 } else { mp - 9 } as u8;
        let year = (yoe + era * 400 + i64::from(month <= 2)) as u16;
        Timestamp {
            year,
            month,
            day,
            hour: (rem / 3600) as u8,
            minute: (rem / 60 % 60) as u8,
            second: (rem % 60) as u8,
        }
    }

    /// Parses `YYYY-MM-DDThh:mm:ss` (the ISO 8601 form STEP's FILE_NAME uses).
    pub fn parse_iso8601(s: &str) -> Result<Timestamp> {
        let bad = || Error::InvalidOption(format!("timestamp {s:?} is not YYYY-MM-DDThh:mm:ss"));
        let b = s.as_bytes();
        if b.len() != 19
            || b[4] != b'-'
            || b[7] != b'-'
            || b[10] != b'T'
            || b[13] != b':'
            || b[16] != b':'
        {
            return Err(bad());
        }
        let num = |r: std::ops::Range<usize>| -> Result<u16> {
            let t = &s[r];
            if !t.bytes().all(|c| c.is_ascii_digit()) {
                return Err(bad());
            }
            t.parse().map_err(|_| bad())
        };
        let ts = Timestamp {
            year: num(0..4)?,
            month: num(5..7)? as u8,
            day: num(8..10)? as u8,
            hour: num(11..13)? as u8,
            minute: num(14..16)? as u8,
            second: num(17..19)? as u8,
        };
        if !(1..=12).contains(&ts.month)
            || !(1..=31).contains(&ts.day)
            || ts.hour > 23
            || ts.minute > 59
            || ts.second > 60
        {
            return Err(bad());
        }
        Ok(ts)
    }

    /// `YYYY-MM-DDThh:mm:ss`.
    pub fn iso8601(&self) -> String {
        format!(
            "{:04}-{:02}-{:02}T{:02}:{:02}:{:02}",
            self.year, self.month, self.day, self.hour, self.minute, self.second
        )
    }

    /// IGES form `YYYYMMDD.HHNNSS` (15 characters).
    pub fn iges(&self) -> String {
        format!(
            "{:04}{:02}{:02}.{:02}{:02}{:02}",
            self.year, self.month, self.day, self.hour, self.minute, self.second
        )
    }
}

/// Header and unit data shared by the STEP and IGES writers.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    /// File / product name (STEP FILE_NAME.name and PRODUCT name; IGES file name and product
    /// ids). Usually the output file's name.
    pub name: String,
    /// Header time; `None` writes [`Timestamp::EPOCH`].
    pub timestamp: Option<Timestamp>,
    pub author: String,
    pub organization: String,
    /// STEP FILE_NAME.authorisation.
    pub authorization: String,
    /// Unit of the network's coordinates.
    pub unit: LengthUnit,
    /// Length tolerance in `unit`: STEP UNCERTAINTY_MEASURE_WITH_UNIT and IGES minimum
    /// resolution. Must be finite and positive.
    pub tolerance: f64,
    /// Whether STEP faces may be written as trimmed regions of extended surfaces
    /// ([`apron`]).
    pub extend_surfaces: ExtendSurfaces,
}

/// When the STEP writer extends a face's surface beyond the face ([`apron`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExtendSurfaces {
    /// Where a patch is small enough, in millimetres, for OpenCASCADE's point projection to
    /// fail on it ([`apron::apron_widths`]); other faces are untrimmed.
    #[default]
    Auto,
    /// Never: every face is its whole (untrimmed) surface.
    Never,
}

impl std::str::FromStr for ExtendSurfaces {
    type Err = Error;
    fn from_str(s: &str) -> Result<ExtendSurfaces> {
        match s.to_ascii_lowercase().as_str() {
            "auto" => Ok(ExtendSurfaces::Auto),
            "never" | "no" | "none" => Ok(ExtendSurfaces::Never),
            other => Err(Error::InvalidOption(format!(
                "unknown surface extension '{other}': expected auto or never"
            ))),
        }
    }
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            name: "scansurf".into(),
            timestamp: None,
            author: String::new(),
            organization: String::new(),
            authorization: String::new(),
            unit: LengthUnit::Millimetre,
            tolerance: 1e-6,
            extend_surfaces: ExtendSurfaces::Auto,
        }
    }
}

impl ExportOptions {
    pub(crate) fn check(&self) -> Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::InvalidOption(format!(
                "export tolerance must be positive, got {}",
                self.tolerance
            )));
        }
        Ok(())
    }

    /// The apron widths (e_u, e_v) the STEP writer gives a face on `s`.
    pub fn apron_widths(&self, s: &crate::nurbs::BSplineSurface) -> (f64, f64) {
        match self.extend_surfaces {
            ExtendSurfaces::Auto => apron::apron_widths(s, self.unit),
            ExtendSurfaces::Never => (0.0, 0.0),
        }
    }

    /// The extended surface a face on `s` is written on (STEP and IGES alike), `None` when the
    /// face is written as its whole surface.
    pub fn extended_surface(
        &self,
        s: &crate::nurbs::BSplineSurface,
    ) -> Option<crate::nurbs::BSplineSurface> {
        let (eu, ev) = self.apron_widths(s);
        (eu > 0.0 || ev > 0.0).then(|| s.extended(eu, ev))
    }

    pub(crate) fn time(&self) -> Timestamp {
        self.timestamp.unwrap_or(Timestamp::EPOCH)
    }
}

/// `scansurf <crate version>`, the preprocessor / originating system name in headers.
pub(crate) fn software() -> String {
    format!("scansurf {}", env!("CARGO_PKG_VERSION"))
}

/// A finite real in the shortest form that reads back to the same `f64`, in the syntax STEP
/// (ISO 10303-21 §6.3.3) and IGES both accept: always a decimal point, upper-case exponent,
/// e.g. `0.`, `1.`, `-2.5`, `1.E-7`, `-1.2345678901234567E20`. Negative zero is written `0.`.
/// Callers guarantee finiteness (the network is validated first).
pub fn fmt_real(x: f64) -> String {
    let mut s = String::with_capacity(24);
    push_real(&mut s, x);
    s
}

/// Appends [`fmt_real`]`(x)` to `out` without allocating (the writers format about a million
/// reals for a 1,500-patch network).
pub fn push_real(out: &mut String, x: f64) {
    if x == 0.0 {
        out.push_str("0.");
        return;
    }
    // ryu gives the shortest representation that reads back as x ("1.0", "0.1", "1e-7",
    // "1.5e20"), several times faster than core's formatting (2 million reals in the bunny's
    // STEP file).
    let mut buf = ryu::Buffer::new();
    let s = buf.format(x);
    let (mant, exp) = match s.split_once('e') {
        Some((m, e)) => (m, Some(e)),
        None => (s, None),
    };
    if let Some(stripped) = mant.strip_suffix(".0") {
        out.push_str(stripped);
        out.push('.');
    } else {
        out.push_str(mant);
        if !mant.contains('.') {
            out.push('.');
        }
    }
    if let Some(e) = exp {
        out.push('E');
        out.push_str(e);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_round_trip_and_have_a_point() {
        let cases = [
            (1.0, "1."),
            (-2.5e-7, "-2.5E-7"),
            (0.1, "0.1"),
            (-0.0, "0."),
            (1e20, "1.E20"),
            (123.456, "123.456"),
            (-3.0, "-3."),
        ];
        for (x, want) in cases {
            assert_eq!(fmt_real(x), want);
        }
        let mut seed = 12345u64;
        for _ in 0..2000 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = f64::from_bits(seed >> 2) * if seed & 1 == 0 { 1.0 } else { -1.0 };
            if !x.is_finite() {
                continue;
            }
            let s = fmt_real(x);
            assert!(s.contains('.'), "{s}");
            let back: f64 = s.parse().unwrap();
            assert_eq!(back, x, "{s}");
        }
    }

    #[test]
    fn timestamps() {
        assert_eq!(Timestamp::from_unix_seconds(0), Timestamp::EPOCH);
        let t = Timestamp::from_unix_seconds(1_700_000_000);
        assert_eq!(t.iso8601(), "2023-11-14T22:13:20");
        assert_eq!(t.iges(), "20231114.221320");
        assert_eq!(Timestamp::parse_iso8601("2023-11-14T22:13:20").unwrap(), t);
        // Leap day.
        assert_eq!(
            Timestamp::from_unix_seconds(951_782_400).iso8601(),
            "2000-02-29T00:00:00"
        );
        assert!(Timestamp::parse_iso8601("2023-13-14T22:13:20").is_err());
        assert!(Timestamp::parse_iso8601("2023-11-14 22:13:20").is_err());
        assert!(Timestamp::parse_iso8601("2023-11-1T22:13:200").is_err());
    }
}
