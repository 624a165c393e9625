//! Held-out evaluation: full-frame PSNR, object PSNR, SSIM and mask IoU ([`crate::metrics`]),
//! each a mean with a 95% interval beside what an all-black image scores, and per-shape PSNR.

use super::batch::Batch;
use crate::data::{Dataset, Split};
use crate::error::Result;
use crate::graph::Executor;
use crate::gpu::Gpu;
use crate::metrics::Scores;
use crate::nn::rendernet::{Head, Preset, RenderNet};
use crate::reference::Image;
use std::collections::BTreeMap;
use std::path::Path;

/// A score's mean over samples and the half width of its 95% interval.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Interval {
    /// Mean over samples.
    pub mean: f32,
    /// Half width of the 95% interval of the mean (1.96 standard errors).
    pub ci95: f32,
}

impl Interval {
    /// Mean and 95% half width of `xs` (sample standard deviation; 0 for one sample).
    pub fn of(xs: &[f64]) -> Self {
        let n = xs.len().max(1) as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n.max(2.0) - 1.0);
        Interval { mean: mean as f32, ci95: (1.96 * (var / n).sqrt()) as f32 }
    }
}

/// Scores over a split. Full-frame PSNR keeps its original fields (`mean`, `ci95`, `black`,
/// `per_shape`), which the training loop and older readers use.
#[derive(Clone, Debug)]
pub struct EvalReport {
    /// Mean full-frame PSNR (dB) over samples.
    pub mean: f32,
    /// Half width of the 95% interval of `mean` (1.96 standard errors).
    pub ci95: f32,
    /// Samples evaluated.
    pub count: usize,
    /// Mean full-frame PSNR per shape id.
    pub per_shape: BTreeMap<u32, f32>,
    /// Mean full-frame PSNR an all-black image would score on the same samples: with small
    /// objects on a black background PSNR is dominated by the background, so this is the
    /// floor to compare against.
    pub black: f32,
    /// PSNR inside the object box ([`crate::metrics::object_psnr`]).
    pub object_psnr: Interval,
    /// SSIM over the object box ([`crate::metrics::ssim`]).
    pub ssim: Interval,
    /// IoU of the foreground masks ([`crate::metrics::mask_iou`]).
    pub iou: Interval,
    /// Mean object PSNR of an all-black image (its box is the truth's).
    pub black_object_psnr: f32,
    /// Mean SSIM of an all-black image.
    pub black_ssim: f32,
    /// Mean IoU of an all-black image: 0 unless some truth has no foreground.
    pub black_iou: f32,
    /// Mean object PSNR per shape id.
    pub per_shape_object_psnr: BTreeMap<u32, f32>,
    /// The shader's background (0, or 1 for contours): the "black" floors above are then an
    /// all-white image, and every score is taken on the distance from the background
    /// ([`crate::metrics::Scores::on_background`]).
    pub background: f32,
}

/// Renders up to `limit` held-out samples (0 = all) with the weights at `weights` and
/// compares them with the targets (the Phong image, or the single image).
pub fn evaluate(gpu: &Gpu, p: &Preset, head: Head, weights: &Path, ds: &Dataset, limit: usize) -> Result<EvalReport> {
    let bytes = std::fs::read(weights).map_err(|e| crate::error::Error::Io { path: weights.display().to_string(), source: e })?;
    evaluate_bytes(gpu, p, head, &bytes, &weights.display().to_string(), ds, limit)
}

