//! `rendernet eval`: held-out full-frame PSNR, object PSNR, SSIM and mask IoU, each a mean
//! with a 95% interval beside the all-black image's score, and per-shape PSNR.

use clap::Args;
use rendernet::data::Dataset;
use rendernet::nn::rendernet::Preset;
use rendernet::train::eval::{EvalReport, Interval};
use rendernet::nn::render::shipped_weights;
use rendernet::reference::Shader;
use rendernet::train::eval::{evaluate_bytes, evaluate_reference_on_input};
use rendernet::train::{eval::evaluate, head_for};
use rendernet::{Error, Gpu, Result};
use serde_json::{Map, Value, json};
use std::path::PathBuf;

/// Evaluate weights on a dataset's held-out split.
#[derive(Args)]
pub struct EvalArgs {
    /// Weights (safetensors, as written by `train` or shipped in weights/; a training
    /// checkpoint works too, its Adam state ignored). Default: the embedded weights of
    /// --preset for the dataset's shader, where some are shipped.
    #[arg(long)]
    weights: Option<PathBuf>,
    /// The shader the weights were trained for; must be the dataset's (its manifest.json
    /// names it). A check: evaluating AO weights on Phong images is an error, not a score.
    #[arg(long, value_parser = super::truth::parse_shader)]
    shader: Option<Shader>,
    /// Dataset directory.
    #[arg(long)]
    data: PathBuf,
    /// Network size the weights belong to (nano, tiny, small, base, paper, ec, ec-deep).
    #[arg(long, default_value = "tiny")]
    preset: String,
    /// Held-out samples to evaluate (0 = all).
    #[arg(long, default_value_t = 0)]
    samples: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Also score the reference renderer drawing each sample's input grid (the grid the
    /// network reads) against the target, which the dataset drew from a finer grid: what an
    /// exact renderer that sees only the network's input scores. Printed as a second column
    /// (JSON: `reference_on_input`, the same keys).
    #[arg(long)]
    reference_on_input: bool,
}

/// Evaluates and prints the report.
pub fn run(a: EvalArgs) -> Result<()> {
    let gpu = Gpu::new()?;
    let ds = Dataset::open(&a.data)?;
    let p = Preset::by_name(&a.preset)?;
    let p = if ds.manifest.colour { p.with_colour() } else { p };
    let shader = ds.manifest.shader_kind()?;
    if let Some(want) = a.shader.filter(|&s| s != shader) {
        return Err(Error::Invalid(format!(
            "--shader {}: {} holds {} images (manifest.json); evaluate on a dataset made with `rendernet dataset --shader {0}`",
            want.name(),
            a.data.display(),
            shader.name()
        )));
    }
    let head = head_for(&ds)?;
    let r = match &a.weights {
        Some(w) => evaluate(&gpu, &p, head, w, &ds, a.samples)?,
        None => {
            let w = shipped_weights(&p, shader).ok_or_else(|| {
                let colour = if p.colour { " for coloured voxels (the dataset is painted)" } else { "" };
                Error::Invalid(format!("no {}-{} weights are shipped{colour}; pass --weights FILE", p.name, shader.name()))
            })?;
            evaluate_bytes(&gpu, &p, head, w, &format!("embedded {}-{} weights", p.name, shader.name()), &ds, a.samples)?
        }
    };
    let reference = if a.reference_on_input { Some(evaluate_reference_on_input(&gpu, &ds, a.samples)?) } else { None };
    if a.json {
        let mut j = to_json(&r);
        if let Some(q) = &reference {
            j["reference_on_input"] = to_json(q);
        }
        println!("{j}");
    } else {
        print_text(&r, reference.as_ref());
    }
    Ok(())
}

/// Three decimals, as the text output: float noise in the JSON helps no reader.
fn r3(v: f32) -> Value {
    json!((v as f64 * 1000.0).round() / 1000.0)
}

/// The report as JSON: the original format's keys (`psnr_mean`, `psnr_ci95`,
/// `black_image_psnr`, `samples`, `per_shape`) with per-shape values now objects, plus the
/// other scores' means, intervals and all-black floors.
fn to_json(r: &EvalReport) -> Value {
    let per_shape: Map<String, Value> = r
        .per_shape
        .iter()
        .map(|(k, v)| (k.to_string(), json!({ "psnr": r3(*v), "object_psnr": r3(r.per_shape_object_psnr[k]) })))
        .collect();
    json!({
        "psnr_mean": r3(r.mean),
        "psnr_ci95": r3(r.ci95),
        "black_image_psnr": r3(r.black),
        "samples": r.count,
        "per_shape": per_shape,
        "object_psnr_mean": r3(r.object_psnr.mean),
        "object_psnr_ci95": r3(r.object_psnr.ci95),
        "black_image_object_psnr": r3(r.black_object_psnr),
        "ssim_mean": r3(r.ssim.mean),
        "ssim_ci95": r3(r.ssim.ci95),
        "black_image_ssim": r3(r.black_ssim),
        "iou_mean": r3(r.iou.mean),
        "iou_ci95": r3(r.iou.ci95),
        "black_image_iou": r3(r.black_iou),
    })
}

/// One block, a row per score (with the reference renderer on the input grid when given),
/// then full-frame and object PSNR per shape.
fn print_text(r: &EvalReport, reference: Option<&EvalReport>) {
    let floor = rendernet::metrics::floor_name(r.background);
    println!("held-out scores, {} samples, {} shapes (mean ± 95% interval; an {floor} image beside):", r.count, r.per_shape.len());
    let rows = |r: &EvalReport| {
        [
            ("full-frame PSNR", Interval { mean: r.mean, ci95: r.ci95 }, r.black, 2, " dB"),
            ("object PSNR", r.object_psnr, r.black_object_psnr, 2, " dB"),
            ("SSIM", r.ssim, r.black_ssim, 3, ""),
            ("mask IoU", r.iou, r.black_iou, 3, ""),
        ]
    };
    let score = |s: Interval, d: usize, unit: &str| format!("{:.d$} ± {:.d$}{unit}", s.mean, s.ci95);
    for (k, (name, s, black, d, unit)) in rows(r).into_iter().enumerate() {
        let tail = reference.map(|q| format!("  reference on the input grid {}", score(rows(q)[k].1, d, unit))).unwrap_or_default();
        let black = format!("{floor} {black:.d$}{unit}");
        println!("  {name:<16} {:<20} {black:<20}{tail}", score(s, d, unit));
    }
    println!("per shape, full-frame / object PSNR:");
    for (k, v) in &r.per_shape {
        println!("  shape {k}: {v:.2} / {:.2} dB", r.per_shape_object_psnr[k]);
    }
}
