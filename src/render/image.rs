//! An 8-bit sRGB picture, PNG output (through the `png` crate and `io::write_atomic`) and
//! the numbers tests use to tell a real render from an empty or flat one.

use crate::error::{Error, Result};
use std::path::Path;

/// An RGB picture, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// `width * height` pixels, row-major.
    pub pixels: Vec<[u8; 3]>,
}

/// Coverage and contrast of a picture against its background colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageStats {
    /// Fraction of the pixels that differ from the background.
    pub foreground_fraction: f64,
    /// Number of distinct grey levels (Rec. 601 luma, 0-255) among the foreground pixels.
    pub grey_levels: usize,
    /// Fraction of the foreground whose channels differ by more than 40 (clearly coloured).
    pub colored_fraction: f64,
    /// Fraction of the foreground darker than luma 64: outlines and drawn lines (patch
    /// boundaries), which shaded surfaces under the default lights do not reach.
    pub dark_fraction: f64,
}

impl Image {
    /// A picture filled with one colour.
    pub fn new(width: u32, height: u32, fill: [u8; 3]) -> Image {
        Image {
            width,
            height,
            pixels: vec![fill; width as usize * height as usize],
        }
    }

    /// The pixel at (`x`, `y`).
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Fills a rectangle, clipped to the picture.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, color: [u8; 3]) {
        let x0 = x.max(0);
        let y0 = y.max(0);
        let x1 = (x + w).min(self.width as i64);
        let y1 = (y + h).min(self.height as i64);
        for yy in y0..y1 {
            let row = yy as usize * self.width as usize;
            for xx in x0..x1 {
                self.pixels[row + xx as usize] = color;
            }
        }
    }

    /// PNG bytes (8-bit RGB, default compression).
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        self.write_png(&mut out)
            .map_err(|e| Error::Numerical(format!("PNG encoding failed: {e}")))?;
        Ok(out)
    }

    fn write_png(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut enc = png::Encoder::new(w, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(self.pixels.as_flattened())
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    }

    /// Writes the picture as a PNG, atomically (a failed write leaves no partial file).
    pub fn save_png(&self, path: &Path) -> Result<()> {
        crate::io::write_atomic(path, |w| self.write_png(w))
    }

    /// Reads an 8-bit RGB or RGBA PNG (alpha dropped); for tests and checks of written files.
    pub fn load_png(path: &Path) -> Result<Image> {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let mut dec = png::Decoder::new(std::io::BufReader::new(file));
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = dec
            .read_info()
            .map_err(|e| Error::content(path, format!("not a readable PNG: {e}")))?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| Error::content(path, "PNG too large"))?;
        let mut buf = vec![0u8; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| Error::content(path, format!("not a readable PNG: {e}")))?;
        let channels = match info.color_type {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            other => {
                return Err(Error::unsupported(
                    path,
                    format!("PNG colour type {other:?}"),
                ))
            }
        };
        let pixels = buf[..info.buffer_size()]
            .chunks_exact(channels)
            .map(|c| {
                if channels < 3 {
                    [c[0]; 3]
                } else {
                    [c[0], c[1], c[2]]
                }
            })
            .collect();
        Ok(Image {
            width: info.width,
            height: info.height,
            pixels,
        })
    }

    /// Foreground fraction, grey levels and colourfulness against `background`.
    pub fn stats(&self, background: [u8; 3]) -> ImageStats {
        let mut fg = 0usize;
        let mut colored = 0usize;
        let mut dark = 0usize;
        let mut levels = [false; 256];
        for p in &self.pixels {
            if *p == background {
                continue;
            }
            fg += 1;
            let [r, g, b] = p.map(|c| c as u32);
            let luma = (299 * r + 587 * g + 114 * b + 500) / 1000;
            levels[luma as usize] = true;
            if luma < 64 {
                dark += 1;
            }
            if r.max(g).max(b) - r.min(g).min(b) > 40 {
                colored += 1;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        let of_fg = |k: usize| if fg == 0 { 0.0 } else { k as f64 / fg as f64 };
        ImageStats {
            foreground_fraction: fg as f64 / n,
            grey_levels: levels.iter().filter(|&&l| l).count(),
            colored_fraction: of_fg(colored),
            dark_fraction: of_fg(dark),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_and_stats() {
        let mut img = Image::new(7, 5, [255, 255, 255]);
        img.fill_rect(1, 1, 3, 2, [10, 200, 30]);
        img.fill_rect(-5, 4, 100, 100, [128, 128, 128]);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.png");
        img.save_png(&p).unwrap();
        let back = Image::load_png(&p).unwrap();
        assert_eq!(back, img);
        let s = img.stats([255, 255, 255]);
        assert!((s.foreground_fraction - 13.0 / 35.0).abs() < 1e-12);
        assert_eq!(s.grey_levels, 2);
        assert!((s.colored_fraction - 6.0 / 13.0).abs() < 1e-12);
        assert_eq!(s.dark_fraction, 0.0);
        img.fill_rect(0, 0, 1, 1, [20, 24, 40]);
        let s = img.stats([255, 255, 255]);
        assert!((s.dark_fraction - 1.0 / 14.0).abs() < 1e-12);
        assert!(img.save_png(&dir.path().join("no/such/dir.png")).is_err());
        assert!(!img.encode_png().unwrap().is_empty());
    }
}
