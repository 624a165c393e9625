//! Training the texture decoder (`rendernet train-texture`): random paints
//! ([`Paint::random`], the distribution of `dataset --colour`), their codes in, the
//! textures they draw as targets, MSE, Adam; held-out PSNR of the decoded textures on a
//! fixed set of paints no step draws, atomic checkpoints and exact resume. No dataset: the
//! family is procedural.

use super::steps::{self, StepConfig};
use crate::error::Result;
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::nn::texture::{TextureDecoder, TexturePreset, texture_values};
use crate::rng::SplitMix64;
use crate::voxel::shapes::Paint;

/// How to train the texture decoder.
#[derive(Clone, Debug)]
pub struct TextureConfig {
    /// Network sizes.
    pub preset: TexturePreset,
    /// Steps, batch, checkpoints and evaluations (`eval_samples` held-out paints, at least 1).
    pub steps: StepConfig,
}

/// Stream of the held-out paints: the same for every seed, never drawn by a training step.
const HELD_OUT: u64 = 0x7e57_7e57;

/// Held-out paint `i`.
pub fn held_out_paint(i: usize) -> Paint {
    Paint::random(&mut SplitMix64::new(HELD_OUT, i as u64))
}

/// Codes `[n, TEXTURE_CODE]` and target textures `[n, 3, R, R, R]` of `paints`.
fn batch(paints: &[Paint], res: usize) -> Result<(Vec<f32>, Vec<f32>)> {
    let codes = paints.iter().flat_map(|p| p.code()).collect();
    let mut targets = Vec::with_capacity(paints.len() * 3 * res.pow(3));
    for p in paints {
        targets.extend(texture_values(p, res)?);
    }
    Ok((codes, targets))
}

/// PSNR (dB, peak 1) of the decoder with weights `weights` (safetensors bytes) over the first
/// `samples` held-out paints: the whole cube, every voxel and channel.
pub fn evaluate(gpu: &Gpu, p: &TexturePreset, weights: &[u8], samples: usize) -> Result<f64> {
    let paints: Vec<Paint> = (0..samples.max(1)).map(held_out_paint).collect();
    let net = TextureDecoder::build(p, paints.len(), false)?;
    let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
    ex.load_params_bytes(gpu, weights, "texture decoder weights")?;
    ex.keep(net.texture);
    let (codes, targets) = batch(&paints, p.res)?;
    ex.feed(gpu, net.code, &codes)?;
    ex.forward(gpu)?;
    let got = ex.read(gpu, net.texture)?;
    let mse = got.iter().zip(&targets).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>() / targets.len() as f64;
    Ok(-10.0 * mse.max(1e-12).log10())
}

/// Trains as configured; `report(step, loss, psnr)` after every step (`psnr` at
/// evaluations). Returns the last held-out PSNR.
pub fn train_texture(gpu: &Gpu, cfg: &TextureConfig, report: impl FnMut(u64, f32, Option<f64>)) -> Result<f64> {
    let s = &cfg.steps;
    let net = TextureDecoder::build(&cfg.preset, s.batch.max(1), true)?;
    let (loss, target) = (net.loss.expect("built with a loss"), net.target.expect("built with a loss"));
    let mut ex = Executor::new(gpu, net.graph.clone(), s.seed)?;
    let feed = |ex: &mut Executor, step: u64| {
        // The paints of a step depend on (seed, step) only: a resumed run repeats them.
        let mut rng = SplitMix64::new(s.seed ^ 0x7e_c0de, step);
        let paints: Vec<Paint> = (0..s.batch).map(|_| Paint::random(&mut rng)).collect();
        let (codes, targets) = batch(&paints, cfg.preset.res)?;
        ex.feed(gpu, net.code, &codes)?;
        ex.feed(gpu, target, &targets)
    };
    steps::run(gpu, &mut ex, loss, s, feed, |w| evaluate(gpu, &cfg.preset, w, s.eval_samples), report)
}
