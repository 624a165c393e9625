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
    /// The image resampled to `size` x `size` (Catmull-Rom: sharper than bilinear, with little
    /// ringing), each channel alike, clamped to [0, 1].
    pub fn resized(&self, size: usize) -> Image {
        let plane = self.size * self.size;
        let mut data = Vec::with_capacity(self.channels * size * size);
        for c in 0..self.channels {
            let src = image::ImageBuffer::<image::Luma<f32>, _>::from_raw(self.size as u32, self.size as u32, self.data[c * plane..(c + 1) * plane].to_vec())
                .expect("a channel holds size * size values");
            let out = image::imageops::resize(&src, size as u32, size as u32, image::imageops::FilterType::CatmullRom);
            data.extend(out.into_raw().into_iter().map(|v| v.clamp(0.0, 1.0)));
        }
        Image { channels: self.channels, size, data }
    }

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

    /// Images of one size placed left to right in one RGB image (grey ones replicated);
    /// the result is `size` high and not square, so it is only for saving as a PNG.
    pub fn side_by_side(images: &[&Image]) -> Result<image::RgbImage> {
        let s = images.first().map_or(0, |i| i.size);
        if let Some(i) = images.iter().find(|i| i.size != s) {
            return Err(Error::Invalid(format!("side by side: images of {s} and {} px", i.size)));
        }
        let mut strip = image::RgbImage::new((images.len() * s) as u32, s as u32);
        for (k, img) in images.iter().enumerate() {
            image::imageops::replace(&mut strip, &img.to_rgb8(), (k * s) as i64, 0);
        }
        Ok(strip)
    }

    /// Reads a square image file (PNG or any format the `image` crate was built with) as
    /// RGB; errors name the file and say what is wrong (missing, undecodable, not square).
    pub fn load_rgb(path: impl AsRef<Path>) -> Result<Image> {
        let path = path.as_ref();
        let img = image::open(path).map_err(|e| match e {
            image::ImageError::IoError(source) => Error::Io { path: path.display().to_string(), source },
            other => Error::Invalid(format!("{}: cannot decode the image: {other}", path.display())),
        })?;
        let rgb = img.to_rgb8();
        let (w, h) = rgb.dimensions();
        if w != h {
            return Err(Error::Invalid(format!("{}: the image is {w}x{h}; a square image is needed", path.display())));
        }
        let s = w as usize;
        let mut data = vec![0.0; 3 * s * s];
        for (x, y, p) in rgb.enumerate_pixels() {
            for c in 0..3 {
                data[(c * s + y as usize) * s + x as usize] = p[c] as f32 / 255.0;
            }
        }
        Ok(Image { channels: 3, size: s, data })
    }

    /// Writes a PNG (RGB, or 8-bit grey for one channel) with [`write_png`]: atomically,
    /// and only to a `.png` path.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<()> {
        let img = if self.channels == 1 {
            let s = self.size as u32;
            image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(s, s, |x, y| {
                image::Luma([(self.get(0, y as usize, x as usize).clamp(0.0, 1.0) * 255.0).round() as u8])
            }))
        } else {
            image::DynamicImage::ImageRgb8(self.to_rgb8())
        };
        write_png(&img, path.as_ref())
    }
}

/// Why `path` cannot name a PNG this crate writes, if it cannot: the `image` crate is built
/// with its `png` feature only, so `.png` (any case) is the one extension.
pub fn png_path_problem(path: &Path) -> Option<String> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => None,
        Some(e) => Some(format!("images are written as PNG only; '.{e}' is not supported (use a .png name)")),
        None => Some("images are written as PNG only; the name needs the .png extension".into()),
    }
}

/// Writes `img` to `path` as a PNG, atomically: encoded into a temporary file in the same
/// folder, then renamed over `path`, so a failed write (a full disk, a missing folder) never
/// leaves an empty or truncated image behind, nor destroys the one already there.
pub fn write_png(img: &image::DynamicImage, path: &Path) -> Result<()> {
    let shown = path.display().to_string();
    if let Some(m) = png_path_problem(path) {
        return Err(Error::Invalid(format!("{shown}: {m}")));
    }
    let io = |source| Error::Io { path: shown.clone(), source };
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("image.png");
    // The process id keeps two concurrent writers of the same name off each other's file.
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let written = (|| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(io)?);
        img.write_to(&mut f, image::ImageFormat::Png).map_err(|e| match e {
            image::ImageError::IoError(source) => io(source),
            other => Error::Invalid(format!("{shown}: writing PNG failed: {other}")),
        })?;
        f.into_inner().map_err(|e| io(e.into_error()))?.sync_all().map_err(io)?;
        std::fs::rename(&tmp, path).map_err(io)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}
