//! Atomic output: the data goes to a temporary file in the target's own directory (so the
//! final rename never crosses file systems), is flushed and synced, and only then renamed over
//! the target. A failure or an interrupted run leaves the target untouched and removes the
//! temporary file (tempfile deletes it on drop).
//!
//! Drop does not run when a signal ends the process, so every live temporary file is also listed
//! in [`LIVE`]: the Ctrl-C handler ([`crate::cli::interrupt`]) deletes them and exits. The list's
//! lock is held across the final rename, so an interrupt either sees the output complete or
//! removes the temporary file before the rename: never a partial target. (SIGKILL cannot be
//! caught: a kill inside the few milliseconds of writing can leave a hidden `.NAME.*.tmp`.)

use crate::error::{Error, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files being written now (removed by the interrupt handler).
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Deletes every live temporary file and keeps the list locked, so no writer renames one into
/// place afterwards; call only right before the process exits (the interrupt handler).
pub fn remove_live_temp_files_and_hold() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    let guard = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    for p in guard.iter() {
        let _ = std::fs::remove_file(p);
    }
    guard
}

/// Unlists a temporary file when it is dropped or persisted.
struct Listed(PathBuf);

impl Listed {
    fn new(p: &Path) -> Listed {
        LIVE.lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(p.to_path_buf());
        Listed(p.to_path_buf())
    }
}

impl Drop for Listed {
    fn drop(&mut self) {
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = live.iter().position(|p| *p == self.0) {
            live.swap_remove(i);
        }
    }
}

/// The directory `path` would be written in; errors, naming the file, when `path` is a
/// directory or its directory does not exist. Commands call it on their outputs before they
/// start, so a typo in a path does not cost a whole run.
pub fn check_target(path: &Path) -> Result<std::path::PathBuf> {
    if path.is_dir() {
        return Err(Error::content(
            path,
            "is a directory; give an output file name",
        ));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(Error::content(
            path,
            format!("output directory {} does not exist", dir.display()),
        ));
    }
    Ok(dir)
}

/// Writes `path` through `body`, atomically.
pub fn write_atomic<F>(path: &Path, body: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let dir = check_target(path)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    // Declared before `tmp` so it is dropped after it: the file is listed for as long as it exists.
    let listed: Listed;
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempfile_in(&dir)
        .map_err(|e| Error::io(path, e))?;
    listed = Listed::new(tmp.path());
    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        body(&mut w).map_err(|e| Error::io(path, e))?;
        w.flush().map_err(|e| Error::io(path, e))?;
    }
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    // tempfile creates 0600 files; give the output the target's old permissions, or the usual
    // rw-r--r-- for a new file.
    #[cfg(unix)]
    {
        let perms = match std::fs::metadata(path) {
            Ok(m) => m.permissions(),
            Err(_) => default_permissions(),
        };
        tmp.as_file()
            .set_permissions(perms)
            .map_err(|e| Error::io(path, e))?;
    }
    // Rename under the list's lock: an interrupt waits for it, or came first and removed `tmp`.
    let renamed = {
        let _live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        tmp.persist(path)
    };
    drop(listed);
    renamed.map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

#[cfg(unix)]
fn default_permissions() -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt;
    std::fs::Permissions::from_mode(0o644)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failure_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.ply");
        let r = write_atomic(&target, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn success_replaces_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.txt");
        std::fs::write(&target, b"old").unwrap();
        write_atomic(&target, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn missing_directory_is_an_error() {
        let r = write_atomic(Path::new("/nonexistent-dir-xyz/out.ply"), |w| {
            w.write_all(b"x")
        });
        let msg = r.unwrap_err().to_string();
        assert!(msg.contains("does not exist"), "{msg}");
    }
}
