//! Learning-rate sweep: trains the same short run at several learning rates and charts the
//! loss against the step, one line per rate, so the rate where training stops improving or
//! diverges is visible; a run whose loss turns NaN or infinite stops with the trainer's
//! error (the NaN guard), which the table reports.
//!
//! `cargo run --release --example lr_sweep -- --data DATASET [--steps 300] [--out lr-sweep.png]`

mod common;

use clap::Parser;
use rendernet::Gpu;
use rendernet::nn::rendernet::Preset;
use rendernet::train::{Augment, Progress, TrainConfig, train};
use std::path::PathBuf;
use std::process::ExitCode;

/// Trains `--steps` steps at each `--lrs` rate (fixed crop, no decay) and charts the losses.
#[derive(Parser)]
struct Args {
    /// Dataset directory (`rendernet dataset` output).
    #[arg(long)]
    data: PathBuf,
    /// Learning rates to try, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1e-4,5e-4,2e-3,1e-2,5e-2,2e-1,1")]
    lrs: Vec<f32>,
    /// Steps per run.
    #[arg(long, default_value_t = 300)]
    steps: u64,
    /// Samples per step.
    #[arg(long, default_value_t = 2)]
    batch: usize,
    /// Camera-grid crop (a multiple of 4).
    #[arg(long, default_value_t = 16)]
    crop: usize,
    /// Chart (PNG); the runs' checkpoints go to a temporary folder.
    #[arg(long, default_value = "lr-sweep.png", value_parser = common::png_out)]
    out: PathBuf,
}

/// One run's outcome.
struct Run {
    lr: f32,
    losses: Vec<(f64, f64)>,
    error: Option<String>,
}

fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let gpu = Gpu::new()?;
    let dir = std::env::temp_dir().join(format!("rendernet-lr-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let mut runs = Vec::new();
    for &lr in &a.lrs {
        let cfg = TrainConfig {
            preset: Preset::tiny(),
            data: a.data.clone(),
            out: dir.join(format!("lr{lr}.ckpt")),
            steps: a.steps,
            resume: None,
            init: None,
            batch: a.batch,
            lr,
            decay: 1.0,
            decay_steps: 1000,
            seed: 0,
            eval_every: a.steps,
            eval_samples: 8,
            window: Some(a.crop),
            augment: Augment::default(),
        };
        let mut losses = Vec::new();
        let outcome = train(&gpu, &cfg, |p| {
            if let Progress::Step { step, loss, .. } = p {
                losses.push((step as f64, loss as f64));
            }
        });
        let r = Run { lr, losses, error: outcome.err().map(|e| e.to_string()) };
        let tail: Vec<f64> = r.losses.iter().rev().take(20).map(|l| l.1).collect();
        let last = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
        println!(
            "lr {lr:<8} mean loss of the last 20 steps {last:.4}  {}",
            r.error.as_deref().map_or("finished".to_string(), |e| format!("stopped: {e}"))
        );
        runs.push(r);
    }
    // Smoothed over 10 steps so the lines can be told apart.
    let series: Vec<(String, Vec<(f64, f64)>)> = runs
        .iter()
        .map(|r| {
            let pts = r.losses.chunks(10).map(|c| (c[c.len() - 1].0, c.iter().map(|l| l.1).sum::<f64>() / c.len() as f64)).collect();
            (format!("lr {}", r.lr), pts)
        })
        .collect();
    let opts = rendernet::chart::Options { log_y: true, ..Default::default() };
    rendernet::chart::line_chart(&a.out, "Training loss by learning rate (tiny, Adam, no decay)", "step", "loss (mean of 10 steps)", &series, &opts)?;
    println!("wrote {}", a.out.display());
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
