//! Fuzzes the PLY reader on in-memory bytes: any input must give `Ok` with a mesh that passes
//! `io::validate`, or an `Err`; never a panic, a hang or an allocation the bytes cannot back.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.ply");
    if let Ok(mesh) = scansurf::io::ply::parse(path, data) {
        scansurf::io::validate(path, &mesh).expect("reader output passes validate");
    }
});
