//! Training the shape prior (`rendernet train-prior`): the autoencoder of
//! [`crate::nn::prior`] reconstructs the training split's grids (sampled uniformly; a
//! dataset holds each shape once per view, so every shape is equally likely), BCE loss,
//! Adam, held-out IoU at each evaluation, atomic checkpoints and exact resume.

use crate::data::{Dataset, Split};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::nn::prior::{PriorPreset, ShapePrior, iou};
use crate::rng::SplitMix64;
use super::steps::{self, StepConfig};
use std::path::PathBuf;

/// How to train the prior.
#[derive(Clone, Debug)]
pub struct PriorConfig {
    /// Network sizes (the grid side is taken from the dataset).
    pub preset: PriorPreset,
    /// Dataset directory (its grids are used; images are not).
    pub data: PathBuf,
    /// Steps, batch, checkpoints and evaluations (`eval_samples` 0: the whole test split).
    pub steps: StepConfig,
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
pub fn train_prior(gpu: &Gpu, cfg: &PriorConfig, report: impl FnMut(u64, f32, Option<f64>)) -> Result<f64> {
    let ds = Dataset::open(&cfg.data)?;
    let train = ds.split(Split::Train);
    if train.is_empty() {
        return Err(Error::Invalid(format!("{}: the train split is empty", cfg.data.display())));
    }
    // The grid side is the dataset's.
    let preset = PriorPreset { res: ds.manifest.res, ..cfg.preset.clone() };
    let s = &cfg.steps;
    let net = ShapePrior::build(&preset, s.batch, true)?;
    let loss = net.loss.expect("built with a loss");
    let mut ex = Executor::new(gpu, net.graph.clone(), s.seed)?;
    let feed = |ex: &mut Executor, step: u64| {
        // The samples of a step depend on (seed, step) only: a resumed run repeats them.
        let mut rng = SplitMix64::new(s.seed ^ 0x9_1102, step);
        let mut grids = Vec::with_capacity(s.batch * preset.res.pow(3));
        for _ in 0..s.batch {
            let i = (rng.next_u64() % train.len() as u64) as usize;
            grids.extend(grid_of(&ds, Split::Train, i, preset.res)?);
        }
        ex.feed(gpu, net.grid, &grids)
    };
    steps::run(gpu, &mut ex, loss, s, feed, |w| evaluate(gpu, &preset, w, &ds, s.eval_samples), report)
}
