//! `rendernet train`: patch training with a progress bar, checkpoints and a curve PNG.

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rendernet::nn::rendernet::Preset;
use rendernet::train::{Augment, Progress, TrainConfig, train};
use rendernet::{Error, Gpu, Result};
use std::path::PathBuf;

/// Train RenderNet on a dataset from `rendernet dataset`.
#[derive(Args)]
pub struct TrainArgs {
    /// Network size, smallest first: nano, tiny (the default render's), small, base (all
    /// train on a CPU through lavapipe; base slowly), or paper (the appendix; real GPUs); or
    /// the paper's baselines ec and ec-deep (whole frames, no crops; BCE on the image).
    #[arg(long, default_value = "tiny")]
    preset: String,
    /// Dataset directory (its manifest decides the shader: phong trains the normal, albedo and
    /// mask heads shaded by the Phong op; other shaders train a direct image head).
    #[arg(long)]
    data: PathBuf,
    /// Checkpoint to write (atomically). Next to it: <out>.weights.safetensors (parameters
    /// only, for `render` and `eval`) and <out>.curve.png (log loss in red, PSNR in blue).
    /// An existing <out> is only replaced with --resume or --force.
    #[arg(long)]
    out: PathBuf,
    /// Overwrite an existing --out checkpoint (and the files beside it) with a fresh run.
    #[arg(long)]
    force: bool,
    /// Optimizer steps in all; crops grow from 1/8 to 1/2 of the grid over three equal phases.
    #[arg(long, default_value_t = 6000)]
    steps: u64,
    /// Resume from this checkpoint (same preset and dataset shader).
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Grid side the network reads: every dataset grid is resampled to N^3 before the camera
    /// resampling. Default: the preset's (32), or with --resume the checkpoint's. The paper
    /// reads 64, which keeps thin parts and a 64^3 bunny's face; it costs the network nothing
    /// (its convs run on the camera grid). Recorded in the weights' metadata (`input`), so
    /// `render` and `eval` read grids at the same side.
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..=rendernet::nn::rendernet::MAX_INPUT as u64))]
    input: Option<u64>,
    /// Start a fresh run from these weights wherever a tensor's name and shape match (a
    /// Phong network's trunk under a contour, toon or AO head, or grey weights under a colour
    /// network's first conv); the other layers start from their initialisation.
    #[arg(long, conflicts_with = "resume")]
    init: Option<PathBuf>,
    /// Samples per step.
    #[arg(long, default_value_t = 1)]
    batch: usize,
    /// Initial learning rate (Adam, beta1 0.5 as the original code).
    #[arg(long, default_value_t = 5e-4)]
    lr: f32,
    /// Learning-rate decay factor per --decay-steps (the original's 0.96).
    #[arg(long, default_value_t = 0.96)]
    decay: f32,
    /// Steps per decay period.
    #[arg(long, default_value_t = 500)]
    decay_steps: u64,
    /// Seed for initialisation, sample order and crops.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Steps between held-out evaluations (each also writes the checkpoint).
    #[arg(long, default_value_t = 500)]
    eval_every: u64,
    /// Held-out samples per evaluation (0 = all).
    #[arg(long, default_value_t = 50)]
    eval_samples: usize,
    /// Train on a fixed camera-grid window (a multiple of 4, at most the grid side) instead of
    /// the growing crop schedule; for fine-tuning a resumed checkpoint.
    #[arg(long)]
    crop: Option<usize>,
    /// Robustness training: half the samples lose a random fraction (up to this) of their
    /// occupied voxels; the target stays the clean image. 0 = off.
    #[arg(long, default_value_t = 0.0)]
    augment_dropout: f64,
    /// Robustness training: half the samples get a random fraction (up to this) of the empty
    /// voxels inside the object's box switched on. 0 = off.
    #[arg(long, default_value_t = 0.0)]
    augment_salt: f64,
}

/// A fresh run over an existing checkpoint would replace hours of training at its first
/// evaluation; --resume continues it (same file or not), --force says the loss is meant.
pub(crate) fn refuse_overwrite(out: &std::path::Path, resume: bool, force: bool) -> Result<()> {
    if !resume && !force && out.exists() {
        return Err(Error::Invalid(format!(
            "--out {}: the file exists (a checkpoint of an earlier run?); pass --resume {0} to continue it, \
             or --force to overwrite it with a fresh run",
            out.display()
        )));
    }
    Ok(())
}

