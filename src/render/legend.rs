//! The colour legend: a vertical bar of the colour map at the right of the picture, with tick
//! labels in model units at "nice" values and a title above it.
//!
//! Nice ticks: the step is the smallest of `{1, 2, 2.5, 5} x 10^k` that gives at most
//! `MAX_TICKS` intervals over the scale's range, and the ticks are the step's multiples inside
//! the range. Labels print with just enough decimals for the step, or in exponent form
//! (`2.5e-4`) for very small or large values.

use super::colormap::ColorScale;
use super::font::{draw_text, text_height, text_width};
use super::image::Image;

/// Most intervals between ticks.
const MAX_TICKS: f64 = 8.0;
const INK: [u8; 3] = [40, 40, 40];

/// Where the legend goes in a picture.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendLayout {
    /// Pixels at the right edge kept free of the model.
    pub reserved_width: u32,
    font_scale: u32,
    bar_x: i64,
    bar_y: i64,
    bar_w: i64,
    bar_h: i64,
    ticks: Vec<(f64, String)>,
    title: String,
}

/// The tick values of a range.
pub fn nice_ticks(min: f64, max: f64) -> (Vec<f64>, f64) {
    let range = max - min;
    if !(range.is_finite() && range > 0.0) {
        return (vec![min], 0.0);
    }
    let raw = range / MAX_TICKS;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| range / s <= MAX_TICKS + 1e-9)
        .unwrap_or(10.0 * mag);
    let first = (min / step - 1e-9).ceil() as i64;
    let last = (max / step + 1e-9).floor() as i64;
    let ticks = (first..=last)
        .map(|i| {
            let v = i as f64 * step;
            if v.abs() < step * 1e-9 {
                0.0
            } else {
                v
            }
        })
        .collect();
    (ticks, step)
}

/// A tick label for `v` on a scale with tick spacing `step`.
pub fn format_tick(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let big = v.abs().max(step);
    if step < 1e-3 || big >= 1e5 {
        // Exponent form with the digits the step needs: 2.5e-4, 1e6.
        let digits = ((v.abs().log10().floor() - step.log10().floor()).max(0.0) as usize).min(6);
        let s = format!("{:.*e}", digits, v);
        // Trim trailing zeros of the mantissa: "2.50e-4" -> "2.5e-4".
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            _ => s,
        }
    } else {
        // Decimals to resolve the step (2.5 needs one more than 2).
        let mut decimals = (-step.log10().floor()).max(0.0) as usize;
        let scaled = step * 10f64.powi(decimals as i32);
        if (scaled - scaled.round()).abs() > 1e-6 {
            decimals += 1;
        }
        format!("{:.*}", decimals, v)
    }
}

impl LegendLayout {
    /// Lays out a legend for a `width` x `height` picture.
    pub fn new(width: u32, height: u32, scale: &ColorScale, title: &str) -> LegendLayout {
        let font_scale = ((height as f64 / 400.0).round() as u32).max(1);
        let (values, step) = nice_ticks(scale.min, scale.max);
        let ticks: Vec<(f64, String)> = values
            .into_iter()
            .map(|v| (v, format_tick(v, step)))
            .collect();
        let label_w = ticks
            .iter()
            .map(|(_, s)| text_width(s, font_scale))
            .max()
            .unwrap_or(0) as i64;
        let margin = (width as i64 / 40).max(4);
        let bar_w = (width as i64 / 40).max(6);
        let tick_len = (bar_w / 3).max(2);
        let gap = 2 * font_scale as i64;
        let bar_h = (height as i64 * 3 / 5).max(8);
        let bar_y = (height as i64 - bar_h) / 2 + text_height(font_scale) as i64;
        let reserved = margin + bar_w + tick_len + gap + label_w + margin;
        let bar_x = width as i64 - reserved + margin;
        LegendLayout {
            reserved_width: reserved.clamp(0, width as i64 / 2) as u32,
            font_scale,
            bar_x,
            bar_y,
            bar_w,
            bar_h,
            ticks,
            title: title.to_string(),
        }
    }

