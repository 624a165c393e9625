//! `rendernet bench`: times the conv, transposed-conv, projection and resampling kernels on
//! shapes from the RenderNet presets and reports GFLOP/s per (op, shape, pass, kernel).

use clap::Args;
use rendernet::bench::{self, Clock};
use rendernet::gpu::Memo;
use rendernet::ops::conv::{Conv, ConvKernel, Padding, Pass};
use rendernet::ops::conv_transpose::ConvTranspose;
use rendernet::ops::projection;
use rendernet::ops::resample::{self, Sampling};
use rendernet::graph::profile::by_kind;
use rendernet::graph::{Executor, OpTime};
use rendernet::nn::rendernet::{Head, Preset, RenderNet, phong_of};
use rendernet::ops::adam::Adam;
use rendernet::nn::render::{CROP_MARGIN, object_window};
use rendernet::reference::{Light, View};
use rendernet::{Gpu, Result, Tensor};

/// Options of `rendernet bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Print a JSON array (one object per op, shape, pass and kernel) instead of a table.
    #[arg(long)]
    json: bool,
    /// Only cases whose op or shape contains this text (e.g. conv3d, projection).
    #[arg(long)]
    filter: Option<String>,
    /// Only this pass: e.g. to sample one kernel alone with `ci/jit-profile.sh`.
    #[arg(long, value_parser = PASS_NAMES)]
    pass: Option<String>,
    /// Samples per measurement; the median is reported.
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Which conv kernels, comma-separated: reference (one output per invocation), fast
    /// (tiled, storage buffers), texture (tiled, textures + subgroup shuffles), nchw (texture,
    /// but the narrow 3x3 heads' forward reads its input unpacked: rows only there), or all.
    /// For the resampling rows, fast reads the grid from its storage buffer, texture from a
    /// texture. Kernels of one case are sampled in turn, so they see the same machine load.
    #[arg(long, default_value = "all")]
    kernel: String,
    /// After the whole-network rows, time every op of one run of each (GPU timestamps between
    /// ops, inside the run's passes) and print the time per op kind and the slowest ops:
    /// where a forward or a training step spends its time.
    #[arg(long)]
    profile: bool,
    /// Instead of the kernels, time what reading one operand costs beyond a plain FMA, per kind
    /// (storage-buffer, uniform-buffer, texel and workgroup-memory loads with a per-lane or a
    /// lane-uniform address, a subgroup shuffle, an integer division), and what a store to a
    /// storage buffer or a storage texture costs: on lavapipe this changes several-fold with
    /// the driver and the CPU, and decides how a kernel should read and write its operands.
    #[arg(long, conflicts_with_all = ["filter", "pass", "kernel", "profile"])]
    operands: bool,
}

/// Records one call of a case's kernel.
type Recorder = Box<dyn FnMut(&Gpu, &mut wgpu::ComputePass<'_>) -> Result<()>>;

/// One timed thing: a pass of an op on one shape with one kernel choice.
struct Case {
    op: &'static str,
    shape: String,
    pass: &'static str,
    kernel: &'static str,
    flops: f64,
    record: Recorder,
}

fn pass_name(p: Pass) -> &'static str {
    match p {
        Pass::Forward => "forward",
        Pass::BackwardInput => "backward_input",
        Pass::BackwardWeight => "backward_weight",
    }
}

const PASSES: [Pass; 3] = [Pass::Forward, Pass::BackwardInput, Pass::BackwardWeight];

/// Every row's pass: the convs' ([`pass_name`]), the resampling's pose gradient and the
/// whole network's training step (`--pass` takes one).
const PASS_NAMES: [&str; 5] = ["forward", "backward_input", "backward_weight", "backward_pose", "train_step"];

/// The passes of the whole-network rows (`model_rows`), which `--profile` times.
const MODEL_PASSES: [&str; 2] = ["forward", "train_step"];

