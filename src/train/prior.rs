//! Training the shape prior (`rendernet train-prior`): the autoencoder of
//! [`crate::nn::prior`] reconstructs the training split's grids (sampled uniformly; a
//! dataset holds each shape once per view, so every shape is equally likely), BCE loss,
//! Adam, held-out IoU at each evaluation, atomic checkpoints and exact resume.

use crate::data::{Dataset, Split};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::nn::prior::{CodeStats, PriorPreset, ShapePrior, iou};
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

/// Training shapes whose codes a prior's weights file keeps ([`CodeStats`]).
pub const STATS_SHAPES: usize = 256;

/// The codes of `samples` training grids of `ds` (spread over the split) under the prior
/// weights `weights`, and their mean and spread.
pub fn code_stats(gpu: &Gpu, p: &PriorPreset, weights: &[u8], ds: &Dataset, samples: usize) -> Result<CodeStats> {
    const BATCH: usize = 8;
    let train = ds.split(Split::Train);
    let ids: Vec<usize> = train.spread(samples).collect();
    if ids.is_empty() {
        return Err(Error::Invalid(format!("{}: the train split is empty", ds.dir().display())));
    }
    let net = ShapePrior::build(p, BATCH, false)?;
    let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
    ex.load_params_bytes(gpu, weights, "prior weights")?;
    ex.training = false;
    ex.keep(net.code);
    let mut codes = Vec::with_capacity(ids.len() * p.latent);
    for chunk in ids.chunks(BATCH) {
        let mut grids = Vec::with_capacity(BATCH * p.res.pow(3));
        for &i in chunk {
            grids.extend(grid_of(ds, Split::Train, i, p.res)?);
        }
        // A short last batch is padded with its first grid; those codes are dropped.
        let one = grids[..p.res.pow(3)].to_vec();
        while grids.len() < BATCH * p.res.pow(3) {
            grids.extend_from_slice(&one);
        }
        ex.feed(gpu, net.grid, &grids)?;
        ex.forward(gpu)?;
        codes.extend_from_slice(&ex.read(gpu, net.code)?[..chunk.len() * p.latent]);
    }
    CodeStats::of(codes, p.latent)
}

/// Rewrites the weights file `path` (atomically) with `stats` beside its parameters.
pub fn attach_code_stats(path: &std::path::Path, stats: &CodeStats) -> Result<()> {
    let (tensors, meta) = crate::graph::params::load_safetensors(path)?;
    let mut named: Vec<crate::graph::params::Named> =
        tensors.into_iter().filter(|(k, _)| !k.starts_with(crate::nn::prior::STATS_PREFIX)).map(|(k, (s, v))| (k, s, v)).collect();
    named.extend(stats.tensors());
    crate::graph::params::save_safetensors(path, &named, meta)
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
    // Each checkpoint's weights file also keeps the code statistics of its own weights.
    let weights = s.out.with_extension("weights.safetensors");
    let eval = |w: &[u8]| {
        attach_code_stats(&weights, &code_stats(gpu, &preset, w, &ds, STATS_SHAPES)?)?;
        evaluate(gpu, &preset, w, &ds, s.eval_samples)
    };
    steps::run(gpu, &mut ex, loss, s, feed, eval, report)
}