    /// Draws the legend for `scale` into `img`.
    pub fn draw(&self, img: &mut Image, scale: &ColorScale) {
        let (x, y, w, h) = (self.bar_x, self.bar_y, self.bar_w, self.bar_h);
        for row in 0..h {
            let t = 1.0 - row as f64 / (h - 1).max(1) as f64;
            img.fill_rect(x, y + row, w, 1, scale.map.srgb8(t));
        }
        // Frame.
        img.fill_rect(x - 1, y - 1, w + 2, 1, INK);
        img.fill_rect(x - 1, y + h, w + 2, 1, INK);
        img.fill_rect(x - 1, y - 1, 1, h + 2, INK);
        img.fill_rect(x + w, y - 1, 1, h + 2, INK);
        let fs = self.font_scale;
        let th = text_height(fs) as i64;
        let tick_len = (w / 3).max(2);
        for (v, label) in &self.ticks {
            let ty = y + ((1.0 - scale.t(*v)) * (h - 1) as f64).round() as i64;
            img.fill_rect(x + w, ty, tick_len, fs.max(1) as i64, INK);
            draw_text(
                img,
                x + w + tick_len + 2 * fs as i64,
                ty - th / 2,
                label,
                fs,
                INK,
            );
        }
        // Title above the bar, kept inside the picture.
        let tw = text_width(&self.title, fs) as i64;
        let tx = (x + w / 2 - tw / 2).min(img.width as i64 - tw - 2).max(0);
        draw_text(img, tx, y - 2 * th - th / 2, &self.title, fs, INK);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::colormap::ColorMap;

    #[test]
    fn ticks_are_nice_and_inside() {
        let (t, s) = nice_ticks(-0.0123, 0.0123);
        assert_eq!(s, 0.005);
        assert_eq!(t, vec![-0.01, -0.005, 0.0, 0.005, 0.01]);
        let (t, s) = nice_ticks(0.0, 1.0);
        assert_eq!(s, 0.2);
        assert_eq!(t.len(), 6);
        let (t, s) = nice_ticks(-0.04, 0.04);
        assert_eq!((t.len(), s), (9, 0.01));
        let (t, _) = nice_ticks(3.0, 3.0);
        assert_eq!(t, vec![3.0]);
        let labels: Vec<String> = [-0.01, -0.005, 0.0, 0.005]
            .iter()
            .map(|&v| format_tick(v, 0.005))
            .collect();
        assert_eq!(labels, ["-0.010", "-0.005", "0", "0.005"]);
        assert_eq!(format_tick(0.25, 0.25), "0.25");
        assert_eq!(format_tick(2.0, 1.0), "2");
        assert_eq!(format_tick(2.5e-4, 5e-5), "2.5e-4");
        assert_eq!(format_tick(-1e-4, 5e-5), "-1e-4");
        assert_eq!(format_tick(2e6, 5e5), "2e6");
    }

    #[test]
    fn legend_draws_a_coloured_bar_and_labels() {
        let scale = ColorScale::symmetric(0.02).unwrap();
        let mut img = Image::new(800, 600, [255; 3]);
        let l = LegendLayout::new(800, 600, &scale, "deviation");
        assert!(
            l.reserved_width > 60 && l.reserved_width < 300,
            "{}",
            l.reserved_width
        );
        l.draw(&mut img, &scale);
        // The bar's top is red, bottom blue, and text ink is present right of the bar.
        let (bx, by, bh) = (l.bar_x + l.bar_w / 2, l.bar_y, l.bar_h);
        assert_eq!(
            img.get(bx as u32, by as u32),
            ColorMap::Diverging.srgb8(1.0)
        );
        assert_eq!(
            img.get(bx as u32, (by + bh - 1) as u32),
            ColorMap::Diverging.srgb8(0.0)
        );
        let ink = (0..600)
            .flat_map(|y| ((l.bar_x + l.bar_w + 4) as u32..800).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get(x, y) == INK)
            .count();
        assert!(ink > 100, "{ink}");
    }
}