const KERNELS: [(&str, ConvKernel); 4] =
    [("reference", ConvKernel::Reference), ("fast", ConvKernel::Buffers), ("texture", ConvKernel::Texture), ("nchw", ConvKernel::Nchw)];

/// Whether `--kernel` `choice` (comma-separated, or `all`) names kernel `name`.
fn chosen(choice: &str, name: &str) -> bool {
    choice == "all" || choice.split(',').any(|c| c.trim() == name)
}

fn kernels(choice: &str) -> Vec<(&'static str, ConvKernel)> {
    KERNELS.into_iter().filter(|(n, _)| chosen(choice, n)).collect()
}

/// A forward conv case set: input `xs`, weights `ws` (tensors are zeros: timing only).
fn conv_cases(gpu: &Gpu, op: &'static str, shape: &str, c: Conv, xs: &[usize], ws: &[usize], choice: &str) -> Result<Vec<Case>> {
    let ys = c.output_shape(xs, ws)?;
    let (x, w, y) = (Tensor::zeros(gpu, xs)?, Tensor::zeros(gpu, ws)?, Tensor::zeros(gpu, &ys)?);
    let b = Tensor::zeros(gpu, &[ws[0]])?;
    // Multiply-adds: every output value sums Cin * |kernel| products, padding included.
    let flops = 2.0 * ys.iter().product::<usize>() as f64 * ws[1..].iter().product::<usize>() as f64;
    let mut out = Vec::new();
    for pass in PASSES {
        for (name, k) in kernels(choice) {
            if name != "reference" && !c.runs_fast(k, pass, xs, ws)? {
                continue;
            }
            // `nchw` differs from `texture` only in the forward of the narrow 3x3 heads.
            if name == "nchw" && (pass != Pass::Forward || !c.forward_reads_unpacked(k, gpu, xs, ws)?) {
                continue;
            }
            let (x, w, y, b) = (x.clone(), w.clone(), y.clone(), b.clone());
            let record: Recorder = match pass {
                Pass::Forward => Box::new(move |g, p| c.forward(k, g, p, &x, &w, Some(&b), &y)),
                Pass::BackwardInput => Box::new(move |g, p| c.backward_input(k, g, p, &y, &w, &x)),
                Pass::BackwardWeight => Box::new(move |g, p| c.backward_weight(k, g, p, &x, &y, &w)),
            };
            out.push(Case { op, shape: shape.into(), pass: pass_name(pass), kernel: name, flops, record });
        }
    }
    Ok(out)
}

/// A transposed conv case set: input `xs`, weights `ws` = [Cin, Cout, k...].
fn transposed_cases(gpu: &Gpu, shape: &str, t: ConvTranspose, xs: &[usize], ws: &[usize], choice: &str) -> Result<Vec<Case>> {
    let ys = t.output_shape(xs, ws)?;
    let (x, w, y) = (Tensor::zeros(gpu, xs)?, Tensor::zeros(gpu, ws)?, Tensor::zeros(gpu, &ys)?);
    let b = Tensor::zeros(gpu, &[ws[1]])?;
    // The equivalent forward conv's multiply-adds: each input value meets Cout * |kernel| weights.
    let flops = 2.0 * xs.iter().product::<usize>() as f64 * ws[1..].iter().product::<usize>() as f64;
    let mut out = Vec::new();
    for pass in PASSES {
        for (name, k) in kernels(choice) {
            if name == "nchw" || (name != "reference" && !t.runs_fast(k, pass, xs, ws, &ys)?) {
                continue;
            }
            let (x, w, y, b) = (x.clone(), w.clone(), y.clone(), b.clone());
            let record: Recorder = match pass {
                Pass::Forward => Box::new(move |g, p| t.forward(k, g, p, &x, &w, Some(&b), &y)),
                Pass::BackwardInput => Box::new(move |g, p| t.backward_input(k, g, p, &y, &w, &x)),
                Pass::BackwardWeight => Box::new(move |g, p| t.backward_weight(k, g, p, &x, &y, &w)),
            };
            out.push(Case { op: "conv_transpose2d", shape: shape.into(), pass: pass_name(pass), kernel: name, flops, record });
        }
    }
    Ok(out)
}

