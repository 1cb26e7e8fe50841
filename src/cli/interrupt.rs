//! Clean stop on Ctrl-C (SIGINT), SIGTERM and SIGHUP: the handler deletes the temporary files
//! the atomic writer has open ([`crate::io::atomic`]), so an interrupted run leaves neither a
//! partial output nor a stray temporary file, and exits with 130 (the shell's code for SIGINT).
//! Outputs already renamed into place are complete and stay.

/// Installs the handler once per process; a failure (a handler already set by an embedding
/// program) is ignored: the default signal action then applies.
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        let _held = crate::io::atomic::remove_live_temp_files_and_hold();
        eprintln!("scansurf: interrupted; no output written for the unfinished step");
        std::process::exit(130);
    });
}
