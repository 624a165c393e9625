//! Training the shape prior (`rendernet train-prior`): the autoencoder of
//! [`crate::nn::prior`] reconstructs the training split's grids (sampled uniformly; a
//! dataset holds each shape once per view, so every shape is equally likely), BCE loss,
//! Adam, held-out IoU at each evaluation, atomic checkpoints and exact resume.

use crate::data::{Dataset, Split};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::nn::prior::{PriorPreset, ShapePrior, iou};
use crate::ops::adam::Adam;
use crate::rng::SplitMix64;
use std::path::PathBuf;

/// How to train the prior.
#[derive(Clone, Debug)]
pub struct PriorConfig {
    /// Network sizes (the grid side is taken from the dataset).
    pub preset: PriorPreset,
    /// Dataset directory (its grids are used; images are not).
    pub data: PathBuf,
    /// Checkpoint path; `<out>.weights.safetensors` is written beside it.
    pub out: PathBuf,
    /// Total optimizer steps.
    pub steps: u64,
    /// Checkpoint to resume from.
    pub resume: Option<PathBuf>,
    /// Grids per step.
    pub batch: usize,
    /// Learning rate (Adam, beta1 0.5).
    pub lr: f32,
    /// Seed for initialisation and sampling.
    pub seed: u64,
    /// Steps between evaluations + checkpoints.
    pub eval_every: u64,
    /// Held-out grids per evaluation (0 = all).
    pub eval_samples: usize,
}

/// The grid of sample `i` of `split` as the prior reads it: in RenderNet's input layout
/// (`nn::camera::input_values`), so a decoded grid feeds the renderer as it is. The
/// dataset's resolution must be the preset's.
fn grid_of(ds: &Dataset, split: Split, i: usize, res: usize) -> Result<Vec<f32>> {
    let s = ds.split(split).get(i)?;
    if s.grid.dims() != [res; 3] {
        return Err(Error::Invalid(format!("{}: grids are {:?}; the prior needs {res}^3", ds.dir().display(), s.grid.dims())));
    }
    Ok(crate::nn::camera::input_values(&s.grid))
}

/// Mean IoU (threshold 0.5) of the prior's reconstructions of `samples` held-out grids
/// (spread over the split; 0 = all), with weights from `weights` (safetensors bytes).
pub fn evaluate(gpu: &Gpu, p: &PriorPreset, weights: &[u8], ds: &Dataset, samples: usize) -> Result<f64> {
    let test = ds.split(Split::Test);
    let n = test.spread(samples).count();
    if n == 0 {
        return Err(Error::Invalid(format!("{}: the test split is empty", ds.dir().display())));
    }
    let net = ShapePrior::build(p, 1, false)?;
    let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
    ex.load_params_bytes(gpu, weights, "prior weights")?;
    ex.training = false;
    ex.keep(net.recon);
    let mut sum = 0.0;
    for i in test.spread(samples) {
        let g = grid_of(ds, Split::Test, i, p.res)?;
        ex.feed(gpu, net.grid, &g)?;
        ex.forward(gpu)?;
        sum += iou(&ex.read(gpu, net.recon)?, &g);
    }
    Ok(sum / n as f64)
}

/// Trains as configured; `report(step, loss, iou)` after every step (`iou` at evaluations).
/// Returns the last held-out IoU.
pub fn train_prior(gpu: &Gpu, cfg: &PriorConfig, mut report: impl FnMut(u64, f32, Option<f64>)) -> Result<f64> {
    let ds = Dataset::open(&cfg.data)?;
    let train = ds.split(Split::Train);
    if train.is_empty() {
        return Err(Error::Invalid(format!("{}: the train split is empty", cfg.data.display())));
    }
    // The grid side is the dataset's.
    let preset = PriorPreset { res: ds.manifest.res, ..cfg.preset.clone() };
    let net = ShapePrior::build(&preset, cfg.batch, true)?;
    let loss = net.loss.expect("built with a loss");
    let mut ex = Executor::new(gpu, net.graph.clone(), cfg.seed)?;
    let mut start = 0;
    if let Some(r) = &cfg.resume {
        ex.load_checkpoint(gpu, r)?;
        start = ex.step;
    }
    let mut last = f64::NAN;
    for step in start..cfg.steps {
        // The samples of a step depend on (seed, step) only: a resumed run repeats them.
        let mut rng = SplitMix64::new(cfg.seed ^ 0x9_1102, step);
        let mut grids = Vec::with_capacity(cfg.batch * cfg.preset.res.pow(3));
        for _ in 0..cfg.batch {
            let i = (rng.next_u64() % train.len() as u64) as usize;
            grids.extend(grid_of(&ds, Split::Train, i, preset.res)?);
        }
        ex.feed(gpu, net.grid, &grids)?;
        let stats = ex.train_step(gpu, loss, &Adam::new(cfg.lr))?;
        let l = stats.loss.expect("a training step reads its loss back");
        if !l.is_finite() {
            return Err(Error::Invalid(format!("step {}: the loss is {l}; stopping (last checkpoint: {})", step + 1, cfg.out.display())));
        }
        let eval = (step + 1) % cfg.eval_every == 0 || step + 1 == cfg.steps;
        if eval {
            ex.save_checkpoint(gpu, &cfg.out)?;
            let weights = cfg.out.with_extension("weights.safetensors");
            ex.save_params(gpu, &weights)?;
            let bytes = std::fs::read(&weights).map_err(|e| Error::Io { path: weights.display().to_string(), source: e })?;
            last = evaluate(gpu, &preset, &bytes, &ds, cfg.eval_samples)?;
        }
        report(step + 1, l, eval.then_some(last));
    }
    Ok(last)
}