fn projection_cases(gpu: &Gpu, choice: &str) -> Result<Vec<Case>> {
    let (n, k, o, h, w) = (1, 512, 256, 64, 64);
    let x = Tensor::zeros(gpu, &[n, k, h, w])?;
    let wt = Tensor::zeros(gpu, &[o, k, 1, 1])?;
    let (b, y) = (Tensor::zeros(gpu, &[o])?, Tensor::zeros(gpu, &[n, o, h, w])?);
    let flops = 2.0 * (n * k * o * h * w) as f64;
    let shape = format!("{k}->{o} 1x1 on {h}x{w}, batch {n}");
    let mut out = Vec::new();
    for pass in PASSES {
        for (name, kern) in kernels(choice).into_iter().filter(|(n, _)| *n != "nchw") {
            let (x, wt, b, y) = (x.clone(), wt.clone(), b.clone(), y.clone());
            let record: Recorder = match pass {
                Pass::Forward => Box::new(move |g, p| projection::forward(kern, g, p, &x, &wt, &b, &y)),
                Pass::BackwardInput => Box::new(move |g, p| projection::backward_input(kern, g, p, &y, &wt, &x)),
                Pass::BackwardWeight => Box::new(move |g, p| projection::backward_weight(kern, g, p, &x, &y, &wt)),
            };
            out.push(Case { op: "projection", shape: shape.clone(), pass: pass_name(pass), kernel: name, flops, record });
        }
    }
    Ok(out)
}

/// The tiny preset's resampling of a 1-channel 32^3 grid into the camera grid `out` under a
/// turned pose: forward and pose gradient from the buffer (`fast`) or a texture (`texture`),
/// and the grid gradient (buffer only). FLOPs: 8 multiply-adds per sampled value (its
/// trilinear sum), though a sample also costs 8 loads and its weights.
fn resample_cases(gpu: &Gpu, out: [usize; 3], choice: &str) -> Result<Vec<Case>> {
    let xs = [1, 1, 32, 32, 32];
    let ys = [1, 1, out[0], out[1], out[2]];
    let (x, dx) = (Tensor::zeros(gpu, &xs)?, Tensor::zeros(gpu, &xs)?);
    let (y, dpose) = (Tensor::zeros(gpu, &ys)?, Tensor::zeros(gpu, &[1, 6])?);
    // Non-zero dy: the buffer path skips voxels whose dy is zero.
    let dy = Tensor::from_slice(gpu, &ys, &vec![1.0; ys.iter().product()])?;
    let pose = Tensor::from_slice(gpu, &[1, 6], &resample::pose_from_view(30.0, 60.0, 3.3))?;
    let flops = 16.0 * ys.iter().product::<usize>() as f64;
    let shape = format!("1ch 32^3 -> {}x{}x{}, batch 1", out[0], out[1], out[2]);
    // The texture rows only where the adapter runs them (as the conv rows, `runs_fast`).
    let ways = [("fast", Sampling::Buffer), ("texture", Sampling::Texture)];
    let ways: Vec<_> = ways
        .into_iter()
        .filter(|(n, s)| chosen(choice, n) && (*s == Sampling::Buffer || resample::textures_supported(gpu)))
        .collect();
    let mut v = Vec::new();
    for &(name, s) in &ways {
        let (x, pose, y) = (x.clone(), pose.clone(), y.clone());
        let record: Recorder = Box::new(move |g, p| resample::forward_with(g, p, &x, &pose, &y, s));
        v.push(Case { op: "resample", shape: shape.clone(), pass: "forward", kernel: name, flops, record });
    }
    if ways.iter().any(|w| w.1 == Sampling::Buffer) {
        let (pose, dy) = (pose.clone(), dy.clone());
        let record: Recorder = Box::new(move |g, p| resample::backward_input(g, p, &pose, &dy, &dx));
        v.push(Case { op: "resample", shape: shape.clone(), pass: "backward_input", kernel: "fast", flops, record });
    }
    for &(name, s) in &ways {
        let (x, pose, dy, dpose) = (x.clone(), pose.clone(), dy.clone(), dpose.clone());
        let record: Recorder = Box::new(move |g, p| resample::backward_pose_with(g, p, &x, &pose, &dy, &dpose, s));
        v.push(Case { op: "resample", shape: shape.clone(), pass: "backward_pose", kernel: name, flops, record });
    }
    Ok(v)
}

