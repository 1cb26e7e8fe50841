//! A fast hasher for integer keys (grid cells, vertex and edge indices).
//!
//! std's default SipHash resists adversarially chosen keys, which grid coordinates and mesh
//! indices are not; it costs a large share of marching cubes and subdivision. This hasher mixes
//! each written integer with a multiply-rotate step and finishes with the splitmix64 finalizer,
//! enough to spread structured keys over the table. Hand-written because no hashing crate is a
//! dependency and the code is a few lines.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// Multiply-rotate hasher for integer keys.
#[derive(Debug, Default, Clone, Copy)]
pub struct IntHasher(u64);

impl IntHasher {
    #[inline]
    fn mix(&mut self, x: u64) {
        self.0 = (self.0 ^ x)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(29);
    }
}

impl Hasher for IntHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.mix(u64::from_le_bytes(b));
        }
    }
    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.mix(i as u64);
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.mix(i as u64);
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.mix(i);
    }
    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.mix(i as u64);
    }
    #[inline]
    fn finish(&self) -> u64 {
        // splitmix64 finalizer.
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// `HashMap` with [`IntHasher`].
pub type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<IntHasher>>;
/// `HashSet` with [`IntHasher`].
pub type IntSet<K> = HashSet<K, BuildHasherDefault<IntHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_work_and_spread() {
        let mut m: IntMap<(u32, u32), u32> = IntMap::default();
        for i in 0..1000u32 {
            m.insert((i, i + 1), i);
        }
        assert_eq!(m[&(500, 501)], 500);
        assert_eq!(m.len(), 1000);
        // Consecutive keys land in different low bits.
        let h = |x: u64| {
            let mut s = IntHasher::default();
            s.write_u64(x);
            s.finish() & 1023
        };
        let mut seen: IntSet<u64> = IntSet::default();
        for x in 0..1024 {
            seen.insert(h(x));
        }
        assert!(seen.len() > 600);
    }
}
