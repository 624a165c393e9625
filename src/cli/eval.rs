//! `rendernet eval`: mean held-out PSNR with a 95% interval and per-shape PSNR.

use clap::Args;
use rendernet::data::Dataset;
use rendernet::nn::rendernet::Preset;
use rendernet::train::{eval::evaluate, head_for};
use rendernet::{Gpu, Result};
use std::path::PathBuf;

/// Evaluate weights on a dataset's held-out split.
#[derive(Args)]
pub struct EvalArgs {
    /// Weights (safetensors, as written by `train` or shipped in weights/).
    #[arg(long)]
    weights: PathBuf,
    /// Dataset directory.
    #[arg(long)]
    data: PathBuf,
    /// Network size the weights belong to.
    #[arg(long, default_value = "tiny")]
    preset: String,
    /// Held-out samples to evaluate (0 = all).
    #[arg(long, default_value_t = 0)]
    samples: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Evaluates and prints the report.
pub fn run(a: EvalArgs) -> Result<()> {
    let gpu = Gpu::new()?;
    let ds = Dataset::open(&a.data)?;
    let p = Preset::by_name(&a.preset)?;
    let r = evaluate(&gpu, &p, head_for(&ds)?, &a.weights, &ds, a.samples)?;
    if a.json {
        let shapes: Vec<String> = r.per_shape.iter().map(|(k, v)| format!("\"{k}\":{v:.3}")).collect();
        println!(
            "{{\"psnr_mean\":{:.3},\"psnr_ci95\":{:.3},\"black_image_psnr\":{:.3},\"samples\":{},\"per_shape\":{{{}}}}}",
            r.mean,
            r.ci95,
            r.black,
            r.count,
            shapes.join(",")
        );
    } else {
        println!("held-out PSNR {:.2} dB ± {:.2} (95%), {} samples, {} shapes", r.mean, r.ci95, r.count, r.per_shape.len());
        println!("an all-black image scores {:.2} dB on the same samples (the background's share)", r.black);
        for (k, v) in &r.per_shape {
            println!("  shape {k}: {v:.2} dB");
        }
    }
    Ok(())
}
