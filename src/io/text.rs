//! Helpers shared by the text readers: UTF-8 checking with a line number, and number parsing
//! with errors that name the line.

use crate::error::{Error, Location, Result};
use std::path::Path;

/// The bytes as UTF-8, or an error naming the line of the first invalid byte.
pub fn as_utf8<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::syntax(
            path,
            Location::Line(line),
            format!("not UTF-8 text (invalid byte at offset {at}); is this a binary file?"),
        )
    })
}

/// Parses a finite-or-not float token; the caller checks finiteness where it matters.
pub fn parse_f64(path: &Path, line: usize, token: &str, what: &str) -> Result<f64> {
    token.parse::<f64>().map_err(|_| {
        Error::syntax(
            path,
            Location::Line(line),
            format!("expected a number for {what}, found '{}'", clip(token)),
        )
    })
}

/// Shortens a token for an error message.
pub fn clip(s: &str) -> String {
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s.to_string()
    }
}

/// Checks three coordinates are finite.
pub fn check_finite(path: &Path, line: usize, v: [f64; 3], what: &str) -> Result<()> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(Error::syntax(
            path,
            Location::Line(line),
            format!(
                "{what} has a non-finite coordinate ({}, {}, {})",
                v[0], v[1], v[2]
            ),
        ))
    }
}
