//! The thin-plate kernel sum of an RBF (seed 003 eq. 1, seed 004 eq. 3) and its gradient, over
//! all centres at once:
//!
//! ```text
//! s(y)      = sum_j lambda_j phi(|y - c_j|),  phi(r) = r^2 log r = 0.5 r^2 ln(r^2)
//! grad s(y) = sum_j lambda_j (y - c_j) (ln(r_j^2) + 1)
//! ```
//!
//! This is where `fit` spends most of its time (every evaluation of the partition-of-unity
//! implicit sums two or three RBFs of about 60 centres: one `ln` per centre), so the centres
//! are stored as four coordinate arrays padded to a multiple of [`LANES`] and summed
//! lane-parallel with a branch-free `ln` ([`ln`]). On x86-64 with AVX2 and FMA the sums run on
//! 4-wide registers through explicit intrinsics ([`avx2`]); elsewhere a portable build performs
//! the same operations one lane at a time.
//!
//! **Determinism.** Both builds perform the same IEEE operations in the same order: four
//! partial sums, one per lane, added as (s0 + s1) + (s2 + s3), and the same fused
//! multiply-adds (`f64::mul_add` in the portable build, correctly rounded on every platform,
//! in hardware or by libm), so results are bit-identical with and without AVX2 and the STEP
//! and IGES files stay byte-identical across machines. The `ln` polynomial is evaluated by
//! Estrin's scheme (independent products, a short dependency chain) rather than Horner's:
//! with the fused multiply-adds the bunny's kernel sums take 27 % less time per centre
//! (docs/BENCHMARKS.md, session 10).
//!
//! Hand-written rather than a crate: the SIMD math crates either need nightly (`std::simd`)
//! or return a different `ln` per instruction set, which would break the determinism above.

/// Centres summed together per step (the width of an AVX2 register of `f64`).
pub const LANES: usize = 4;

/// RBF centres and weights as coordinate arrays, padded with zero-weight centres at the
/// origin to a multiple of [`LANES`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Centres {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    lambda: Vec<f64>,
    len: usize,
}

/// Whether this CPU runs the [`avx2`] build (AVX2 and FMA; std caches the answer).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn has_avx2_fma() -> bool {
    std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
}

impl Centres {
    /// Centres `c` with weights `lambda` (equal lengths).
    pub fn new(c: &[nalgebra::Vector3<f64>], lambda: &[f64]) -> Centres {
        debug_assert_eq!(c.len(), lambda.len());
        let len = c.len().min(lambda.len());
        let padded = len.div_ceil(LANES) * LANES;
        let coord = |k: usize| -> Vec<f64> {
            let mut v: Vec<f64> = c[..len].iter().map(|p| p[k]).collect();
            v.resize(padded, 0.0);
            v
        };
        let mut l = lambda[..len].to_vec();
        l.resize(padded, 0.0);
        Centres {
            x: coord(0),
            y: coord(1),
            z: coord(2),
            lambda: l,
            len,
        }
    }

    /// The centres [`LANES`] at a time: x, y, z and lambda blocks.
    #[inline(always)]
    fn blocks(&self) -> impl Iterator<Item = (&[f64], &[f64], &[f64], &[f64])> {
        self.x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES))
            .zip(self.lambda.chunks_exact(LANES))
            .map(|(((x, y), z), l)| (x, y, z, l))
    }

    /// Number of (unpadded) centres.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no centres.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The kernel sum s(y) (module doc).
    pub fn value(&self, y: [f64; 3]) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if has_avx2_fma() {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return unsafe { avx2::value(self, y) };
        }
        value_lanes(self, y)
    }

    /// The kernel sum s(y) and its gradient (module doc).
    pub fn value_and_gradient(&self, y: [f64; 3]) -> (f64, [f64; 3]) {
        #[cfg(target_arch = "x86_64")]
        if has_avx2_fma() {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return unsafe { avx2::value_and_gradient(self, y) };
        }
        value_and_gradient_lanes(self, y)
    }
}

