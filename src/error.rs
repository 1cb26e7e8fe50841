//! Typed errors. Every error that concerns a file names it; syntax errors also name the line
//! (text formats) or the byte offset (binary formats) where reading broke.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file a problem was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number of a text file.
    Line(usize),
    /// 0-based byte offset into a binary file.
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// The crate's error type.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused to open, read or write a file.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file's bytes do not follow its format.
    #[error("{}: {location}: {message}", path.display())]
    Syntax {
        path: PathBuf,
        location: Location,
        message: String,
    },
    /// The file is well formed but its content cannot be used (NaN coordinates, face indices past
    /// the vertex list, no points at all, ...).
    #[error("{}: {message}", path.display())]
    Content { path: PathBuf, message: String },
    /// The file's format is not one scansurf reads or writes.
    #[error("{}: {message}", path.display())]
    Unsupported { path: PathBuf, message: String },
    /// Input data that an algorithm cannot work with (too few points, degenerate geometry).
    #[error("{0}")]
    Degenerate(String),
    /// A user-supplied option is out of range or inconsistent.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// An allocation the input asks for exceeds the memory budget (`--max-memory`,
    /// [`crate::limits`]).
    #[error("{0}")]
    Limit(String),
    /// A numerical method did not converge or met a singular system.
    #[error("numerical failure: {0}")]
    Numerical(String),
}

/// Result alias used across the crate.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    pub fn syntax(path: &Path, location: Location, message: impl Into<String>) -> Self {
        Error::Syntax {
            path: path.to_path_buf(),
            location,
            message: message.into(),
        }
    }
    pub fn content(path: &Path, message: impl Into<String>) -> Self {
        Error::Content {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
    pub fn unsupported(path: &Path, message: impl Into<String>) -> Self {
        Error::Unsupported {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}
