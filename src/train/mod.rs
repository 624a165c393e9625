//! Training RenderNet: patch training with growing crops, Adam with the original code's
//! exponential decay, periodic held-out evaluation, atomic checkpoints and resume.

pub mod batch;
pub mod eval;
pub mod lr;
pub mod plot;
pub mod prior;
pub mod steps;
pub mod texture;

use crate::data::{Dataset, Split};
use crate::error::{Error, Result};
use crate::graph::Executor;
use crate::nn::rendernet::{Head, Preset, RenderNet, phong_of};
use crate::ops::adam::Adam;
use crate::rng::SplitMix64;
use crate::gpu::Gpu;
use batch::Batch;
use lr::exponential_decay;
use std::collections::HashMap;
use std::path::PathBuf;

/// How to train.
#[derive(Clone, Debug)]
pub struct TrainConfig {
    /// Network sizes.
    pub preset: Preset,
    /// Dataset directory (`rendernet dataset` output).
    pub data: PathBuf,
    /// Checkpoint path; the weights, the curve and the log go next to it.
    pub out: PathBuf,
    /// Total optimizer steps.
    pub steps: u64,
    /// Checkpoint to resume from.
    pub resume: Option<PathBuf>,
    /// Weights to start a fresh run from where names and shapes match
    /// ([`Executor::load_params_matching`]), e.g. a Phong network's trunk for a contour head.
    pub init: Option<PathBuf>,
    /// Batch size.
    pub batch: usize,
    /// Initial learning rate.
    pub lr: f32,
    /// Exponential decay rate per `decay_steps` (the original code: 0.96).
    pub decay: f32,
    /// Steps per decay period.
    pub decay_steps: u64,
    /// Seed for initialisation, sampling and crops.
    pub seed: u64,
    /// Steps between evaluations + checkpoints.
    pub eval_every: u64,
    /// Held-out samples per evaluation (0 = all).
    pub eval_samples: usize,
    /// A fixed camera-grid window instead of the growing schedule (fine-tuning).
    pub window: Option<usize>,
    /// Corruptions applied to input grids (targets stay clean).
    pub augment: Augment,
}

/// Input-grid corruptions for robustness training: the network sees a damaged grid and is
/// asked for the clean scene's image. Each sample is corrupted with probability 1/2 (so the
/// clean case keeps its share), and then at a level drawn uniformly in `[0, max]` for each
/// corruption whose `max` is non-zero. All zero (the default) trains on clean grids only.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Augment {
    /// Largest fraction of occupied voxels removed ([`crate::stress::dropout`]).
    pub dropout: f64,
    /// Largest fraction of empty voxels in the object's box switched on ([`crate::stress::salt`]).
    pub salt: f64,
}

impl Augment {
    /// Checks the levels: each a fraction in `[0, 1]`.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("--augment-dropout", self.dropout), ("--augment-salt", self.salt)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::Invalid(format!("{name} {v}: must be a fraction in 0..=1")));
            }
        }
        Ok(())
    }

    /// `grid`, corrupted or not as drawn from `r`.
    pub fn apply(&self, grid: crate::voxel::VoxelGrid, r: &mut SplitMix64) -> crate::voxel::VoxelGrid {
        let (coin, seed) = (r.next_u64(), r.next_u64());
        let mut g = grid;
        if *self == Augment::default() || coin % 2 == 0 {
            return g;
        }
        if self.dropout > 0.0 {
            g = crate::stress::dropout(&g, self.dropout * r.next_f64(), seed);
        }
        if self.salt > 0.0 {
            g = crate::stress::salt(&g, self.salt * r.next_f64(), seed ^ 1);
        }
        g
    }
}

/// Reported to the caller (the CLI draws a progress bar from it).
#[derive(Clone, Debug)]
pub enum Progress {
    /// A training step finished.
    Step { step: u64, loss: f32, lr: f32, window: usize, images_per_s: f32 },
    /// An evaluation finished and a checkpoint was written.
    Eval { step: u64, psnr: f32, checkpoint: PathBuf },
    /// A fresh run started from `--init` weights: the parameters taken from them, and those
    /// left as initialised (new heads, reshaped layers).
    Init { loaded: usize, widened: Vec<String>, fresh: Vec<String> },
}

/// The camera-grid window side at `step`: the paper's patch schedule, growing from 1/8 to
/// 1/2 of the grid in three equal phases (depth always whole).
pub fn window_at(p: &Preset, step: u64, steps: u64) -> usize {
    let phase = (3 * step / steps.max(1)).min(2);
    (p.cam >> (3 - phase)).max(4)
}