/// The fixed shape list, from the RenderNet presets (see the README's Benchmarks section).
fn cases(gpu: &Gpu, choice: &str) -> Result<Vec<Case>> {
    let mut v = Vec::new();
    let c3 = Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same);
    v.extend(conv_cases(gpu, "conv3d", "16->16 3^3 on 32^3, batch 1", c3, &[1, 16, 32, 32, 32], &[16, 16, 3, 3, 3], choice)?);
    let c2 = Conv::conv2d([3, 3], [1, 1], Padding::Same);
    v.extend(conv_cases(gpu, "conv2d", "256->256 3x3 on 32x32, batch 1", c2, &[1, 256, 32, 32], &[256, 256, 3, 3], choice)?);
    let t = ConvTranspose::conv2d([4, 4], [2, 2], Padding::Same);
    v.extend(transposed_cases(gpu, "64->32 4x4 s2 on 64x64, batch 1", t, &[1, 64, 64, 64], &[64, 32, 4, 4], choice)?);
    v.extend(projection_cases(gpu, choice)?);
    // The small-channel ends of the tiny preset: its first layer, an image head and the
    // Phong heads as one conv (normal 3 + albedo 1 + mask 1 channels, `nn::rendernet`).
    let c5 = Conv::conv3d([5, 5, 5], [2, 2, 2], Padding::Same);
    v.extend(conv_cases(gpu, "conv3d", "1->8 5^3 s2 on 64^3, batch 1", c5, &[1, 1, 64, 64, 64], &[8, 1, 5, 5, 5], choice)?);
    v.extend(conv_cases(gpu, "conv2d", "16->3 3x3 on 128x128, batch 1", c2, &[1, 16, 128, 128], &[3, 16, 3, 3], choice)?);
    v.extend(conv_cases(gpu, "conv2d", "16->5 3x3 on 128x128, batch 1", c2, &[1, 16, 128, 128], &[5, 16, 3, 3], choice)?);
    // The tiny preset's first two 3D convs and a 2D residual conv, at the sizes a training
    // step on a 64x64 patch runs them.
    v.extend(conv_cases(gpu, "conv3d", "1->8 5^3 s2 on 64x32x32, batch 1", c5, &[1, 1, 64, 32, 32], &[8, 1, 5, 5, 5], choice)?);
    v.extend(conv_cases(gpu, "conv2d", "32->32 3x3 on 32x32, batch 1", c2, &[1, 32, 32, 32], &[32, 32, 3, 3], choice)?);
    let c3s = Conv::conv3d([3, 3, 3], [2, 1, 1], Padding::Same);
    v.extend(conv_cases(gpu, "conv3d", "8->16 3^3 s2x1x1 on 32x16x16, batch 1", c3s, &[1, 8, 32, 16, 16], &[16, 8, 3, 3, 3], choice)?);
    // The tiny preset's first op, for a 128x128 image and a 64x64 training patch.
    v.extend(resample_cases(gpu, [64, 64, 64], choice)?);
    v.extend(resample_cases(gpu, [64, 32, 32], choice)?);
    Ok(v)
}

/// What every row carries besides its own timing: where it ran, and the FMA probe that is
/// timed between the row's samples (`probe.sample_row`): the row is divided by the median of
/// its own, so a machine that speeds up or slows down during the run moves both alike.
struct Machine {
    adapter: String,
    cpu: Option<String>,
    probe: bench::FmaProbe,
}

