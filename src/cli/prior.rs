//! `rendernet train-prior`: the 3D shape autoencoder used as a shape prior, with a progress
//! bar, checkpoints and held-out IoU.

use clap::Args;
use rendernet::nn::prior::PriorPreset;
use rendernet::train::prior::{PriorConfig, train_prior};
use rendernet::{Gpu, Result};
use std::path::PathBuf;

/// Train the shape prior on a dataset's grids.
#[derive(Args)]
pub struct TrainPriorArgs {
    /// Dataset directory from `rendernet dataset` (grid side a multiple of 16, e.g. `--res 32`).
    #[arg(long)]
    data: PathBuf,
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
    /// Grids per step.
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
    /// Held-out grids per evaluation (0 = all).
    #[arg(long, default_value_t = 100)]
    eval_samples: usize,
}

/// Runs prior training with a progress bar (a line per 100 steps without a terminal).
pub fn run(a: TrainPriorArgs) -> Result<()> {
    super::train::refuse_overwrite(&a.out, a.resume.is_some(), a.force)?;
    let cfg = PriorConfig {
        preset: PriorPreset::small(),
        data: a.data,
        out: a.out,
        steps: a.steps,
        resume: a.resume,
        batch: a.batch.max(1),
        lr: a.lr,
        seed: a.seed,
        eval_every: a.eval_every.max(1),
        eval_samples: a.eval_samples,
    };
    let gpu = Gpu::new()?;
    let bar = super::train::step_bar(cfg.steps);
    let mut ema = None::<f32>;
    let mut last = String::from("-");
    let iou = train_prior(&gpu, &cfg, |step, loss, iou| {
        let e = ema.map_or(loss, |e| 0.98 * e + 0.02 * loss);
        ema = Some(e);
        if let Some(i) = iou {
            last = format!("{i:.3}");
        }
        let msg = format!("loss {e:.4} held-out IoU {last}");
        bar.set_position(step);
        if bar.is_hidden() && (step % 100 == 0 || iou.is_some()) {
            println!("step {step}/{}: {msg}", cfg.steps);
        }
        bar.set_message(msg);
    })?;
    bar.finish();
    println!("final held-out IoU {iou:.3}; weights in {}", cfg.out.with_extension("weights.safetensors").display());
    Ok(())
}
