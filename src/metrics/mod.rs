//! Quality measures shared by the commands and their reports.

pub mod deviation;

pub use deviation::{deviation, Deviation, DistanceStats};