impl Machine {
    fn row(&self, op: &str, shape: &str, pass: &str, kernel: &str, ms: f64, gflops: f64, ceiling: f64) -> serde_json::Value {
        serde_json::json!({
            "op": op, "shape": shape, "pass": pass, "kernel": kernel,
            "ms": finite(ms), "gflops": finite(gflops),
            "fma_ceiling_gflops": finite(ceiling),
            "fraction_of_fma_ceiling": finite(gflops / ceiling),
            "adapter": self.adapter, "cpu": self.cpu,
        })
    }
}

/// JSON has no NaN or infinity: such values become null.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Whole-network entries: a RenderNet forward at full size and on the bunny's window, and a
/// training step on the largest patch of the schedule at batch 1 and 2, with the executor's
/// dispatch, submit and memory figures.
/// Timed by wall clock around each submit and wait (the executor owns its encoder).
fn model_rows(gpu: &Gpu, repeat: usize, m: &Machine, profile: bool, only: Option<&str>) -> Result<Vec<(String, serde_json::Value)>> {
    let p = Preset::tiny();
    let head = Head::Phong(phong_of(&Light::default()));
    let mut rows = Vec::new();
    // The default scene's window: `render` crops the camera grid to the object (nn::render).
    let bunny = rendernet::voxel::bunny().resample_to(p.input)?;
    let crop = object_window(&bunny, &View::default(), p.cam, CROP_MARGIN);
    // The last: the fine-tuning recipes' step (`train --crop 32 --batch 2`, weights/README.md).
    let cases = [
        ("forward", [p.cam; 2], false, "", 1),
        ("forward", [crop[2], crop[3]], false, " (bunny crop)", 1),
        ("train_step", [p.cam / 2; 2], true, "", 1),
        ("train_step", [p.cam / 2; 2], true, "", 2),
    ];
    for (pass, win, train, what, batch) in cases.into_iter().filter(|c| only.is_none_or(|p| p == c.0)) {
        let net = RenderNet::build(&p, head, batch, win, train)?;
        let flops = net.graph.forward_flops() * if train { 3.0 } else { 1.0 };
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        let step = |ex: &mut Executor| match net.loss {
            Some(l) if train => ex.train_step(gpu, l, &Adam::new(0.0)),
            _ => ex.forward(gpu),
        };
        let stats = step(&mut ex)?; // pipelines compile on first use
        let mut ms = Vec::new();
        let mut ceilings = Vec::new();
        let (mut again, mut copies) = (stats, 0);
        for _ in 0..repeat.max(1) {
            ceilings.push(m.probe.sample_row(gpu)?);
            let (t, splits) = (std::time::Instant::now(), gpu.pass_splits());
            again = step(&mut ex)?;
            ms.push(t.elapsed().as_secs_f64() * 1e3);
            copies = gpu.pass_splits() - splits;
        }
        let (ms, ceiling) = (bench::median(&ms), bench::median(&ceilings));
        let gflops = flops / (ms * 1e6);
        let (ih, iw) = (p.image_for(win[0]), p.image_for(win[1]));
        let shape = format!("{} {}^3 grid, {ih}x{iw} image{what}, batch {batch}", p.name, p.input);
        let mut json = m.row("rendernet", &shape, pass, "auto", ms, gflops, ceiling);
        // Later runs may make fewer: a frozen network's weights stay packed (gpu/constant.rs).
        json["dispatches"] = again.dispatches.into();
        json["first_run_dispatches"] = stats.dispatches.into();
        json["submits_per_step"] = stats.submits.into();
        json["copies"] = copies.into();
        json["pool_bytes"] = stats.pool_bytes.into();
        json["tensor_bytes"] = stats.tensor_bytes.into();
        json["scratch_bytes"] = stats.scratch_bytes.into();
        json["created_per_step"] = again.created.into();
        let text = format!(
            "{:<17} {:<34} {:<16} {:<9} {ms:>10.1} {gflops:>9.2} {:>8.1}% {:>9.1}  ({} dispatches ({} in the first run), {copies} copies into textures, {} submit, {} GPU objects created after the first run, pool {:.1} MiB for {:.1} MiB of tensors, scratch {:.1} MiB)",
            "rendernet", shape, pass, "auto", 100.0 * gflops / ceiling, ceiling, again.dispatches, stats.dispatches, stats.submits, again.created,
            stats.pool_bytes as f64 / 1048576.0, stats.tensor_bytes as f64 / 1048576.0, stats.scratch_bytes as f64 / 1048576.0
        );
        if profile {
            ex.profile(gpu, true)?;
            step(&mut ex)?;
            let times = ex.op_times();
            json["profile"] = profile_json(times);
            rows.push((format!("{text}\n{}", profile_text(times, ms)), json));
            ex.profile(gpu, false)?;
        } else {
            rows.push((text, json));
        }
    }
    Ok(rows)
}

