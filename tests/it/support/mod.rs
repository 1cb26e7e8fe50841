//! Helpers shared by integration tests.
pub mod scanner_writers;

use std::path::PathBuf;

/// A file of the shared test data: `$SCANSURF_SHARED_DATA/name` when that variable is set,
/// else `../shared/data/name` next to the crate (where CI puts it); `None` when absent.
pub fn shared_data(name: &str) -> Option<PathBuf> {
    let dir = match std::env::var_os("SCANSURF_SHARED_DATA") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
    };
    let p = dir.join(name);
    p.exists().then_some(p)
}