/// One column of the RBF system matrix (seed 003 eq. 6): `out[i] = phi(|c_i - y|)` for the
/// centres with coordinates `x[i], y[i], z[i]`, vectorized like the sums; 0 where c_i = y.
pub fn phi_column(cx: &[f64], cy: &[f64], cz: &[f64], y: [f64; 3], out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked just above).
        return unsafe { avx2::phi_column(cx, cy, cz, y, out) };
    }
    phi_column_lanes(cx, cy, cz, y, out)
}

/// Squared distance |(dx, dy, dz)|^2 = fma(dx, dx, fma(dy, dy, dz dz)) as the kernel forms it.
#[inline(always)]
fn dist2(dx: f64, dy: f64, dz: f64) -> f64 {
    dx.mul_add(dx, dy.mul_add(dy, dz * dz))
}

/// phi(r) = 0.5 r^2 ln(r^2) of a squared distance r2 > 0, as the kernel forms it.
#[inline(always)]
fn phi_of(r2: f64, lr: f64) -> f64 {
    0.5 * r2 * lr
}

#[inline(always)]
fn phi_column_lanes(cx: &[f64], cy: &[f64], cz: &[f64], y: [f64; 3], out: &mut [f64]) {
    for (((o, &x0), &y0), &z0) in out.iter_mut().zip(cx).zip(cy).zip(cz) {
        let r2 = dist2(y[0] - x0, y[1] - y0, y[2] - z0);
        let v = phi_of(r2, ln(r2.max(f64::MIN_POSITIVE)));
        *o = if r2 > 0.0 { v } else { 0.0 };
    }
}

/// Squared distance, kept above the smallest normal number so that `ln` stays finite; a
/// centre at y itself then contributes 0.5 * 2.2e-308 * (-708) to s (below any double's
/// rounding of a non-zero sum) and exactly 0 to the gradient (y - c = 0).
#[inline(always)]
fn r2_of(dx: f64, dy: f64, dz: f64) -> f64 {
    dist2(dx, dy, dz).max(f64::MIN_POSITIVE)
}

#[inline(always)]
fn reduce(s: [f64; LANES]) -> f64 {
    (s[0] + s[1]) + (s[2] + s[3])
}

fn value_lanes(c: &Centres, y: [f64; 3]) -> f64 {
    let mut s = [0.0; LANES];
    for (cx, cy, cz, l) in c.blocks() {
        for k in 0..LANES {
            let r2 = r2_of(y[0] - cx[k], y[1] - cy[k], y[2] - cz[k]);
            s[k] = l[k].mul_add(phi_of(r2, ln(r2)), s[k]);
        }
    }
    reduce(s)
}

fn value_and_gradient_lanes(c: &Centres, y: [f64; 3]) -> (f64, [f64; 3]) {
    let mut s = [0.0; LANES];
    let mut gx = [0.0; LANES];
    let mut gy = [0.0; LANES];
    let mut gz = [0.0; LANES];
    for (cx, cy, cz, l) in c.blocks() {
        for k in 0..LANES {
            let (dx, dy, dz) = (y[0] - cx[k], y[1] - cy[k], y[2] - cz[k]);
            let r2 = r2_of(dx, dy, dz);
            let lr = ln(r2);
            s[k] = l[k].mul_add(phi_of(r2, lr), s[k]);
            let t = l[k] * (lr + 1.0);
            gx[k] = dx.mul_add(t, gx[k]);
            gy[k] = dy.mul_add(t, gy[k]);
            gz[k] = dz.mul_add(t, gz[k]);
        }
    }
    (reduce(s), [reduce(gx), reduce(gy), reduce(gz)])
}