/// The ops of one profiled run, slowest first, as JSON: `{name, kind, ms, dispatches}`.
fn profile_json(times: &[OpTime]) -> serde_json::Value {
    let mut v: Vec<&OpTime> = times.iter().collect();
    v.sort_by(|a, b| b.ns.total_cmp(&a.ns));
    v.iter().map(|t| serde_json::json!({"name": t.name, "kind": t.kind, "ms": t.ns * 1e-6, "dispatches": t.dispatches})).collect()
}

/// Time per op kind and the 10 slowest ops of one profiled run whose wall time was `wall_ms`.
fn profile_text(times: &[OpTime], wall_ms: f64) -> String {
    let total: f64 = times.iter().map(|t| t.ns).sum::<f64>() * 1e-6;
    let mut s = format!("  profile: {total:.1} ms on the GPU between the first and last op ({wall_ms:.1} ms wall, median)\n");
    for (kind, ns, count, dispatches) in by_kind(times) {
        s += &format!("    {kind:<16} {:>8.2} ms {:>5.1}%  ({count} steps, {dispatches} dispatches)\n", ns * 1e-6, 100.0 * ns * 1e-6 / total.max(1e-9));
    }
    let mut v: Vec<&OpTime> = times.iter().collect();
    v.sort_by(|a, b| b.ns.total_cmp(&a.ns));
    s += "    slowest:\n";
    for t in v.iter().take(10) {
        s += &format!("      {:<36} {:>8.2} ms  ({} dispatches)\n", t.name, t.ns * 1e-6, t.dispatches);
    }
    s.trim_end().to_string()
}

