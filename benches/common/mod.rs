//! What the bench binaries share.

use std::time::Instant;

/// The shortest of `n` timed runs of `f`, in seconds.
pub fn best_of<F: FnMut()>(n: usize, mut f: F) -> f64 {
    (0..n)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}
