//! The memory budget (`--max-memory`): large allocations whose size comes from the input (a
//! file's declared point count, a voxel grid's cell count) are estimated and checked against it
//! before they are made, so a hostile header or too fine a grid gives a clear error instead of
//! an out-of-memory kill.
//!
//! The library default is no limit; the command line sets 3/4 of the physical memory
//! ([`default_max_memory`], from `/proc/meminfo`) unless `--max-memory` says otherwise.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicU64, Ordering};

static MAX_MEMORY: AtomicU64 = AtomicU64::new(u64::MAX);

/// Sets the budget in bytes for the whole process.
pub fn set_max_memory(bytes: u64) {
    MAX_MEMORY.store(bytes, Ordering::Relaxed);
}

/// The budget in bytes (`u64::MAX`: none).
pub fn max_memory() -> u64 {
    MAX_MEMORY.load(Ordering::Relaxed)
}

/// 3/4 of `MemTotal` in `/proc/meminfo`; `None` where that file is missing or unreadable.
pub fn default_max_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: u64 = text
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib.saturating_mul(1024) / 4 * 3)
}

/// Parses a size: a number of bytes with an optional unit K, M, G, T (powers of 1024; `KB`,
/// `KiB`, lower case accepted), e.g. `8G`, `1.5GiB`, `500M`, `1000000`.
pub fn parse_size(s: &str) -> Result<u64> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num
        .trim()
        .parse()
        .map_err(|_| Error::InvalidOption(format!("--max-memory {s}: expected e.g. 8G or 500M")))?;
    let mult = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1u64,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        other => {
            return Err(Error::InvalidOption(format!(
                "--max-memory {s}: unknown unit '{other}' (use K, M, G or T)"
            )))
        }
    };
    let bytes = value * mult as f64;
    if !(bytes.is_finite() && bytes >= 1.0) {
        return Err(Error::InvalidOption(format!(
            "--max-memory {s}: must be a positive size"
        )));
    }
    Ok(bytes.min(u64::MAX as f64) as u64)
}

/// A size in human units (GiB/MiB/KiB with one decimal).
pub fn human(bytes: f64) -> String {
    const UNITS: [(&str, f64); 3] = [("GiB", 1073741824.0), ("MiB", 1048576.0), ("KiB", 1024.0)];
    for (u, m) in UNITS {
        if bytes >= m {
            return format!("{:.1} {u}", bytes / m);
        }
    }
    format!("{bytes:.0} B")
}

/// Fails with [`Error::Limit`] when `bytes` (an estimate, f64 so that absurd claims do not
/// overflow) exceed the budget. `what` names the allocation, `hint` says how to shrink it.
pub fn check(what: &str, bytes: f64, hint: &str) -> Result<()> {
    let max = max_memory();
    if max == u64::MAX || bytes <= max as f64 {
        return Ok(());
    }
    Err(Error::Limit(format!(
        "{what} would need about {}, more than --max-memory {}; {hint}",
        human(bytes),
        human(max as f64)
    )))
}

/// Checks a surface-following (sparse) grid of cell `h` over a box of extent `ext`: it holds the
/// cells the surface crosses, estimated as the box's surface area over h^2 (a closed surface
/// inside the box has less area than it, up to folds), at `bytes_per_cell` each.
pub fn check_surface_grid(ext: [f64; 3], h: f64, bytes_per_cell: f64) -> Result<()> {
    let area = 2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[2] * ext[0]);
    let cells = area / (h * h) + 1.0;
    check(
        &format!("a grid of cell size {h:.3e} ({cells:.2e} surface cells)"),
        cells * bytes_per_cell,
        "use a coarser --patch-size or fewer --patches (fit), a coarser --resolution \
         (reconstruct), or --max-points",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_sizes() {
        assert_eq!(parse_size("1000").unwrap(), 1000);
        assert_eq!(parse_size("8G").unwrap(), 8 << 30);
        assert_eq!(parse_size("1.5GiB").unwrap(), 3 << 29);
        assert_eq!(parse_size("500m").unwrap(), 500 << 20);
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("lots").is_err());
        assert!(parse_size("3X").is_err());
    }

    #[test]
    fn meminfo_gives_a_plausible_default() {
        if let Some(m) = default_max_memory() {
            assert!(m > 1 << 26, "{m}");
        }
    }

    #[test]
    fn check_names_the_allocation_and_the_way_out() {
        // No limit by default in the library.
        assert!(check("x", 1e30, "").is_ok());
        let msg = format!(
            "{}",
            Error::Limit("a voxel grid would need about 2.0 GiB".into())
        );
        assert!(msg.contains("voxel grid"));
        assert_eq!(human(3.0 * 1073741824.0), "3.0 GiB");
        assert_eq!(human(512.0), "512 B");
    }
}