/// Runs the benchmark and prints a table or JSON.
pub fn run(a: BenchArgs) -> Result<()> {
    if let Some(bad) = a.kernel.split(',').map(str::trim).find(|k| *k != "all" && !KERNELS.iter().any(|(n, _)| n == k)) {
        return Err(rendernet::Error::Invalid(format!(
            "--kernel: unknown kernel '{bad}'; expected a comma-separated list of reference, fast, texture, nchw, or all"
        )));
    }
    let with_model = a.filter.as_deref().is_none_or(|f| "rendernet".contains(f));
    if a.profile && !with_model {
        return Err(rendernet::Error::Invalid(format!(
            "--profile times the whole-network (rendernet) rows, which --filter {} leaves out",
            a.filter.as_deref().unwrap_or_default()
        )));
    }
    if let Some(p) = a.pass.as_deref().filter(|p| a.profile && !MODEL_PASSES.contains(p)) {
        return Err(rendernet::Error::Invalid(format!(
            "--profile times the whole-network rows (forward, train_step), which --pass {p} leaves out"
        )));
    }
    let gpu = Gpu::new()?;
    let clock = bench::default_clock(&gpu);
    if a.operands {
        return operands(&gpu, clock, a.repeat, a.json);
    }
    let mut all = cases(&gpu, &a.kernel)?;
    if let Some(f) = &a.filter {
        all.retain(|c| c.op.contains(f.as_str()) || c.shape.contains(f.as_str()));
    }
    if let Some(p) = &a.pass {
        all.retain(|c| c.pass == p);
    }
    let m = Machine { adapter: gpu.info.name.clone(), cpu: bench::cpu_model(), probe: bench::FmaProbe::new(&gpu, clock)? };
    let start = m.probe.best(&gpu, 5)?;
    if !a.json {
        let how = if clock == Clock::Gpu { "GPU timestamps" } else { "wall time" };
        println!("adapter: {} ({how}; median of {} samples)", m.adapter, a.repeat);
        println!("cpu:     {}", m.cpu.as_deref().unwrap_or("unknown"));
        println!("FMA ceiling (shaders/bench_fma.wgsl, best of 5): {start:.1} GFLOP/s at the start; each row is divided by");
        println!("the median of the ceilings timed between its own samples (last column, GFLOP/s)");
        println!("the last column counts one call's dispatches / copies into textures (each ends and begins a pass)");
        println!("{:<17} {:<34} {:<16} {:<9} {:>10} {:>9} {:>9} {:>9} {:>6}", "op", "shape", "pass", "kernel", "ms", "GFLOP/s", "ceiling", "its GF/s", "disp");
    }
    let mut json = Vec::new();
    // Cases of one (op, shape, pass) are sampled in turn, so kernels compared see the same load.
    let mut i = 0;
    while i < all.len() {
        let j = (i..all.len()).find(|&j| all[j].op != all[i].op || all[j].pass != all[i].pass).unwrap_or(all.len());
        let group = &mut all[i..j];
        // Warm-up call: compiles the pipelines (llvmpipe compiles at first dispatch) and sizes
        // the sample so each lasts ~200 ms.
        // Each case keeps a memo, as a graph does: timed calls reuse scratch and bind groups.
        let mut memos: Vec<Memo> = group.iter().map(|_| Memo::default()).collect();
        let mut calls = Vec::new();
        // Dispatches and copies (pass splits) of one call: what each costs beside its work.
        let mut counts = Vec::new();
        for (c, memo) in group.iter_mut().zip(&mut memos) {
            let (g, rec) = (&gpu, &mut c.record);
            bench::time_calls_reusing(&gpu, memo, clock, 1, &mut |p| rec(g, p))?;
            let before = (gpu.dispatch_count(), gpu.pass_splits());
            let once = bench::time_calls_reusing(&gpu, memo, clock, 1, &mut |p| rec(g, p))?;
            counts.push((gpu.dispatch_count() - before.0, gpu.pass_splits() - before.1));
            calls.push(bench::calls_for(once, 200.0));
        }
        let mut samples = vec![Vec::new(); group.len()];
        let mut ceilings = Vec::new();
        for _ in 0..a.repeat.max(1) {
            ceilings.push(m.probe.sample_row(&gpu)?);
            for (k, c) in group.iter_mut().enumerate() {
                let (g, rec) = (&gpu, &mut c.record);
                samples[k].push(bench::time_calls_reusing(&gpu, &mut memos[k], clock, calls[k], &mut |p| rec(g, p))?);
            }
        }
        let ceiling = bench::median(&ceilings);
        for (k, c) in group.iter().enumerate() {
            let ms = bench::median(&samples[k]);
            let gflops = c.flops / (ms * 1e6);
            let pass = c.pass;
            let (dispatches, copies) = counts[k];
            if a.json {
                let mut row = m.row(c.op, &c.shape, pass, c.kernel, ms, gflops, ceiling);
                row["dispatches"] = dispatches.into();
                row["copies"] = copies.into();
                json.push(row);
            } else {
                println!(
                    "{:<17} {:<34} {:<16} {:<9} {ms:>10.3} {gflops:>9.2} {:>8.1}% {ceiling:>9.1} {:>6}",
                    c.op, c.shape, pass, c.kernel, 100.0 * gflops / ceiling, format!("{dispatches}/{copies}")
                );
            }
        }
        i = j;
    }
    if with_model {
        for (text, row) in model_rows(&gpu, a.repeat, &m, a.profile, a.pass.as_deref())? {
            if a.json {
                json.push(row);
            } else {
                println!("{text}");
            }
        }
    }
    // The ceiling again at the end, reported beside the first: how much the machine's speed
    // moved over the run.
    let after = m.probe.best(&gpu, 5)?;
    if a.json {
        let out = serde_json::json!({
            "adapter": m.adapter, "cpu": m.cpu,
            "fma_ceiling_gflops": finite(start), "fma_ceiling_at_end_gflops": finite(after),
            "rows": json,
        });
        println!("{}", serde_json::to_string_pretty(&out).map_err(|e| rendernet::Error::Invalid(e.to_string()))?);
    } else {
        println!("FMA ceiling at the end of the run: {after:.1} GFLOP/s");
    }
    Ok(())
}