/// The head a dataset's shader needs.
pub fn head_for(ds: &Dataset) -> Result<Head> {
    let shader = ds.manifest.shader_kind()?;
    Ok(match shader {
        crate::reference::Shader::Phong => {
            let l = &ds.manifest.light;
            Head::Phong(phong_of(&crate::reference::Light { ambient: l.ambient, kd: l.kd, ks: l.ks, shininess: l.shininess, ..Default::default() }))
        }
        s => Head::Image(s.channels()),
    })
}

/// One phase of the crop schedule: the training graph built for its window, and its executor.
struct CropPhase {
    window: usize,
    net: RenderNet,
    ex: Executor,
    /// What `cfg.init` filled, on a fresh run's first phase.
    init: Option<crate::graph::params::InitReport>,
}

fn crop_phase(gpu: &Gpu, cfg: &TrainConfig, head: Head, window: usize, from: Option<&std::path::Path>) -> Result<CropPhase> {
    let net = RenderNet::build(&cfg.preset, head, cfg.batch, [window, window], true)?;
    let mut ex = Executor::new(gpu, net.graph.clone(), cfg.seed)?;
    let mut init = None;
    if let Some(ckpt) = from {
        ex.load_checkpoint(gpu, ckpt)?;
    } else if let Some(path) = &cfg.init {
        let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.display().to_string(), source: e })?;
        init = Some(ex.load_params_matching(gpu, &bytes, &path.display().to_string())?);
    }
    // The transposed convs stay resize-convolutions ("nearest upsample + 3x3 conv"), which
    // cannot grow a checkerboard, at the transposed conv's cost (see `graph::resize_conv`).
    for v in net.graph.params() {
        let info = net.graph.info(v);
        if info.name.starts_with("up.") && info.name.ends_with(".weight") && info.shape[2..] == [4, 4] {
            ex.keep_resize_conv(gpu, v)?;
        }
    }
    Ok(CropPhase { window, net, ex, init })
}

