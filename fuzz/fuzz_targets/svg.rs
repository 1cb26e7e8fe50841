//! Fuzzes the sketch drawing reader (SVG paths and JSON polylines) on in-memory bytes: any input
//! must give `Ok` with finite contours or an `Err`; never a panic, a hang or a huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    for name in ["fuzz.svg", "fuzz.json"] {
        let path = Path::new(name);
        if let Ok(d) = scansurf::sketch::input::parse_drawing(path, data.to_vec()) {
            assert!(d
                .contours
                .iter()
                .flatten()
                .all(|p| p.x.is_finite() && p.y.is_finite()));
        }
    }
});