/// [`evaluate`] with the weights' safetensors bytes (`name` labels them in errors), e.g. the
/// embedded ones.
pub fn evaluate_bytes(gpu: &Gpu, p: &Preset, head: Head, weights: &[u8], name: &str, ds: &Dataset, limit: usize) -> Result<EvalReport> {
    // The grid side the weights were trained at (their metadata), as `render` reads them.
    let p = &p.clone().for_weights(weights, name)?;
    let net = RenderNet::build(p, head, 1, [p.cam, p.cam], false)?;
    let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
    ex.load_params_bytes(gpu, weights, name)?;
    ex.training = false;
    ex.keep(net.image);
    let target = match head {
        Head::Phong(_) => "phong",
        Head::Image(_) => "image",
    };
    // The image side (twice the camera grid's for the tiny preset), from the network itself.
    let side = net.graph.info(net.image).shape[3];
    score(ds, limit, |s| {
        let truth = s.images.get(target).ok_or_else(|| crate::error::Error::Invalid(format!("{}: held-out sample lacks the '{target}' image", ds.dir().display())))?;
        if truth.size < side {
            return Err(crate::error::Error::Invalid(format!(
                "{}: images are {}px but preset '{}' renders {side}px (larger images are scored upscaled, as `render` draws them; smaller ones are not)",
                ds.dir().display(),
                truth.size,
                p.name
            )));
        }
        let mut b = Batch::default();
        b.push(p, s, [0, 0, p.cam, p.cam], &[])?;
        ex.feed(gpu, net.grid, &b.grid)?;
        ex.feed(gpu, net.pose, &b.pose)?;
        if let Some(l) = net.light {
            ex.feed(gpu, l, &b.light)?;
        }
        ex.forward(gpu)?;
        let y = ex.read(gpu, net.image)?;
        // Clamped to [0, 1], as images are stored (the metrics clamp too); larger targets are
        // met as `Renderer` meets a larger size: drawn at the trained side, then upscaled.
        let drawn = Image { channels: truth.channels, size: side, data: y.iter().map(|v| v.clamp(0.0, 1.0)).collect() };
        Ok((if truth.size == side { drawn } else { drawn.resized(truth.size) }, truth.clone()))
    })
}

/// The reference renderer's scores when it draws each held-out sample's *input* grid (the
/// grid the network reads, before any resampling) against the target, which the dataset drew
/// from a finer grid (`truth_res`, twice the input's by default). It is what an exact
/// renderer seeing only the network's input scores: a network can beat it only by guessing
/// the detail the input lost (thin parts, the anti-aliased surface), so it says how much of a
/// score bar the input's resolution already rules out.
pub fn evaluate_reference_on_input(gpu: &Gpu, ds: &Dataset, limit: usize) -> Result<EvalReport> {
    let m = &ds.manifest;
    let shader = m.shader_kind()?;
    let marcher = crate::reference::RayMarcher::new(gpu).with_options(crate::data::generate::target_options(m.supersample, m.ao_rays)?);
    let target = crate::data::image_outputs(shader, m.colour).first().map(|o| o.0).unwrap_or("image");
    score(ds, limit, |s| {
        let truth = s.images.get(target).ok_or_else(|| crate::error::Error::Invalid(format!("{}: held-out sample lacks the '{target}' image", ds.dir().display())))?;
        let drawn = marcher.render(gpu, &s.grid, &s.view, &s.light, shader, truth.size as u32)?;
        Ok((drawn, truth.clone()))
    })
}

/// Scores up to `limit` held-out samples (0 = all) of `ds`, `draw` giving each sample's
/// prediction and truth.
fn score(ds: &Dataset, limit: usize, mut draw: impl FnMut(&crate::data::Sample) -> Result<(Image, Image)>) -> Result<EvalReport> {
    let test = ds.split(Split::Test);
    let n = test.spread(limit).count();
    let background = ds.manifest.shader_kind()?.background();
    let (mut net_scores, mut black_scores) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut shapes: BTreeMap<u32, Vec<Scores>> = BTreeMap::new();
    for i in test.spread(limit) {
        let s = test.get(i)?;
        let (pred, truth) = draw(&s)?;
        let scores = Scores::on_background(&pred, &truth, background);
        net_scores.push(scores);
        black_scores.push(Scores::background_floor(&truth, background));
        shapes.entry(s.shape_id).or_default().push(scores);
    }
    let stat = |v: &[Scores], f: fn(&Scores) -> f64| Interval::of(&v.iter().map(f).collect::<Vec<_>>());
    let psnr = stat(&net_scores, |s| s.psnr);
    let per_shape = |f: fn(&Scores) -> f64| shapes.iter().map(|(k, v)| (*k, stat(v, f).mean)).collect();
    Ok(EvalReport {
        mean: psnr.mean,
        ci95: psnr.ci95,
        count: net_scores.len(),
        per_shape: per_shape(|s| s.psnr),
        black: stat(&black_scores, |s| s.psnr).mean,
        object_psnr: stat(&net_scores, |s| s.object_psnr),
        ssim: stat(&net_scores, |s| s.ssim),
        iou: stat(&net_scores, |s| s.iou),
        black_object_psnr: stat(&black_scores, |s| s.object_psnr).mean,
        black_ssim: stat(&black_scores, |s| s.ssim).mean,
        black_iou: stat(&black_scores, |s| s.iou).mean,
        background,
        per_shape_object_psnr: per_shape(|s| s.object_psnr),
    })
}