const SQRT_2: f64 = std::f64::consts::SQRT_2;
/// ln 2 split so that e * LN2_HI is exact for |e| < 2^11 (Cody & Waite; fdlibm's values,
/// 6.93147180369123816490e-01 and 1.90821492927058770002e-10).
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
/// 2^52 + 1023: (2^52 + biased exponent) - this = unbiased exponent, exactly.
const EXP_MAGIC: f64 = 4_503_599_627_371_519.0;
/// Coefficients 2 / (2k + 1), k = 1..9, of the atanh series below.
const C3: f64 = 2.0 / 3.0;
const C5: f64 = 2.0 / 5.0;
const C7: f64 = 2.0 / 7.0;
const C9: f64 = 2.0 / 9.0;
const C11: f64 = 2.0 / 11.0;
const C13: f64 = 2.0 / 13.0;
const C15: f64 = 2.0 / 15.0;
const C17: f64 = 2.0 / 17.0;
const C19: f64 = 2.0 / 19.0;

/// Natural logarithm of a positive normal double, branch-free, within 2 ulp of `f64::ln`
/// (tested below).
///
/// ```text
/// x = m 2^e,  m in [sqrt(1/2), sqrt(2)),  s = (m - 1) / (m + 1),  |s| <= 0.172
/// ln x = e ln 2 + 2 atanh(s) = e ln 2 + 2 s + s z P(z),  z = s^2,
/// P(z) = 2/3 + 2/5 z + ... + 2/19 z^8   (Estrin: pairs, then pairs of pairs)
/// ```
///
/// The series is cut after s^19: the next term is below 2.4e-17 of the sum. Zero, negative,
/// subnormal, infinite or NaN arguments give unspecified finite or NaN results (the callers
/// pass r^2 clamped to the smallest normal number). [`avx2::ln`] is the same sequence of
/// operations on four lanes.
#[inline(always)]
pub fn ln(x: f64) -> f64 {
    let bits = x.to_bits();
    let m1 = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    let big = m1 >= SQRT_2;
    let m = if big { 0.5 * m1 } else { m1 };
    let eb = (bits >> 52) + big as u64;
    let e = f64::from_bits(0x4330_0000_0000_0000 | eb) - EXP_MAGIC;
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let z2 = z * z;
    let z4 = z2 * z2;
    let z8 = z4 * z4;
    let a0 = z.mul_add(C5, C3);
    let a1 = z.mul_add(C9, C7);
    let a2 = z.mul_add(C13, C11);
    let a3 = z.mul_add(C17, C15);
    let b0 = z2.mul_add(a1, a0);
    let b1 = z2.mul_add(a3, a2);
    let c0 = z4.mul_add(b1, b0);
    let p = z8.mul_add(C19, c0);
    let r = s * z * p;
    e.mul_add(LN2_HI, e.mul_add(LN2_LO, r) + (s + s))
}

