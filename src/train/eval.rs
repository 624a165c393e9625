//! Held-out evaluation: mean PSNR with a 95% interval, and per-shape PSNR.

use super::batch::Batch;
use crate::data::{Dataset, Split};
use crate::error::Result;
use crate::graph::Executor;
use crate::gpu::Gpu;
use crate::nn::rendernet::{Head, Preset, RenderNet};
use crate::ops::loss::psnr_from_mse;
use std::collections::BTreeMap;
use std::path::Path;

/// PSNR statistics over a split.
#[derive(Clone, Debug)]
pub struct EvalReport {
    /// Mean PSNR (dB) over samples.
    pub mean: f32,
    /// Half width of the 95% interval of the mean (1.96 standard errors).
    pub ci95: f32,
    /// Samples evaluated.
    pub count: usize,
    /// Mean PSNR per shape id.
    pub per_shape: BTreeMap<u32, f32>,
    /// Mean PSNR an all-black image would score on the same samples: with small objects on
    /// a black background PSNR is dominated by the background, so this is the floor to
    /// compare against.
    pub black: f32,
}

/// Renders up to `limit` held-out samples (0 = all) with the weights at `weights` and
/// compares them with the targets (the Phong image, or the single image).
pub fn evaluate(gpu: &Gpu, p: &Preset, head: Head, weights: &Path, ds: &Dataset, limit: usize) -> Result<EvalReport> {
    let test = ds.split(Split::Test);
    let n = if limit == 0 { test.len() } else { limit.min(test.len()) };
    let net = RenderNet::build(p, head, 1, [p.cam, p.cam], false)?;
    let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
    ex.load_params(gpu, weights)?;
    ex.training = false;
    ex.keep(net.image);
    let target = match head {
        Head::Phong(_) => "phong",
        Head::Image(_) => "image",
    };
    let mut psnrs = Vec::with_capacity(n);
    let mut black = 0.0f32;
    let mut shapes: BTreeMap<u32, Vec<f32>> = BTreeMap::new();
    // Spread the evaluated samples over the split so every shape is represented.
    for k in 0..n {
        let i = k * test.len() / n;
        let s = test.get(i)?;
        let mut b = Batch::default();
        b.push(p, &s, [0, 0, p.cam, p.cam], &[target.to_string()])?;
        ex.feed(gpu, net.grid, &b.grid)?;
        ex.feed(gpu, net.pose, &b.pose)?;
        if let Some(l) = net.light {
            ex.feed(gpu, l, &b.light)?;
        }
        ex.forward(gpu)?;
        let y = ex.read(gpu, net.image)?;
        let t = &b.targets[0].1;
        // Both sides clamped to [0, 1], as images are stored.
        let mse = y.iter().zip(t).map(|(a, b)| (a.clamp(0.0, 1.0) - b) as f64).map(|d| d * d).sum::<f64>() / t.len() as f64;
        let db = psnr_from_mse(mse as f32, 1.0).min(99.0);
        psnrs.push(db);
        let mse0 = t.iter().map(|&b| (b as f64) * (b as f64)).sum::<f64>() / t.len() as f64;
        black += psnr_from_mse(mse0 as f32, 1.0).min(99.0);
        shapes.entry(s.shape_id).or_default().push(db);
    }
    let count = psnrs.len().max(1);
    let mean = psnrs.iter().sum::<f32>() / count as f32;
    let var = psnrs.iter().map(|x| (x - mean) * (x - mean)).sum::<f32>() / (count.max(2) - 1) as f32;
    Ok(EvalReport {
        mean,
        ci95: 1.96 * (var / count as f32).sqrt(),
        count: psnrs.len(),
        black: black / count as f32,
        per_shape: shapes.into_iter().map(|(k, v)| (k, v.iter().sum::<f32>() / v.len() as f32)).collect(),
    })
}
