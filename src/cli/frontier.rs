//! `rendernet frontier`: speed against accuracy. Every model given (and the shipped one) is
//! scored on a dataset's held-out split and timed on this adapter; the reference renderer is
//! timed too and drawn as the exact point. Chart (PNG) and JSON or a table.

use clap::Args;
use rendernet::chart::{self, Cap, Options};
use rendernet::data::Dataset;
use rendernet::metrics::PSNR_CAP;
use rendernet::nn::render::{NANO_PHONG_WEIGHTS, Renderer, TINY_PHONG_WEIGHTS};
use rendernet::train::{eval::evaluate_bytes, head_for};
use rendernet::{Error, Gpu, Light, Preset, RayMarcher, Result, Shader, View, bench};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `rendernet frontier`.
#[derive(Args, Debug)]
pub struct FrontierArgs {
    /// Phong dataset whose held-out split scores every model (shapes the models never saw).
    #[arg(long)]
    data: PathBuf,
    /// Held-out samples per model, spread over the split (0 = all).
    #[arg(long, default_value_t = 100)]
    samples: usize,
    /// A model to add: LABEL=PRESET:WEIGHTS (e.g. nano=nano:nano.weights.safetensors);
    /// repeat the flag for more. The shipped nano and tiny weights are always included.
    #[arg(long = "model", value_name = "LABEL=PRESET:WEIGHTS")]
    models: Vec<String>,
    /// Timed forwards per model (the median is reported), after one warm-up.
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Chart: object PSNR against forward milliseconds, one point per model.
    #[arg(long, default_value = "frontier.png")]
    out: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// One model to place on the chart.
struct Model {
    label: String,
    preset: Preset,
    weights: Vec<u8>,
    source: String,
}

fn parse_model(s: &str) -> Result<Model> {
    let bad = || Error::Invalid(format!("--model {s}: expected LABEL=PRESET:WEIGHTS, e.g. nano=nano:nano.weights.safetensors"));
    let (label, rest) = s.split_once('=').ok_or_else(bad)?;
    let (preset, path) = rest.split_once(':').ok_or_else(bad)?;
    if label.is_empty() || path.is_empty() {
        return Err(bad());
    }
    let weights = std::fs::read(path).map_err(|e| Error::Io { path: path.to_string(), source: e })?;
    Ok(Model { label: label.to_string(), preset: Preset::by_name(preset)?, weights, source: path.to_string() })
}

/// Median milliseconds of `repeat` calls of `f`, after one warm-up call (pipeline compiles).
fn median_ms(repeat: usize, mut f: impl FnMut() -> Result<()>) -> Result<f64> {
    f()?;
    let mut v = Vec::with_capacity(repeat);
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        f()?;
        v.push(t.elapsed().as_secs_f64() * 1e3);
    }
    Ok(bench::median(&v))
}

/// Scores and times every model and the reference renderer; writes the chart.
pub fn run(a: FrontierArgs) -> Result<()> {
    super::output::check_png_out(&a.out)?;
    let shipped = |p: Preset, w: &[u8]| Model { label: format!("{} (shipped)", p.name), preset: p, weights: w.to_vec(), source: "embedded".into() };
    let mut models = vec![shipped(Preset::nano(), NANO_PHONG_WEIGHTS), shipped(Preset::tiny(), TINY_PHONG_WEIGHTS)];
    for m in &a.models {
        models.push(parse_model(m)?);
    }
    let ds = Dataset::open(&a.data)?;
    let head = head_for(&ds)?;
    let gpu = Gpu::new()?;
    let clock = bench::default_clock(&gpu);
    let ceiling = bench::fma_ceiling(&gpu, clock, 5)?;
    // Timing scene: the default bunny, whole 128 px frame (no crop), as `render --no-crop`.
    let (grid, view, light) = (rendernet::bunny(), View::default(), Light::default());
    let mut rows = Vec::new();
    for m in &models {
        let report = evaluate_bytes(&gpu, &m.preset, head, &m.weights, &m.source, &ds, a.samples)?;
        let mut net = Renderer::new(&gpu, m.preset.clone(), &m.weights, &m.source, 128)?.with_crop_margin(None);
        let ms = median_ms(a.repeat, || net.render(&gpu, &grid, &view, &light).map(drop))?;
        let params = rendernet::graph::params::parse_safetensors(&m.weights, &m.source)?.0.values().map(|(_, v)| v.len()).sum::<usize>();
        rows.push((m, params, report, ms));
    }
    let opts = rendernet::reference::Options { supersample: 2, ..Default::default() };
    let marcher = RayMarcher::new(&gpu).with_options(opts);
    let ref_ms = median_ms(a.repeat, || marcher.render(&gpu, &grid, &view, &light, Shader::Phong, 128).map(drop))?;
    let adapter = gpu.info.name.clone();
    let cpu = bench::cpu_model();
    let points: Vec<(f64, f64, String)> = rows.iter().map(|(m, _, r, ms)| (*ms, r.object_psnr.mean as f64, m.label.clone())).collect();
    let groups = vec![("RenderNet", points), ("reference renderer (exact, not learned)", vec![(ref_ms, PSNR_CAP, "reference".to_string())])];
    let slowest = rows.iter().map(|row| row.3).fold(ref_ms, f64::max);
    let options = Options { cap: Some(Cap { at: PSNR_CAP, note: "exact".into() }), x_range: Some((0.0, 1.15 * slowest)), ..Options::default() };
    chart::scatter_chart(&a.out, "Speed against accuracy (held-out object PSNR)", &format!("forward ms, 128 px, on {adapter}"), "object PSNR (dB)", &groups, &options)?;
    if a.json {
        let models: Vec<_> = rows
            .iter()
            .map(|(m, params, r, ms)| {
                json!({
                    "label": m.label, "preset": m.preset.name, "weights": m.source, "parameters": params,
                    "object_psnr": r.object_psnr.mean, "object_psnr_ci95": r.object_psnr.ci95, "psnr": r.mean, "ssim": r.ssim.mean,
                    "black_object_psnr": r.black_object_psnr, "black_psnr": r.black, "samples": r.count, "forward_ms": ms,
                })
            })
            .collect();
        let j = json!({ "adapter": adapter, "cpu": cpu, "fma_ceiling_gflops": ceiling, "data": a.data.display().to_string(),
            "models": models, "reference": { "forward_ms": ref_ms, "object_psnr": null, "note": "the renderer that makes the targets: exact by definition" } });
        println!("{}", serde_json::to_string_pretty(&j).expect("plain JSON"));
    } else {
        println!("adapter: {adapter}; cpu: {}; FMA ceiling {ceiling:.1} GFLOP/s (same run)", cpu.as_deref().unwrap_or("unknown"));
        println!("{:<18} {:>10} {:>20} {:>10} {:>8} {:>11}", "model", "parameters", "object PSNR (black)", "full PSNR", "SSIM", "forward ms");
        for (m, params, r, ms) in &rows {
            println!("{:<18} {params:>10} {:>12.2} ({:>5.2}) {:>10.2} {:>8.3} {ms:>11.1}", m.label, r.object_psnr.mean, r.black_object_psnr, r.mean, r.ssim.mean);
        }
        println!("{:<18} {:>10} {:>20} {:>10} {:>8} {:>11.1}", "reference", "-", "exact", "-", "-", ref_ms);
        println!("chart: {}", a.out.display());
    }
    Ok(())
}
