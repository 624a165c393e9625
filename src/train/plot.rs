//! The training log (`<out>.log.csv`) and its curve: loss and held-out PSNR against step,
//! drawn by [`crate::chart`] with numbered, labelled axes.

use crate::chart::{self, Options, Panel};
use crate::error::{Error, Result};
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

/// Writes `path`: two panels against the training step, the loss (mean of every k steps,
/// k = 1..=100 so about 200 points show the trend through per-step noise) on a log axis
/// above, held-out PSNR (dB) at each evaluation below.
pub fn write_curve(path: &Path, loss: &[(u64, f32)], psnr: &[(u64, f32)]) -> image::ImageResult<()> {
    let k = (loss.len() / 200).clamp(1, 100);
    let l: Vec<(f64, f64)> = loss
        .chunks(k)
        .map(|c| (c[c.len() - 1].0 as f64, c.iter().map(|p| p.1 as f64).sum::<f64>() / c.len() as f64))
        .collect();
    let p: Vec<(f64, f64)> = psnr.iter().map(|&(s, v)| (s as f64, v as f64)).collect();
    let mean = if k == 1 { "loss at each step".to_string() } else { format!("mean loss of {k} steps") };
    // Both panels span step 0 to the last step, so they line up.
    let last = loss.iter().chain(psnr).map(|p| p.0).max().unwrap_or(1).max(1) as f64;
    let panel = |title: &str, y_label: &str, name: String, series, log_y, markers| Panel {
        title: title.into(),
        x_label: "training step".into(),
        y_label: y_label.into(),
        series: vec![(name, series)],
        options: Options { size: (800, 340), log_y, markers, x_range: Some((0.0, last)), ..Options::default() },
    };
    let panels = [
        panel("Training loss", "loss (log scale)", mean, l, true, false),
        panel("Held-out PSNR", "PSNR (dB)", "mean over held-out samples".into(), p, false, true),
    ];
    chart::line_panels(path, &panels).map_err(|e| image::ImageError::IoError(std::io::Error::other(e.to_string())))
}
