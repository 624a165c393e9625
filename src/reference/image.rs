//! A rendered image on the host: planar f32 `[C, S, S]`, `C` = 1 (grey) or 3 (RGB).

use crate::error::{Error, Result};
use std::path::Path;

/// A square planar image, values nominally in `[0, 1]`, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Channels: 1 or 3.
    pub channels: usize,
    /// Side length `S`.
    pub size: usize,
    /// `channels * size * size` values, channel-major (the network's NCHW without N).
    pub data: Vec<f32>,
}

impl Image {
    /// Shape `[C, S, S]`.
    pub fn shape(&self) -> [usize; 3] {
        [self.channels, self.size, self.size]
    }

    /// Value of channel `c` at row `y`, column `x`.
    pub fn get(&self, c: usize, y: usize, x: usize) -> f32 {
        self.data[(c * self.size + y) * self.size + x]
    }

    /// The image as 8-bit RGB (grey replicated), values clamped to `[0, 1]` and rounded.
    pub fn to_rgb8(&self) -> image::RgbImage {
        let s = self.size as u32;
        image::RgbImage::from_fn(s, s, |x, y| {
            let px = |c: usize| {
                let v = self.get(c.min(self.channels - 1), y as usize, x as usize);
                (v.clamp(0.0, 1.0) * 255.0).round() as u8
            };
            image::Rgb([px(0), px(1), px(2)])
        })
    }

    /// Writes a PNG (RGB, or 8-bit grey for one channel).
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let res = if self.channels == 1 {
            let s = self.size as u32;
            image::GrayImage::from_fn(s, s, |x, y| {
                image::Luma([(self.get(0, y as usize, x as usize).clamp(0.0, 1.0) * 255.0).round() as u8])
            })
            .save(path)
        } else {
            self.to_rgb8().save(path)
        };
        res.map_err(|e| match e {
            image::ImageError::IoError(source) => Error::Io { path: path.display().to_string(), source },
            other => Error::Invalid(format!("{}: writing PNG failed: {other}", path.display())),
        })
    }
}