/// The kernel on 4-wide AVX2 registers with fused multiply-adds: the portable functions above,
/// operation for operation (module doc: determinism).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use std::arch::x86_64::*;

    /// [`super::ln`] of four lanes.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn ln(x: __m256d) -> __m256d {
        let c = |v: f64| _mm256_set1_pd(v);
        let bits = _mm256_castpd_si256(x);
        let m1 = _mm256_or_pd(
            _mm256_and_pd(
                x,
                _mm256_castsi256_pd(_mm256_set1_epi64x(0x000f_ffff_ffff_ffff)),
            ),
            _mm256_castsi256_pd(_mm256_set1_epi64x(0x3ff0_0000_0000_0000)),
        );
        let big = _mm256_cmp_pd::<_CMP_GE_OQ>(m1, c(SQRT_2));
        let m = _mm256_blendv_pd(m1, _mm256_mul_pd(c(0.5), m1), big);
        // big is all ones (-1) where set: subtracting it adds 1 to the biased exponent.
        let eb = _mm256_sub_epi64(_mm256_srli_epi64::<52>(bits), _mm256_castpd_si256(big));
        let e = _mm256_sub_pd(
            _mm256_castsi256_pd(_mm256_or_si256(
                _mm256_set1_epi64x(0x4330_0000_0000_0000),
                eb,
            )),
            c(EXP_MAGIC),
        );
        let one = c(1.0);
        let s = _mm256_div_pd(_mm256_sub_pd(m, one), _mm256_add_pd(m, one));
        let z = _mm256_mul_pd(s, s);
        let z2 = _mm256_mul_pd(z, z);
        let z4 = _mm256_mul_pd(z2, z2);
        let z8 = _mm256_mul_pd(z4, z4);
        let a0 = _mm256_fmadd_pd(z, c(C5), c(C3));
        let a1 = _mm256_fmadd_pd(z, c(C9), c(C7));
        let a2 = _mm256_fmadd_pd(z, c(C13), c(C11));
        let a3 = _mm256_fmadd_pd(z, c(C17), c(C15));
        let b0 = _mm256_fmadd_pd(z2, a1, a0);
        let b1 = _mm256_fmadd_pd(z2, a3, a2);
        let c0 = _mm256_fmadd_pd(z4, b1, b0);
        let p = _mm256_fmadd_pd(z8, c(C19), c0);
        let r = _mm256_mul_pd(_mm256_mul_pd(s, z), p);
        _mm256_fmadd_pd(
            e,
            c(LN2_HI),
            _mm256_add_pd(_mm256_fmadd_pd(e, c(LN2_LO), r), _mm256_add_pd(s, s)),
        )
    }

    /// y in all lanes, per coordinate.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn splat3(y: [f64; 3]) -> [__m256d; 3] {
        [
            _mm256_set1_pd(y[0]),
            _mm256_set1_pd(y[1]),
            _mm256_set1_pd(y[2]),
        ]
    }

    /// [`super::dist2`] of four lanes.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn dist2(dx: __m256d, dy: __m256d, dz: __m256d) -> __m256d {
        _mm256_fmadd_pd(dx, dx, _mm256_fmadd_pd(dy, dy, _mm256_mul_pd(dz, dz)))
    }

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn reduce(v: __m256d) -> f64 {
        let mut a = [0.0; LANES];
        // SAFETY: `a` holds four doubles; unaligned store.
        unsafe { _mm256_storeu_pd(a.as_mut_ptr(), v) };
        super::reduce(a)
    }

    /// [`super::phi_of`] of four lanes.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn phi_of(r2: __m256d, lr: __m256d) -> __m256d {
        _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(0.5), r2), lr)
    }

    /// `v[i..i + 4]` in one register (callers pass whole blocks).
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn load4(v: &[f64], i: usize) -> __m256d {
        let b: &[f64; LANES] = v[i..i + LANES]
            .try_into()
            .unwrap_or_else(|_| unreachable!("blocks of LANES"));
        // SAFETY: `b` is four readable doubles; unaligned load.
        unsafe { _mm256_loadu_pd(b.as_ptr()) }
    }

    /// Lane differences y - c of block `i` (four centres from index 4 i), and their weights.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn deltas(c: &Centres, i: usize, y: &[__m256d; 3]) -> [__m256d; 4] {
        let k = i * LANES;
        [
            _mm256_sub_pd(y[0], load4(&c.x, k)),
            _mm256_sub_pd(y[1], load4(&c.y, k)),
            _mm256_sub_pd(y[2], load4(&c.z, k)),
            load4(&c.lambda, k),
        ]
    }

    /// [`super::value_lanes`].
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn value(c: &Centres, y: [f64; 3]) -> f64 {
        let yv = splat3(y);
        let tiny = _mm256_set1_pd(f64::MIN_POSITIVE);
        let mut s = _mm256_setzero_pd();
        for i in 0..c.x.len() / LANES {
            let [dx, dy, dz, l] = deltas(c, i, &yv);
            let r2 = _mm256_max_pd(dist2(dx, dy, dz), tiny);
            s = _mm256_fmadd_pd(l, phi_of(r2, ln(r2)), s);
        }
        reduce(s)
    }

    /// [`super::value_and_gradient_lanes`].
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn value_and_gradient(c: &Centres, y: [f64; 3]) -> (f64, [f64; 3]) {
        let yv = splat3(y);
        let (one, tiny) = (_mm256_set1_pd(1.0), _mm256_set1_pd(f64::MIN_POSITIVE));
        let (mut s, mut gx, mut gy, mut gz) = (
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
        );
        for i in 0..c.x.len() / LANES {
            let [dx, dy, dz, l] = deltas(c, i, &yv);
            let r2 = _mm256_max_pd(dist2(dx, dy, dz), tiny);
            let lr = ln(r2);
            s = _mm256_fmadd_pd(l, phi_of(r2, lr), s);
            let t = _mm256_mul_pd(l, _mm256_add_pd(lr, one));
            gx = _mm256_fmadd_pd(dx, t, gx);
            gy = _mm256_fmadd_pd(dy, t, gy);
            gz = _mm256_fmadd_pd(dz, t, gz);
        }
        (reduce(s), [reduce(gx), reduce(gy), reduce(gz)])
    }

    /// [`super::phi_column_lanes`]: whole blocks of four here, the rest one lane at a time by
    /// the portable code (the same operations).
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn phi_column(cx: &[f64], cy: &[f64], cz: &[f64], y: [f64; 3], out: &mut [f64]) {
        let n = out.len().min(cx.len()).min(cy.len()).min(cz.len());
        let full = n / LANES * LANES;
        let yv = splat3(y);
        let (tiny, zero) = (_mm256_set1_pd(f64::MIN_POSITIVE), _mm256_setzero_pd());
        for i in (0..full).step_by(LANES) {
            let dx = _mm256_sub_pd(yv[0], load4(cx, i));
            let dy = _mm256_sub_pd(yv[1], load4(cy, i));
            let dz = _mm256_sub_pd(yv[2], load4(cz, i));
            let r2 = dist2(dx, dy, dz);
            let v = phi_of(r2, ln(_mm256_max_pd(r2, tiny)));
            // 0 where r2 = 0 (the centre itself).
            let v = _mm256_and_pd(v, _mm256_cmp_pd::<_CMP_GT_OQ>(r2, zero));
            let o: &mut [f64; LANES] = (&mut out[i..i + LANES])
                .try_into()
                .unwrap_or_else(|_| unreachable!("blocks of LANES"));
            // SAFETY: `o` is four writable doubles; unaligned store.
            unsafe { _mm256_storeu_pd(o.as_mut_ptr(), v) };
        }
        super::phi_column_lanes(
            &cx[full..n],
            &cy[full..n],
            &cz[full..n],
            y,
            &mut out[full..n],
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn ulps(a: f64, b: f64) -> f64 {
        let spacing = f64::EPSILON * b.abs().max(f64::MIN_POSITIVE);
        (a - b).abs() / spacing
    }

    #[test]
    fn ln_is_within_two_ulp_of_std() {
        let mut worst: f64 = 0.0;
        let mut x = f64::MIN_POSITIVE;
        // Every binade, 4,001 points each, plus the neighbourhood of 1 where ln -> 0.
        while x < 1e300 {
            for k in 0..=4000 {
                let v = x * (1.0 + k as f64 / 4000.0);
                worst = worst.max(ulps(ln(v), v.ln()));
            }
            x *= 2.0;
        }
        for k in 1..=20000 {
            for v in [1.0 + k as f64 * 1e-9, 1.0 - k as f64 * 1e-9] {
                // Near 1 ln(v) is tiny: compare with the absolute error the argument's own
                // rounding allows.
                assert!((ln(v) - v.ln()).abs() <= 2.0 * f64::EPSILON * (v - 1.0).abs() + 1e-300);
            }
        }
        assert!(worst <= 2.0, "worst {worst} ulp");
        assert_eq!(ln(1.0), 0.0);
    }

    fn reference(c: &[Vector3<f64>], l: &[f64], y: [f64; 3]) -> (f64, [f64; 3]) {
        let y = Vector3::from(y);
        let (mut s, mut g) = (0.0, Vector3::zeros());
        for (c, l) in c.iter().zip(l) {
            let d = y - c;
            let r2 = d.norm_squared();
            if r2 > 0.0 {
                s += l * 0.5 * r2 * r2.ln();
                g += d * (l * (r2.ln() + 1.0));
            }
        }
        (s, [g.x, g.y, g.z])
    }

    #[test]
    fn sums_match_the_direct_formula_for_every_padding() {
        for n in 1..=11 {
            let c: Vec<Vector3<f64>> = (0..n)
                .map(|i| {
                    let t = i as f64 * 0.7;
                    Vector3::new(t.sin(), (1.3 * t).cos(), 0.2 * t - 0.5)
                })
                .collect();
            let l: Vec<f64> = (0..n).map(|i| (i as f64 - 3.2) * 0.37).collect();
            let k = Centres::new(&c, &l);
            assert_eq!(k.len(), n);
            // Off the centres and exactly on one (phi(0) = 0, no NaN).
            for y in [[0.3, -0.2, 0.1], [c[0].x, c[0].y, c[0].z]] {
                let (s, g) = k.value_and_gradient(y);
                let (rs, rg) = reference(&c, &l, y);
                assert!(
                    (s - rs).abs() <= 1e-14 * (1.0 + rs.abs()),
                    "n {n}: {s} vs {rs}"
                );
                assert_eq!(k.value(y), s);
                for a in 0..3 {
                    assert!((g[a] - rg[a]).abs() <= 1e-13 * (1.0 + rg[a].abs()));
                }
            }
        }
    }

    #[test]
    fn phi_columns_match_the_formula() {
        let c: Vec<[f64; 3]> = (0..13)
            .map(|i| [(i as f64).sin(), (i as f64 * 0.3).cos(), i as f64 * 0.01])
            .collect();
        let (cx, cy, cz): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            c.iter().map(|p| p[0]).collect(),
            c.iter().map(|p| p[1]).collect(),
            c.iter().map(|p| p[2]).collect(),
        );
        let mut out = vec![f64::NAN; c.len()];
        phi_column(&cx, &cy, &cz, c[5], &mut out);
        for (i, p) in c.iter().enumerate() {
            let r2: f64 = (0..3).map(|k| (p[k] - c[5][k]).powi(2)).sum();
            let want = if r2 > 0.0 { 0.5 * r2 * r2.ln() } else { 0.0 };
            assert!((out[i] - want).abs() <= 1e-15 * (1.0 + want.abs()), "{i}");
        }
        assert_eq!(out[5], 0.0);
        let mut portable = vec![0.0; c.len()];
        phi_column_lanes(&cx, &cy, &cz, c[5], &mut portable);
        assert_eq!(out, portable);
    }

    #[test]
    fn vector_and_portable_builds_agree_bit_for_bit() {
        let c: Vec<Vector3<f64>> = (0..37)
            .map(|i| Vector3::new((i as f64).sin(), (i as f64 * 0.3).cos(), i as f64 * 0.01))
            .collect();
        let l: Vec<f64> = (0..37).map(|i| ((i * 7 % 11) as f64) - 5.0).collect();
        let k = Centres::new(&c, &l);
        for i in 0..100 {
            let y = [i as f64 * 0.013 - 0.6, 0.2 - i as f64 * 0.007, 0.05];
            assert_eq!(k.value_and_gradient(y), value_and_gradient_lanes(&k, y));
            assert_eq!(k.value(y), value_lanes(&k, y));
        }
    }
}
