//! scansurf's integration tests, all in one test binary (one link instead of one per file):
//! a module per concept, the shared helpers (`common`, `support`) as modules beside them.
//!
//! Run one module's tests with its path as the filter, e.g.
//! `cargo test --profile fasttest --test it cli_fit::`; `bash scripts/test.sh --quick` skips the
//! long end-to-end fits (tests whose name starts with `slow_`), see docs/DEVELOPING.md.

mod common;
mod support;

mod bad_inputs;
mod cad_roundtrip;
mod cli_close;
mod cli_features;
mod cli_fill_holes;
mod cli_fit;
mod cli_fit_sharp;
mod cli_inspect;
mod cli_reconstruct;
mod cli_render;
mod cli_sketch;
mod cli_smooth;
mod determinism;
mod features;
mod fill_holes_ground_truth;
mod fill_holes_models;
mod fit_scanner;
mod fuzz_regressions;
#[cfg(unix)]
mod interrupt;
mod io_roundtrip;
mod limits;
mod properties;
mod scanner_formats;
