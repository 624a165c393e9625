//! A small line chart of the training curve (loss and held-out PSNR against step), drawn
//! with the `image` crate so no plotting dependency is needed for one PNG.

use crate::error::{Error, Result};
use image::{Rgb, RgbImage};
use std::io::Write;
use std::path::Path;

/// Appends `losses` (one row each, empty PSNR) and one evaluation row to the CSV log.
pub fn append_log(path: &Path, losses: &[(u64, f32)], eval: (u64, f32)) -> Result<()> {
    let io = |e| Error::Io { path: path.display().to_string(), source: e };
    let new = !path.exists();
    let mut f = std::fs::OpenOptions::new().create(true).append(true).open(path).map_err(io)?;
    let mut text = String::new();
    if new {
        text.push_str("step,loss,psnr\n");
    }
    for (s, l) in losses {
        text.push_str(&format!("{s},{l},\n"));
    }
    text.push_str(&format!("{},,{}\n", eval.0, eval.1));
    f.write_all(text.as_bytes()).map_err(io)
}

/// Reads the CSV log up to `upto` (the resumed step): losses and PSNRs. A missing or
/// unreadable log gives empty series (the curve then starts at the resume).
pub fn read_log(path: &Path, upto: u64) -> (Vec<(u64, f32)>, Vec<(u64, f32)>) {
    let (mut loss, mut psnr) = (Vec::new(), Vec::new());
    for line in std::fs::read_to_string(path).unwrap_or_default().lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let Some(step) = f.first().and_then(|s| s.parse::<u64>().ok()).filter(|&s| s <= upto) else { continue };
        if let Some(v) = f.get(1).and_then(|s| s.parse().ok()) {
            loss.push((step, v));
        }
        if let Some(v) = f.get(2).and_then(|s| s.parse().ok()) {
            psnr.push((step, v));
        }
    }
    (loss, psnr)
}

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

/// Writes `path`: log10(loss) in red (mean of every 100 steps, so the trend shows through
/// per-step noise) and held-out PSNR in blue, each scaled to the chart height, against the
/// step on the x axis; grey lines mark tenths of both axes.
pub fn write_curve(path: &Path, loss: &[(u64, f32)], psnr: &[(u64, f32)]) -> image::ImageResult<()> {
    let mut img = RgbImage::from_pixel(640, 360, Rgb([255, 255, 255]));
    for k in 1..10 {
        let (x, y) = (10 + k * 62, 10 + k * 34);
        (10..350).for_each(|yy| img.put_pixel(x, yy, Rgb([225, 225, 225])));
        (10..630).for_each(|xx| img.put_pixel(xx, y, Rgb([225, 225, 225])));
    }
    let x_max = loss.iter().chain(psnr).map(|p| p.0).max().unwrap_or(1) as f64;
    let l: Vec<(f64, f64)> = loss
        .chunks(100)
        .map(|c| {
            let mean = c.iter().map(|p| p.1 as f64).sum::<f64>() / c.len() as f64;
            (c[c.len() - 1].0 as f64, mean.max(1e-9).log10())
        })
        .collect();
    let p: Vec<(f64, f64)> = psnr.iter().map(|&(s, v)| (s as f64, v as f64)).collect();
    draw_series(&mut img, &l, x_max, range(l.iter().map(|p| p.1)), Rgb([200, 30, 30]));
    draw_series(&mut img, &p, x_max, range(p.iter().map(|p| p.1)), Rgb([30, 60, 200]));
    img.save(path)
}