/// The progress bar of a training run of `steps` steps (hidden without a terminal).
pub(crate) fn step_bar(steps: u64) -> ProgressBar {
    let bar = ProgressBar::new(steps);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} [{elapsed_precise}<{eta_precise}] {msg}").expect("static template"));
    bar
}

/// Runs training, drawing a progress bar with loss and images/s.
pub fn run(a: TrainArgs) -> Result<()> {
    refuse_overwrite(&a.out, a.resume.is_some(), a.force)?;
    let preset = Preset::by_name(&a.preset)?;
    let preset = match (a.input, &a.resume) {
        (Some(n), _) => preset.with_input(n as usize),
        (None, Some(ck)) => {
            let bytes = std::fs::read(ck).map_err(|e| Error::Io { path: ck.display().to_string(), source: e })?;
            let input = preset.clone().for_weights(&bytes, &ck.display().to_string())?.input;
            preset.with_input(input)
        }
        (None, None) => preset,
    };
    let cfg = TrainConfig {
        preset,
        data: a.data,
        out: a.out,
        steps: a.steps,
        resume: a.resume,
        init: a.init,
        batch: a.batch.max(1),
        lr: a.lr,
        decay: a.decay,
        decay_steps: a.decay_steps,
        seed: a.seed,
        eval_every: a.eval_every.max(1),
        eval_samples: a.eval_samples,
        window: a.crop,
        augment: Augment { dropout: a.augment_dropout, salt: a.augment_salt },
    };
    let gpu = Gpu::new()?;
    let bar = step_bar(cfg.steps);
    let mut ema = None::<f32>;
    let mut last_psnr = String::from("-");
    let psnr = train(&gpu, &cfg, |p| match p {
        Progress::Step { step, loss, lr, window, images_per_s } => {
            let e = ema.map_or(loss, |e| 0.98 * e + 0.02 * loss);
            ema = Some(e);
            bar.set_position(step);
            let msg = format!("loss {e:.4} lr {lr:.1e} crop {window} {images_per_s:.1} img/s psnr {last_psnr}");
            // Without a terminal (nohup, CI logs) the bar is hidden: log a line now and then.
            if bar.is_hidden() && step % 100 == 0 {
                println!("step {step}/{}: {msg}", bar.length().unwrap_or(0));
            }
            bar.set_message(msg);
        }
        Progress::Init { loaded, widened, fresh } => {
            let init = cfg.init.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
            let grown = if widened.is_empty() { String::new() } else { format!(", {} widened from grey ({})", widened.len(), widened.join(", ")) };
            let fresh = if fresh.is_empty() { String::new() } else { format!(", {} initialised fresh ({})", fresh.len(), fresh.join(", ")) };
            let line = format!("started from {init}: {loaded} tensors taken{grown}{fresh}");
            if bar.is_hidden() {
                println!("{line}");
            } else {
                bar.println(line);
            }
        }
        Progress::Eval { step, psnr, checkpoint } => {
            last_psnr = format!("{psnr:.2}");
            let line = format!("step {step}: held-out PSNR {psnr:.2} dB, checkpoint {}", checkpoint.display());
            if bar.is_hidden() {
                println!("{line}");
            } else {
                bar.println(line);
            }
        }
    })?;
    bar.finish();
    println!("final held-out PSNR {psnr:.2} dB; weights in {}", cfg.out.with_extension("weights.safetensors").display());
    Ok(())
}

/// Flags of `rendernet curve`.
#[derive(Args)]
pub struct CurveArgs {
    /// A training log (`<out>.log.csv`, written by `train` at every evaluation).
    #[arg(long)]
    log: PathBuf,
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
}

/// Redraws a run's curve from its log (the same chart `train` keeps next to the checkpoint).
pub fn run_curve(a: CurveArgs) -> Result<()> {
    super::output::check_png_out(&a.out)?;
    if !a.log.is_file() {
        return Err(rendernet::Error::Invalid(format!("--log {}: no such file", a.log.display())));
    }
    let (loss, psnr) = rendernet::train::plot::read_log(&a.log, u64::MAX);
    if loss.is_empty() && psnr.is_empty() {
        return Err(rendernet::Error::Invalid(format!("--log {}: no step,loss,psnr rows", a.log.display())));
    }
    rendernet::train::plot::write_curve(&a.out, &loss, &psnr).map_err(|e| rendernet::Error::Invalid(format!("{}: {e}", a.out.display())))?;
    println!("wrote {} ({} loss rows, {} evaluations)", a.out.display(), loss.len(), psnr.len());
    Ok(())
}
