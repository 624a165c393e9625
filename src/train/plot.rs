//! A small line chart of the training curve (loss and held-out PSNR against step), drawn
//! with the `image` crate so no plotting dependency is needed for one PNG.

use image::{Rgb, RgbImage};
use std::path::Path;

fn draw_series(img: &mut RgbImage, pts: &[(f64, f64)], x_max: f64, (lo, hi): (f64, f64), colour: Rgb<u8>) {
    let (w, h) = (img.width() as f64 - 20.0, img.height() as f64 - 20.0);
    let to_px = |(x, y): (f64, f64)| (10.0 + x / x_max.max(1.0) * w, 10.0 + (1.0 - (y - lo) / (hi - lo).max(1e-9)) * h);
    for pair in pts.windows(2) {
        let (a, b) = (to_px(pair[0]), to_px(pair[1]));
        let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()) as usize).max(1);
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
                img.put_pixel(x as u32, y as u32, colour);
            }
        }
    }
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| (lo.min(y), hi.max(y)))
}

/// Writes `path`: log10(loss) in red and PSNR (dB) in blue, each scaled to the chart height,
/// against the step on the x axis.
pub fn write_curve(path: &Path, loss: &[(u64, f32)], psnr: &[(u64, f32)]) -> image::ImageResult<()> {
    let mut img = RgbImage::from_pixel(640, 360, Rgb([255, 255, 255]));
    let x_max = loss.iter().chain(psnr).map(|p| p.0).max().unwrap_or(1) as f64;
    let l: Vec<(f64, f64)> = loss.iter().map(|&(s, v)| (s as f64, (v.max(1e-9) as f64).log10())).collect();
    let p: Vec<(f64, f64)> = psnr.iter().map(|&(s, v)| (s as f64, v as f64)).collect();
    draw_series(&mut img, &l, x_max, range(l.iter().map(|p| p.1)), Rgb([200, 30, 30]));
    draw_series(&mut img, &p, x_max, range(p.iter().map(|p| p.1)), Rgb([30, 60, 200]));
    img.save(path)
}
