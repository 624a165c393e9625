//! `rendernet eval-shape`: shape recovery through the shape prior on held-out samples at
//! their true pose and light, scored by voxel IoU (library: `rendernet::invert::evaluate_shapes`).

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rendernet::data::Dataset;
use rendernet::invert::{InvertOptions, PoseSource, ShapeOptions, evaluate_shapes};
use rendernet::nn::prior::PriorPreset;
use rendernet::train::eval::Interval;
use rendernet::{Error, Gpu, Result};
use std::path::PathBuf;

/// Flags of `rendernet eval-shape`.
#[derive(Args, Debug)]
pub struct EvalShapeArgs {
    /// Phong dataset whose held-out samples (grid, view, light, image) are used; its grids
    /// must have the prior's side (32).
    #[arg(long)]
    data: PathBuf,
    /// Shape prior weights from `rendernet train-prior` (`<out>.weights.safetensors`); the
    /// shipped chair prior without it.
    #[arg(long, value_name = "FILE")]
    prior: Option<PathBuf>,
    /// Held-out shapes, spread over the split (0 = all).
    #[arg(long, default_value_t = 8)]
    samples: usize,
    /// Images of each shape it is recovered from (the dataset's first views of it; `dataset
    /// --views` must be at least this).
    #[arg(long, default_value_t = 1)]
    views: usize,
    #[command(flatten)]
    net: super::weights::WeightsArgs,
    /// Adam steps on the code per refined start.
    #[arg(long, default_value_t = ShapeOptions::default().steps)]
    steps: usize,
    /// Training shapes' codes (kept in the prior's weights) scored as starts beside the mean code.
    #[arg(long, default_value_t = ShapeOptions::default().candidates)]
    candidates: usize,
    /// Best-scoring starts refined by Adam.
    #[arg(long, default_value_t = ShapeOptions::default().keep)]
    keep: usize,
    /// Weight of the code's Gaussian prior (from the prior's training codes) against the image MSE.
    #[arg(long, default_value_t = ShapeOptions::default().prior_weight)]
    prior_weight: f64,
    /// Adam's step on the code (which lives in 0..1).
    #[arg(long, default_value_t = ShapeOptions::default().lr)]
    lr: f64,
    /// Leave the silhouette out of the loss (by default the MSE between the network's mask
    /// and the image's foreground is added to the image MSE).
    #[arg(long)]
    no_silhouette: bool,
    /// Search each image's camera and light too (one view per shape; `invert --prior`'s
    /// alternation, with its default search) instead of taking the dataset's.
    #[arg(long)]
    unknown_pose: bool,
    /// With --unknown-pose: rounds of (camera and light search, shape search).
    #[arg(long, default_value_t = 2)]
    rounds: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Recovers held-out shapes and summarises their IoU.
pub fn run(a: EvalShapeArgs) -> Result<()> {
    let gpu = Gpu::new()?;
    let ds = Dataset::open(&a.data)?;
    let (inv, name) = super::invert::dataset_inverter(&a.net, &ds)?;
    let (prior, prior_name) = super::prior::load_prior(a.prior.as_deref())?;
    let o = ShapeOptions { steps: a.steps, lr: a.lr, start: None, candidates: a.candidates, keep: a.keep, prior_weight: a.prior_weight, silhouette: !a.no_silhouette };
    let pose = if a.unknown_pose { PoseSource::Searched { options: InvertOptions::default(), rounds: a.rounds } } else { PoseSource::Known };
    let bar = ProgressBar::new(a.samples as u64);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} shapes [{elapsed_precise}<{eta_precise}]").expect("static template"));
    let errs = evaluate_shapes(&gpu, &inv, &PriorPreset::small(), &prior, &ds, a.samples, a.views, &pose, &o, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let of = |f: fn(&rendernet::invert::ShapeError) -> f64| Interval::of(&errs.iter().map(f).collect::<Vec<_>>());
    let (iou, retrieved, start, secs) = (of(|e| e.iou), of(|e| e.iou_retrieved), of(|e| e.iou_start), of(|e| e.seconds));
    let angles: Vec<(f64, f64)> = errs.iter().filter_map(|e| e.pose_light_degrees).collect();
    let medians = (!angles.is_empty()).then(|| {
        let (p, l): (Vec<f64>, Vec<f64>) = angles.iter().copied().unzip();
        (rendernet::bench::median(&p), rendernet::bench::median(&l))
    });
    if a.json {
        let mut j = serde_json::json!({
            "shapes": errs.len(), "views": a.views, "iou_mean": iou.mean, "iou_ci95": iou.ci95,
            "retrieved_iou_mean": retrieved.mean, "retrieved_iou_ci95": retrieved.ci95,
            "start_iou_mean": start.mean, "start_iou_ci95": start.ci95, "seconds_per_shape": secs.mean,
            "per_shape": errs.iter().map(|e| serde_json::json!({"shape": e.shape_id, "iou": e.iou, "retrieved_iou": e.iou_retrieved, "start_iou": e.iou_start, "loss": e.loss, "seconds": e.seconds,
                "pose_error_degrees": e.pose_light_degrees.map(|d| d.0), "light_error_degrees": e.pose_light_degrees.map(|d| d.1)})).collect::<Vec<_>>(),
        });
        if let Some((p, l)) = medians {
            j["pose_error_degrees_median"] = p.into();
            j["light_error_degrees_median"] = l.into();
        }
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    let posed = if a.unknown_pose { "pose and light searched" } else { "pose and light known" };
    println!("{} held-out shapes of {}, {} view(s) each, {posed}, {} with prior {}", errs.len(), a.data.display(), a.views, name, prior_name);
    println!("voxel IoU {:.3} ± {:.3} (95%); best start before descent {:.3} ± {:.3}; the prior's mean shape alone {:.3} ± {:.3}", iou.mean, iou.ci95, retrieved.mean, retrieved.ci95, start.mean, start.ci95);
    if let Some((p, l)) = medians {
        println!("camera direction error median {p:.1} deg, light direction {l:.1} deg");
    }
    println!("{:.1} s per shape (mean)", secs.mean);
    Ok(())
}
