//! The step loop the grid networks share (`train-prior`, `train-texture`): Adam steps on
//! batches a caller feeds, the loss read back by each step's own submit, an atomic
//! checkpoint and an evaluation every `eval_every` steps, exact resume (a caller's batches
//! must depend on the step number only).

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::{Executor, Value};
use crate::ops::adam::Adam;
use std::path::PathBuf;

/// How a grid network is trained, whichever it is.
#[derive(Clone, Debug)]
pub struct StepConfig {
    /// Checkpoint path; `<out>.weights.safetensors` is written beside it.
    pub out: PathBuf,
    /// Total optimizer steps.
    pub steps: u64,
    /// Checkpoint to resume from.
    pub resume: Option<PathBuf>,
    /// Samples per step.
    pub batch: usize,
    /// Learning rate (Adam, beta1 0.5).
    pub lr: f32,
    /// Seed for initialisation and sampling.
    pub seed: u64,
    /// Steps between evaluations + checkpoints.
    pub eval_every: u64,
    /// Held-out samples per evaluation.
    pub eval_samples: usize,
}

/// Resumes `ex` from `s.resume` if set, then runs steps `ex.step..s.steps` of `loss`:
/// `feed(ex, step)` sets each step's inputs;
/// `eval(weights)` scores the weights at each checkpoint; `report(step, loss, score)` after
/// every step (`score` at evaluations). Returns the last score.
pub(crate) fn run(
    gpu: &Gpu,
    ex: &mut Executor,
    loss: Value,
    s: &StepConfig,
    mut feed: impl FnMut(&mut Executor, u64) -> Result<()>,
    mut eval: impl FnMut(&[u8]) -> Result<f64>,
    mut report: impl FnMut(u64, f32, Option<f64>),
) -> Result<f64> {
    if s.batch == 0 || s.eval_every == 0 {
        return Err(Error::Invalid("--batch and --eval-every must be at least 1".into()));
    }
    if let Some(r) = &s.resume {
        ex.load_checkpoint(gpu, r)?;
    }
    let mut last = f64::NAN;
    for step in ex.step..s.steps {
        feed(ex, step)?;
        let stats = ex.train_step(gpu, loss, &Adam::new(s.lr))?;
        let l = stats.loss.expect("a training step reads its loss back");
        if !l.is_finite() {
            return Err(Error::Invalid(format!("step {}: the loss is {l}; stopping (last checkpoint: {})", step + 1, s.out.display())));
        }
        let at_eval = (step + 1) % s.eval_every == 0 || step + 1 == s.steps;
        if at_eval {
            ex.save_checkpoint(gpu, &s.out)?;
            let weights = s.out.with_extension("weights.safetensors");
            ex.save_params(gpu, &weights)?;
            let bytes = std::fs::read(&weights).map_err(|e| Error::Io { path: weights.display().to_string(), source: e })?;
            last = eval(&bytes)?;
        }
        report(step + 1, l, at_eval.then_some(last));
    }
    Ok(last)
}
