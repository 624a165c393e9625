//! `rendernet frontier`: speed against accuracy. Every model given (and the shipped one) is
//! scored on a dataset's held-out split and timed on this adapter; the reference renderer is
//! timed too and drawn as the exact point. Chart (PNG) and JSON or a table.

use clap::Args;
use rendernet::chart::{self, Cap, Options};
use rendernet::data::Dataset;
use rendernet::metrics::PSNR_CAP;
use rendernet::nn::render::{BASE_PHONG_WEIGHTS, CROP_MARGIN, NANO_PHONG_WEIGHTS, Renderer, TINY_PHONG_WEIGHTS};
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
    /// A model to add: LABEL=PRESET:WEIGHTS (e.g. ec=ec:weights/ladder/ec-phong-2000.safetensors;
    /// presets nano, tiny, small, base, paper, ec, ec-deep); repeat the flag for more. The
    /// shipped nano and tiny weights are always included.
    #[arg(long = "model", value_name = "LABEL=PRESET:WEIGHTS")]
    models: Vec<String>,
    /// Timed forwards per model (the median is reported), after one warm-up.
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Chart: object and full-frame PSNR against whole-frame forward milliseconds and against
    /// training hours (from the weights' metadata), one point per model.
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
    /// Training images seen and wall seconds, from the weights' metadata (`rendernet train`
    /// records them; absent in files written before it did).
    images: Option<u64>,
    train_seconds: Option<f64>,
    parameters: usize,
}

impl Model {
    fn new(label: String, preset: Preset, weights: Vec<u8>, source: String) -> Result<Model> {
        let (tensors, meta) = rendernet::graph::params::parse_safetensors(&weights, &source)?;
        let images = meta.get("images").and_then(|v| v.parse().ok());
        let train_seconds = meta.get("train_seconds").and_then(|v| v.parse().ok());
        let parameters = tensors.values().map(|(_, v)| v.len()).sum();
        Ok(Model { label, preset, weights, source, images, train_seconds, parameters })
    }
}

/// The model family, for the chart's groups and the JSON.
fn family(p: &Preset) -> &'static str {
    if p.fully_convolutional() { "RenderNet" } else { "EC baselines" }
}

/// A model, its held-out scores, whole-frame and cropped forward ms.
type Row<'a> = (&'a Model, rendernet::train::eval::EvalReport, f64, f64);

/// Four panels: object and full-frame PSNR, each against forward ms (the reference renderer
/// as the exact point) and against training hours (models whose weights record it).
fn write_chart(out: &std::path::Path, rows: &[Row], ref_ms: f64, adapter: &str) -> Result<()> {
    let psnrs: [(&str, fn(&rendernet::train::eval::EvalReport) -> f64); 2] =
        [("object PSNR (dB)", |r| r.object_psnr.mean as f64), ("full-frame PSNR (dB)", |r| r.mean as f64)];
    let mut panels = Vec::new();
    for timed in [true, false] {
        for (y_label, y) in psnrs {
            let mut groups: Vec<(String, Vec<(f64, f64, String)>)> = Vec::new();
            for (m, r, ms, _) in rows {
                let x = if timed { Some(*ms) } else { m.train_seconds.map(|s| s / 3600.0) };
                let Some(x) = x else { continue };
                let name = family(&m.preset).to_string();
                let point = (x, y(r), m.label.clone());
                match groups.iter_mut().find(|g| g.0 == name) {
                    Some(g) => g.1.push(point),
                    None => groups.push((name, vec![point])),
                }
            }
            let mut options = Options { size: (760, 520), ..Options::default() };
            let (title, x_label) = if timed {
                groups.push(("reference renderer (exact, not learned)".into(), vec![(ref_ms, PSNR_CAP, "reference".into())]));
                options.cap = Some(Cap { at: PSNR_CAP, note: "exact".into() });
                let slowest = rows.iter().map(|row| row.2).fold(ref_ms, f64::max);
                options.x_range = Some((0.0, 1.15 * slowest));
                (format!("{y_label} against speed"), format!("forward ms, whole 128 px frame, on {adapter}"))
            } else {
                let longest = rows.iter().filter_map(|row| row.0.train_seconds).fold(0.0, f64::max) / 3600.0;
                options.x_range = Some((0.0, 1.15 * longest.max(0.1)));
                (format!("{y_label} against training time"), "training hours (wall clock, 2-core CPU, lavapipe)".to_string())
            };
            panels.push(chart::ScatterPanel { title, x_label, y_label: y_label.into(), groups, options });
        }
    }
    chart::scatter_panels(out, &panels, 2)
}