/// Trains as configured, calling `report` after every step and evaluation. Returns the
/// final held-out PSNR.
pub fn train(gpu: &Gpu, cfg: &TrainConfig, mut report: impl FnMut(Progress)) -> Result<f32> {
    cfg.augment.validate()?;
    let ds = Dataset::open(&cfg.data)?;
    let train = ds.split(Split::Train);
    if train.is_empty() {
        return Err(Error::Invalid(format!("{}: the train split is empty", cfg.data.display())));
    }
    let head = head_for(&ds)?;
    // A coloured dataset trains the preset's colour variant (RGB input and albedo).
    let coloured;
    let cfg = if ds.manifest.colour {
        if !cfg.preset.fully_convolutional() {
            return Err(Error::Invalid(format!("{}: coloured voxels need a RenderNet preset; '{}' takes grey grids only", cfg.data.display(), cfg.preset.name)));
        }
        coloured = TrainConfig { preset: cfg.preset.clone().with_colour(), ..cfg.clone() };
        &coloured
    } else {
        cfg
    };
    let p = &cfg.preset;
    let resume = cfg.resume.as_deref();
    let mut start = 0;
    // Training images seen and wall seconds before this run (from the checkpoint), so the
    // weights' metadata gives the whole run's cost across resumes (`frontier` charts it).
    let (mut images0, mut seconds0) = (0u64, Some(0f64));
    if let Some(r) = resume {
        // The step decides the phase; the checkpoint is loaded into that phase's graph.
        let (_, meta) = crate::graph::params::load_safetensors(r)?;
        start = meta.get("step").and_then(|s| s.parse().ok()).unwrap_or(0);
        images0 = meta.get("images").and_then(|s| s.parse().ok()).unwrap_or(start * cfg.batch as u64);
        // Unknown for checkpoints older than this record: left out rather than understated.
        seconds0 = meta.get("train_seconds").and_then(|s| s.parse().ok());
    }
    let t0 = std::time::Instant::now();
    let stamp = |ex: &mut Executor, steps_done: u64| {
        let images = images0 + (steps_done - start) * cfg.batch as u64;
        ex.notes = HashMap::from([
            ("preset".to_string(), p.name.to_string()),
            ("images".to_string(), images.to_string()),
            // The grid side it learned to read, for `render` and `eval` (Preset::for_weights).
            ("input".to_string(), p.input.to_string()),
        ]);
        if let Some(s0) = seconds0 {
            ex.notes.insert("train_seconds".to_string(), format!("{:.0}", s0 + t0.elapsed().as_secs_f64()));
        }
    };
    // The EC baselines see the whole frame through fully-connected layers: no crops.
    let window = |step: u64| if p.fully_convolutional() { cfg.window.unwrap_or_else(|| window_at(p, step, cfg.steps)) } else { p.cam };
    if let Some(w) = cfg.window {
        if !p.fully_convolutional() && w != p.cam {
            return Err(Error::Invalid(format!("--crop {w}: preset '{}' trains on whole frames only; leave --crop out", p.name)));
        }
        if w == 0 || w % 4 != 0 || w > p.cam {
            return Err(Error::Invalid(format!("--crop {w}: must be a multiple of 4 in 4..={}", p.cam)));
        }
    }
    let mut cur = crop_phase(gpu, cfg, head, window(start), resume)?;
    if let Some(r) = cur.init.take() {
        report(Progress::Init { loaded: r.loaded.len(), widened: r.widened, fresh: r.fresh });
    }
    let names: Vec<String> = cur.net.targets.iter().map(|(n, _)| n.clone()).collect();
    // The curve lives in <out>.log.csv (step,loss,psnr), appended every evaluation and read
    // back on resume, so the PNG covers the whole run across interruptions.
    let log = cfg.out.with_extension("log.csv");
    let mut curve = if resume.is_some() { plot::read_log(&log, start) } else { (Vec::new(), Vec::new()) };
    let mut pending: Vec<(u64, f32)> = Vec::new();
    let mut psnr = f32::NAN;
    for step in start..cfg.steps {
        let w = window(step);
        if w != cur.window {
            stamp(&mut cur.ex, step);
            cur.ex.save_checkpoint(gpu, &cfg.out)?;
            cur = crop_phase(gpu, cfg, head, w, Some(&cfg.out))?;
        }
        // Samples, crops and corruptions of a step depend on (seed, step) only, so a resumed
        // run draws exactly what the uninterrupted one would have.
        let mut rng = SplitMix64::new(cfg.seed ^ 0x5EED, step);
        let mut b = Batch::default();
        for _ in 0..cfg.batch {
            let i = (rng.next_u64() % train.len() as u64) as usize;
            let mut sample = train.get(i)?;
            let r = [rng.next_u64(), rng.next_u64(), rng.next_u64()];
            let (h0, w0) = batch::window_origin(p, &sample, w, r);
            sample.grid = cfg.augment.apply(sample.grid, &mut rng);
            b.push(p, &sample, [h0, w0, w, w], &names)?;
        }
        feed(gpu, &cur, &b)?;
        let lr = exponential_decay(cfg.lr, cfg.decay, cfg.decay_steps, step, false);
        let ts = std::time::Instant::now();
        let stats = cur.ex.train_step(gpu, cur.net.loss.expect("built with loss"), &Adam::new(lr))?;
        let loss = stats.loss.expect("a training step reads its loss back");
        if !loss.is_finite() {
            return Err(Error::Invalid(format!("step {step}: the loss is {loss}; stopping before the weights go bad (last checkpoint: {})", cfg.out.display())));
        }
        pending.push((step + 1, loss));
        let ips = cfg.batch as f32 / ts.elapsed().as_secs_f32();
        report(Progress::Step { step: step + 1, loss, lr, window: w, images_per_s: ips });
        let last = step + 1 == cfg.steps;
        if (step + 1) % cfg.eval_every == 0 || last {
            stamp(&mut cur.ex, step + 1);
            cur.ex.save_checkpoint(gpu, &cfg.out)?;
            let params = cfg.out.with_extension("weights.safetensors");
            cur.ex.save_params(gpu, &params)?;
            psnr = eval::evaluate(gpu, p, head, &params, &ds, cfg.eval_samples)?.mean;
            plot::append_log(&log, &pending, (step + 1, psnr))?;
            curve.0.append(&mut pending);
            curve.1.push((step + 1, psnr));
            let _ = plot::write_curve(&cfg.out.with_extension("curve.png"), &curve.0, &curve.1);
            report(Progress::Eval { step: step + 1, psnr, checkpoint: cfg.out.clone() });
        }
    }
    Ok(psnr)
}

fn feed(gpu: &Gpu, ph: &CropPhase, b: &Batch) -> Result<()> {
    let (ex, net) = (&ph.ex, &ph.net);
    ex.feed(gpu, net.grid, &b.grid)?;
    ex.feed(gpu, net.pose, &b.pose)?;
    if let Some(l) = net.light {
        ex.feed(gpu, l, &b.light)?;
    }
    for (name, v) in &net.targets {
        let vals = &b.targets.iter().find(|(n, _)| n == name).expect("pushed every target").1;
        ex.feed(gpu, *v, vals)?;
    }
    Ok(())
}