/// `bench --operands`: the cost of each kind of operand beside the FMA ceiling and the CPU.
fn operands(gpu: &Gpu, clock: Clock, repeat: usize, json: bool) -> Result<()> {
    if !gpu.has_subgroups_of_8() {
        return Err(rendernet::Error::Invalid("--operands times a subgroup shuffle, which this adapter lacks".into()));
    }
    if !gpu.reads_rgba32f_storage() {
        return Err(rendernet::Error::Invalid("--operands times a read-only storage-texture load, which this adapter lacks".into()));
    }
    let (cpu, ceiling) = (bench::cpu_model(), bench::fma_ceiling(gpu, clock, 5)?);
    let costs = bench::operands::operand_costs(gpu, clock, repeat, ceiling)?;
    let dispatch_us = bench::dispatch_cost_us(gpu, clock, repeat)?;
    // What the device could have computed meanwhile: FMAs at the ceiling (2 FLOPs each).
    let dispatch_fmas = dispatch_us * 1e-6 * ceiling * 1e9 / 2.0;
    if json {
        let rows: Vec<_> = costs
            .iter()
            .map(|c| serde_json::json!({"operand": c.operand, "address": c.address, "ns_per_vector": finite(c.ns_per_vector),
                                         "extra_ns": finite(c.extra_ns), "extra_in_fmas": finite(c.extra_in_fmas)}))
            .collect();
        let out = serde_json::json!({"adapter": gpu.info.name, "cpu": cpu, "fma_ceiling_gflops": finite(ceiling), "operands": rows,
                                     "dispatch_us": finite(dispatch_us), "dispatch_in_fmas": finite(dispatch_fmas)});
        println!("{}", serde_json::to_string_pretty(&out).map_err(|e| rendernet::Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    println!("adapter: {}\ncpu:     {}", gpu.info.name, cpu.as_deref().unwrap_or("unknown"));
    println!("FMA ceiling (shaders/bench_fma.wgsl, best of 5): {ceiling:.1} GFLOP/s");
    println!("One operand per FMA (shaders/bench_operands.wgsl), ns per 8-lane vector op over all CPU threads, best of {repeat}:");
    println!("{:<40} {:<18} {:>9} {:>13} {:>16}", "operand", "address", "ns", "beyond FMA", "ceiling FMAs");
    for c in &costs {
        println!("{:<40} {:<18} {:>9.2} {:>13.2} {:>16.1}", c.operand, c.address, c.ns_per_vector, c.extra_ns, c.extra_in_fmas);
    }
    // What the loop itself costs: the plain FMA row against an FMA at the ceiling.
    let loop_fma = costs[0].ns_per_vector / bench::operands::ceiling_fma_ns(ceiling);
    println!("(a plain FMA in this loop, one per loop-carried value and iteration, costs {loop_fma:.1} FMAs at the ceiling)");
    println!("An (almost) empty dispatch of one workgroup, best of {repeat}: {dispatch_us:.1} us ({:.2} million FMAs at the ceiling)", dispatch_fmas * 1e-6);
    Ok(())
}
