//! `rendernet train-prior` (the 3D shape autoencoder used as a shape prior) and
//! `rendernet train-texture` (the texture decoder), with a progress bar, checkpoints and a
//! held-out score.

use clap::Args;
use rendernet::nn::prior::PriorPreset;
use rendernet::nn::texture::TexturePreset;
use rendernet::train::prior::{PriorConfig, train_prior};
use rendernet::train::steps::StepConfig;
use rendernet::train::texture::{TextureConfig, train_texture};
use rendernet::{Gpu, Result};
use std::path::PathBuf;

/// The options both grid networks' training takes.
#[derive(Args)]
pub struct StepArgs {
    /// Checkpoint to write (atomically); <out>.weights.safetensors is written beside it.
    /// An existing <out> is only replaced with --resume or --force.
    #[arg(long)]
    out: PathBuf,
    /// Overwrite an existing --out with a fresh run.
    #[arg(long)]
    force: bool,
    /// Optimizer steps in all.
    #[arg(long, default_value_t = 4000)]
    steps: u64,
    /// Resume from this checkpoint.
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Samples per step.
    #[arg(long, default_value_t = 8)]
    batch: usize,
    /// Learning rate (Adam, beta1 0.5).
    #[arg(long, default_value_t = 1e-3)]
    lr: f32,
    /// Seed for initialisation and sampling.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Steps between held-out evaluations (each also writes the checkpoint).
    #[arg(long, default_value_t = 500)]
    eval_every: u64,
    /// Held-out samples per evaluation (0 = all the dataset's, for the prior).
    #[arg(long, default_value_t = 100)]
    eval_samples: usize,
}

/// Train the shape prior on a dataset's grids.
#[derive(Args)]
pub struct TrainPriorArgs {
    /// Dataset directory from `rendernet dataset` (grid side a multiple of 16, e.g. `--res 32`).
    #[arg(long)]
    data: PathBuf,
    #[command(flatten)]
    s: StepArgs,
}

/// Train the texture decoder on the procedural paints of `dataset --colour`.
#[derive(Args)]
pub struct TrainTextureArgs {
    #[command(flatten)]
    s: StepArgs,
}

/// Runs `train` with a progress bar (a line per 100 steps without a terminal), showing the
/// held-out score as `what`; prints the final score.
fn with_bar(s: &StepArgs, what: &str, train: impl FnOnce(&mut dyn FnMut(u64, f32, Option<f64>)) -> Result<f64>) -> Result<()> {
    super::train::refuse_overwrite(&s.out, s.resume.is_some(), s.force)?;
    let bar = super::train::step_bar(s.steps);
    let mut ema = None::<f32>;
    let mut last = String::from("-");
    let score = train(&mut |step, loss, score| {
        let e = ema.map_or(loss, |e| 0.98 * e + 0.02 * loss);
        ema = Some(e);
        if let Some(v) = score {
            last = format!("{v:.3}");
        }
        let msg = format!("loss {e:.4} {what} {last}");
        bar.set_position(step);
        if bar.is_hidden() && (step % 100 == 0 || score.is_some()) {
            println!("step {step}/{}: {msg}", s.steps);
        }
        bar.set_message(msg);
    })?;
    bar.finish();
    println!("final {what} {score:.3}; weights in {}", s.out.with_extension("weights.safetensors").display());
    Ok(())
}

/// The library's view of the shared options.
fn step_config(s: &StepArgs) -> StepConfig {
    StepConfig {
        out: s.out.clone(),
        steps: s.steps,
        resume: s.resume.clone(),
        batch: s.batch.max(1),
        lr: s.lr,
        seed: s.seed,
        eval_every: s.eval_every.max(1),
        eval_samples: s.eval_samples,
    }
}

/// The shape prior a command reads: the file at `path`, or the shipped chair prior without
/// one; returns its bytes and a label.
pub fn load_prior(path: Option<&std::path::Path>) -> Result<(Vec<u8>, String)> {
    let Some(path) = path else {
        return Ok((rendernet::nn::prior::PRIOR_CHAIRS_WEIGHTS.to_vec(), "the shipped chair prior".into()));
    };
    let bytes = std::fs::read(path).map_err(|e| rendernet::Error::Io { path: path.display().to_string(), source: e })?;
    Ok((bytes, path.display().to_string()))
}

/// Runs prior training.
pub fn run(a: TrainPriorArgs) -> Result<()> {
    let cfg = PriorConfig { preset: PriorPreset::small(), data: a.data.clone(), steps: step_config(&a.s) };
    with_bar(&a.s, "held-out IoU", |report| train_prior(&Gpu::new()?, &cfg, report))
}

/// Runs texture decoder training.
pub fn run_texture(a: TrainTextureArgs) -> Result<()> {
    let mut steps = step_config(&a.s);
    steps.eval_samples = steps.eval_samples.max(1);
    let cfg = TextureConfig { preset: TexturePreset::small(), steps };
    with_bar(&a.s, "held-out texture PSNR", |report| train_texture(&Gpu::new()?, &cfg, report))
}