fn parse_model(s: &str) -> Result<Model> {
    let bad = || Error::Invalid(format!("--model {s}: expected LABEL=PRESET:WEIGHTS, e.g. nano=nano:nano.weights.safetensors"));
    let (label, rest) = s.split_once('=').ok_or_else(bad)?;
    let (preset, path) = rest.split_once(':').ok_or_else(bad)?;
    if label.is_empty() || path.is_empty() {
        return Err(bad());
    }
    let weights = std::fs::read(path).map_err(|e| Error::Io { path: path.to_string(), source: e })?;
    Model::new(label.to_string(), Preset::by_name(preset)?, weights, path.to_string())
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
    let shipped = |p: Preset, w: &[u8]| Model::new(format!("{} (shipped)", p.name), p, w.to_vec(), "embedded".into());
    let mut models = vec![shipped(Preset::nano(), NANO_PHONG_WEIGHTS)?, shipped(Preset::tiny(), TINY_PHONG_WEIGHTS)?, shipped(Preset::base(), BASE_PHONG_WEIGHTS)?];
    for m in &a.models {
        models.push(parse_model(m)?);
    }
    let ds = Dataset::open(&a.data)?;
    let head = head_for(&ds)?;
    let gpu = Gpu::new()?;
    let clock = bench::default_clock(&gpu);
    let ceiling = bench::fma_ceiling(&gpu, clock, 5)?;
    // Timing scene: the default bunny, whole 128 px frame (no crop) as `render --no-crop`,
    // then as `render` runs it by default (cropped to the object).
    let (grid, view, light) = (rendernet::bunny(), View::default(), Light::default());
    let mut rows = Vec::new();
    for m in &models {
        let report = evaluate_bytes(&gpu, &m.preset, head, &m.weights, &m.source, &ds, a.samples)?;
        let mut net = Renderer::new(&gpu, m.preset.clone(), &m.weights, &m.source, 128)?.with_crop_margin(None);
        let ms = median_ms(a.repeat, || net.render(&gpu, &grid, &view, &light).map(drop))?;
        // As `render` runs it: RenderNet on the object's window only (EC cannot crop).
        let cropped = if m.preset.fully_convolutional() {
            let mut net = net.with_crop_margin(Some(CROP_MARGIN));
            median_ms(a.repeat, || net.render(&gpu, &grid, &view, &light).map(drop))?
        } else {
            ms
        };
        rows.push((m, report, ms, cropped));
    }
    let opts = rendernet::reference::Options { supersample: 2, ..Default::default() };
    let marcher = RayMarcher::new(&gpu).with_options(opts);
    let ref_ms = median_ms(a.repeat, || marcher.render(&gpu, &grid, &view, &light, Shader::Phong, 128).map(drop))?;
    let adapter = gpu.info.name.clone();
    let cpu = bench::cpu_model();
    write_chart(&a.out, &rows, ref_ms, &adapter)?;
    if a.json {
        let models: Vec<_> = rows
            .iter()
            .map(|(m, r, ms, cropped)| {
                json!({
                    "label": m.label, "preset": m.preset.name, "arch": family(&m.preset), "weights": m.source, "parameters": m.parameters,
                    "train_images": m.images, "train_seconds": m.train_seconds,
                    "object_psnr": r.object_psnr.mean, "object_psnr_ci95": r.object_psnr.ci95, "psnr": r.mean, "ssim": r.ssim.mean,
                    "black_object_psnr": r.black_object_psnr, "black_psnr": r.black, "samples": r.count, "forward_ms": ms, "forward_ms_cropped": cropped,
                })
            })
            .collect();
        let j = json!({ "adapter": adapter, "cpu": cpu, "fma_ceiling_gflops": ceiling, "data": a.data.display().to_string(),
            "models": models, "reference": { "forward_ms": ref_ms, "object_psnr": null, "note": "the renderer that makes the targets: exact by definition" } });
        println!("{}", serde_json::to_string_pretty(&j).expect("plain JSON"));
    } else {
        println!("adapter: {adapter}; cpu: {}; FMA ceiling {ceiling:.1} GFLOP/s (same run)", cpu.as_deref().unwrap_or("unknown"));
        println!("{:<18} {:>10} {:>20} {:>10} {:>8} {:>11} {:>11}", "model", "parameters", "object PSNR (black)", "full PSNR", "SSIM", "forward ms", "cropped ms");
        for (m, r, ms, cropped) in &rows {
            println!("{:<18} {:>10} {:>12.2} ({:>5.2}) {:>10.2} {:>8.3} {ms:>11.1} {cropped:>11.1}", m.label, m.parameters, r.object_psnr.mean, r.black_object_psnr, r.mean, r.ssim.mean);
        }
        println!("{:<18} {:>10} {:>20} {:>10} {:>8} {:>11.1}", "reference", "-", "exact", "-", "-", ref_ms);
        println!("chart: {}", a.out.display());
    }
    Ok(())
}
