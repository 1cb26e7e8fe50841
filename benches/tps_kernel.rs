//! The thin-plate kernel sums that dominate `fit` (`implicit::tps_kernel`): nanoseconds per
//! centre for the value with its gradient, the value alone, and one column of the RBF system
//! matrix, on 60 centres (a typical fine cell's RBF) and 1,000 query points around them.
//!
//!     cargo bench --bench tps_kernel
//!
//! Prints the best of five passes. Figures go to docs/BENCHMARKS.md.

mod common;
use common::best_of;
use nalgebra::Vector3;
use scansurf::implicit::tps_kernel::{phi_column, Centres};
use std::hint::black_box;

/// Deterministic numbers in [0, 1) (a 64-bit LCG).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn main() {
    const CENTRES: usize = 60;
    const QUERIES: usize = 1000;
    const PASSES: usize = 200;
    let mut r = Lcg(12345);
    let c: Vec<Vector3<f64>> = (0..CENTRES)
        .map(|_| Vector3::new(r.next(), r.next(), r.next()))
        .collect();
    let lambda: Vec<f64> = (0..CENTRES).map(|_| r.next() - 0.5).collect();
    let y: Vec<[f64; 3]> = (0..QUERIES)
        .map(|_| [r.next(), r.next(), r.next()])
        .collect();
    let k = Centres::new(&c, &lambda);
    let per = (PASSES * QUERIES * CENTRES) as f64;

    let t = best_of(5, || {
        let mut acc = 0.0;
        for _ in 0..PASSES {
            for q in &y {
                let (s, g) = k.value_and_gradient(black_box(*q));
                acc += s + g[0];
            }
        }
        black_box(acc);
    });
    println!("value and gradient: {:.2} ns per centre", t / per * 1e9);

    let t = best_of(5, || {
        let mut acc = 0.0;
        for _ in 0..PASSES {
            for q in &y {
                acc += k.value(black_box(*q));
            }
        }
        black_box(acc);
    });
    println!("value:              {:.2} ns per centre", t / per * 1e9);

    let (cx, cy, cz): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        c.iter().map(|p| p.x).collect(),
        c.iter().map(|p| p.y).collect(),
        c.iter().map(|p| p.z).collect(),
    );
    let mut out = vec![0.0; CENTRES];
    let t = best_of(5, || {
        for _ in 0..PASSES {
            for q in &y {
                phi_column(&cx, &cy, &cz, black_box(*q), &mut out);
                black_box(&out);
            }
        }
    });
    println!("matrix column:      {:.2} ns per entry", t / per * 1e9);
}
