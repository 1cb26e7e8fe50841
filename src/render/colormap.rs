//! Colour maps for scalar fields (deviation) and the scale that maps values onto them.
//!
//! Two maps, each piecewise linear in sRGB through five hand-picked stops:
//! - `Diverging`: blue - near-white - red, for signed values centred on zero (inside/outside).
//!   The middle is a light grey rather than pure white so the surface shading stays visible.
//! - `Sequential`: dark violet - blue - teal - green - yellow (viridis-like: lightness rises
//!   monotonically, readable in greyscale and by colour-blind viewers), for magnitudes.
//!
//! Hand-written rather than a colour crate: two maps of five stops each are a few lines.

use crate::error::{Error, Result};

/// A colour map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorMap {
    Diverging,
    Sequential,
}

const DIVERGING: [[f32; 3]; 5] = [
    [0.16, 0.24, 0.68],
    [0.42, 0.60, 0.93],
    [0.90, 0.90, 0.90],
    [0.95, 0.56, 0.42],
    [0.70, 0.08, 0.13],
];

const SEQUENTIAL: [[f32; 3]; 5] = [
    [0.27, 0.00, 0.33],
    [0.23, 0.32, 0.55],
    [0.13, 0.57, 0.55],
    [0.37, 0.79, 0.38],
    [0.99, 0.91, 0.14],
];

impl ColorMap {
    /// sRGB colour (components in [0, 1]) at `t` in [0, 1] (clamped; NaN maps to 0.5).
    pub fn srgb(self, t: f64) -> [f32; 3] {
        let stops = match self {
            ColorMap::Diverging => &DIVERGING,
            ColorMap::Sequential => &SEQUENTIAL,
        };
        let t = if t.is_nan() { 0.5 } else { t.clamp(0.0, 1.0) } as f32;
        if t >= 1.0 {
            return stops[stops.len() - 1];
        }
        let x = t * (stops.len() - 1) as f32;
        let i = (x.floor() as usize).min(stops.len() - 2);
        let f = x - i as f32;
        let (a, b) = (stops[i], stops[i + 1]);
        [0, 1, 2].map(|k| a[k] + f * (b[k] - a[k]))
    }

    /// The same as 8-bit sRGB.
    pub fn srgb8(self, t: f64) -> [u8; 3] {
        self.srgb(t).map(|c| (c * 255.0).round() as u8)
    }
}

/// Maps scalar values to colours: `t = (v - min) / (max - min)`, clamped to [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColorScale {
    pub min: f64,
    pub max: f64,
    pub map: ColorMap,
}

impl ColorScale {
    /// A diverging scale over [-`limit`, `limit`].
    pub fn symmetric(limit: f64) -> Result<ColorScale> {
        if !(limit.is_finite() && limit > 0.0) {
            return Err(Error::InvalidOption(format!(
                "colour scale limit must be positive, got {limit}"
            )));
        }
        Ok(ColorScale {
            min: -limit,
            max: limit,
            map: ColorMap::Diverging,
        })
    }

    /// A sequential scale over [`min`, `max`].
    pub fn sequential(min: f64, max: f64) -> Result<ColorScale> {
        if !(min.is_finite() && max.is_finite() && max > min) {
            return Err(Error::InvalidOption(format!(
                "colour scale needs min < max, got [{min}, {max}]"
            )));
        }
        Ok(ColorScale {
            min,
            max,
            map: ColorMap::Sequential,
        })
    }

    /// The scale a set of values calls for: values of both signs (signed deviation) get a
    /// diverging map symmetric about zero out to the largest magnitude; one-signed values
    /// (distances) a sequential map from zero (or their minimum, if they do not reach zero)
    /// to their maximum. Non-finite values are skipped; all-equal values get a range around
    /// them. Errors when no value is finite.
    pub fn auto(values: &[f64]) -> Result<ColorScale> {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in values.iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if lo > hi {
            return Err(Error::Degenerate(
                "no finite value to colour the surface with".into(),
            ));
        }
        if lo < 0.0 && hi > 0.0 {
            return ColorScale::symmetric(lo.abs().max(hi));
        }
        let (lo, hi) = if lo >= 0.0 {
            (0.0, hi)
        } else {
            (lo, 0.0) // all negative: up to zero
        };
        if hi > lo {
            ColorScale::sequential(lo, hi)
        } else {
            let pad = if lo == 0.0 { 1.0 } else { lo.abs() * 0.5 };
            ColorScale::sequential(lo - pad, hi + pad)
        }
    }

    /// Position of `v` on the map, in [0, 1] (NaN stays NaN).
    pub fn t(&self, v: f64) -> f64 {
        ((v - self.min) / (self.max - self.min)).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_hit_their_stops_and_clamp() {
        assert_eq!(ColorMap::Diverging.srgb(0.0), DIVERGING[0]);
        assert_eq!(ColorMap::Diverging.srgb(1.0), DIVERGING[4]);
        assert_eq!(ColorMap::Diverging.srgb(-3.0), DIVERGING[0]);
        assert_eq!(ColorMap::Sequential.srgb(0.5), SEQUENTIAL[2]);
        assert_eq!(ColorMap::Diverging.srgb(f64::NAN), DIVERGING[2]);
        // Sequential lightness (a rough luma) increases monotonically.
        let luma = |c: [f32; 3]| 0.3 * c[0] + 0.59 * c[1] + 0.11 * c[2];
        let mut last = -1.0;
        for i in 0..=100 {
            let l = luma(ColorMap::Sequential.srgb(i as f64 / 100.0));
            assert!(l > last, "at {i}");
            last = l;
        }
    }

    #[test]
    fn auto_scales() {
        let s = ColorScale::auto(&[-0.2, 0.05, 0.1, f64::NAN]).unwrap();
        assert_eq!((s.min, s.max, s.map), (-0.2, 0.2, ColorMap::Diverging));
        assert_eq!(s.t(0.0), 0.5);
        let s = ColorScale::auto(&[0.5, 2.0]).unwrap();
        assert_eq!((s.min, s.max, s.map), (0.0, 2.0, ColorMap::Sequential));
        let s = ColorScale::auto(&[0.0, 0.0]).unwrap();
        assert!(s.max > s.min);
        assert!(ColorScale::auto(&[f64::NAN]).is_err());
        assert!(ColorScale::auto(&[]).is_err());
        assert!(ColorScale::symmetric(0.0).is_err());
        assert!(ColorScale::sequential(1.0, 1.0).is_err());
    }
}
