//! Kernel timing for `rendernet bench`: GPU timestamps around a pass of repeated dispatches
//! where the device has them, wall time around submit + wait otherwise, median over repeats.

pub mod operands;

use crate::error::{Error, Result};
use crate::gpu::Gpu;

/// Records one call of the kernel being timed into a pass.
pub type Record<'a> = dyn FnMut(&mut wgpu::ComputePass<'_>) -> Result<()> + 'a;

/// How one sample is timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// Timestamps written at the beginning and end of the pass.
    Gpu,
    /// Host time around submit and wait (includes submit overhead, amortised over the calls).
    Wall,
}

/// [`time_calls`] with `memo` installed as a graph run installs it: each call's scratch
/// buffers, textures and bind groups come from the memo's pools and go back when the call
/// ends, so after the first sample nothing is created while timed (with fresh scratch per
/// call, the 1->8 first layer's forward with its four kernels emptied still took ~9 ms on
/// lavapipe; 1.5 ms with the memo).
pub fn time_calls_reusing(gpu: &Gpu, memo: &mut crate::gpu::Memo, clock: Clock, calls: u32, record: &mut Record) -> Result<f64> {
    gpu.recording(memo, || {
        time_calls(gpu, clock, calls, &mut |p| {
            let r = record(p);
            crate::gpu::op_done();
            r
        })
    })
}

/// Times `calls` calls of `record`, all recorded into one submit (one pass, unless a packing
/// ends it for a copy), and returns
/// milliseconds per call. Several calls per pass amortise the submit and wait (0.1-0.5 ms
/// on lavapipe) when `Clock::Wall` is used, and pass begin/end costs with timestamps.
pub fn time_calls(gpu: &Gpu, clock: Clock, calls: u32, record: &mut Record) -> Result<f64> {
    let calls = calls.max(1);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    let query = (clock == Clock::Gpu).then(|| {
        gpu.device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("bench"), ty: wgpu::QueryType::Timestamp, count: 2 })
    });
    // The stamps sit in empty passes of their own around the calls: an op may end the calls'
    // pass for a copy and begin another (gpu/passes.rs), so that pass's own end is not the end.
    let stamp = |enc: &mut wgpu::CommandEncoder, i: u32| {
        if let Some(q) = &query {
            let at = wgpu::ComputePassTimestampWrites { query_set: q, beginning_of_pass_write_index: Some(i), end_of_pass_write_index: None };
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("bench"), timestamp_writes: Some(at) });
        }
    };
    stamp(&mut enc, 0);
    let (mut enc, recorded) = gpu.record_passes(enc, |pass| {
        for _ in 0..calls {
            record(pass)?;
        }
        Ok(())
    });
    recorded?;
    stamp(&mut enc, 1);
    let Some(q) = query else {
        let t = std::time::Instant::now();
        gpu.submit_and_wait(enc)?;
        return Ok(t.elapsed().as_secs_f64() * 1e3 / calls as f64);
    };
    let usage = |u| wgpu::BufferDescriptor { label: None, size: 16, usage: u, mapped_at_creation: false };
    let resolve = gpu.device.create_buffer(&usage(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC));
    let read = gpu.device.create_buffer(&usage(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST));
    enc.resolve_query_set(&q, 0..2, &resolve, 0);
    enc.copy_buffer_to_buffer(&resolve, 0, &read, 0, 16);
    let t = std::time::Instant::now();
    gpu.submit_and_wait(enc)?;
    let wall_ms = t.elapsed().as_secs_f64() * 1e3;
    read.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Readback(format!("timestamp readback: {e}")))?;
    let ticks: [u64; 2] = {
        let view = read.slice(..).get_mapped_range().map_err(|e| Error::Readback(format!("timestamp readback: {e}")))?;
        bytemuck::pod_read_unaligned(&view[..16])
    };
    let ns = ticks[1].saturating_sub(ticks[0]) as f64 * gpu.queue.get_timestamp_period() as f64;
    Ok(plausible_ms(ns * 1e-6, wall_ms) / calls as f64)
}

/// The pass's time from its timestamps, unless they are implausible beside the wall time
/// around its submit. On lavapipe (Mesa 22.3.6) the pass's first timestamp can land after
/// its first dispatch: once a texture-family conv had run, a pass of N calls of the FMA
/// kernel was stamped at N - 1 calls (2 -> 1, 4 -> 3, 1 -> a few microseconds), its output
/// complete; on an AMD Zen 5 a pass of one seconds-long dispatch was stamped at microseconds.
/// So a pass over 20 ms stamped at under 0.9 of its wall time gets the wall time, whose
/// submit overhead (0.1-0.5 ms on lavapipe) is then at most 2.5% of it.
fn plausible_ms(gpu_ms: f64, wall_ms: f64) -> f64 {
    if wall_ms > 20.0 && gpu_ms < 0.9 * wall_ms { wall_ms } else { gpu_ms }
}

/// The clock `rendernet bench` uses on `gpu`: timestamps when the device has them.
pub fn default_clock(gpu: &Gpu) -> Clock {
    if gpu.has_timestamps() { Clock::Gpu } else { Clock::Wall }
}

/// How many calls per sample make a sample last about `target_ms`, given one call's time.
pub fn calls_for(ms_per_call: f64, target_ms: f64) -> u32 {
    (target_ms / ms_per_call.max(1e-3)).clamp(1.0, 64.0) as u32
}

/// The median of `v` (the mean of the middle two for even lengths); NaN when empty.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// Multiply-adds per invocation and loop iteration of `shaders/bench_fma.wgsl`: 8 vec4
/// accumulators x 4 repeats, 2 FLOPs each.
const FMA_FLOPS_PER_ITER: f64 = 8.0 * 4.0 * 4.0 * 2.0;

/// `shaders/bench_fma.wgsl` (nothing but independent FMAs) ready to be timed again and again:
/// what this adapter reaches at all, for reading kernel speeds as a fraction of it. `bench`
/// times it between a kernel's samples too, since a VM's speed moves within a run (rows'
/// ceilings of 51-99 GFLOP/s in one run on an AMD Zen 3; README "Benchmarks").
pub struct FmaProbe {
    out: crate::gpu::Tensor,
    params: FmaParams,
    grid: [u32; 3],
    clock: Clock,
    /// Calls per [`FmaProbe::sample_row`]: about 50 ms of them.
    calls: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FmaParams {
    iters: u32,
    total: u32,
}

const FMA_SHADER: crate::gpu::Shader = crate::gpu::wgsl!("bench_fma");

impl FmaProbe {
    /// Allocates the kernel's output and compiles it (llvmpipe compiles at first dispatch);
    /// samples are timed by `clock`.
    pub fn new(gpu: &Gpu, clock: Clock) -> Result<Self> {
        let params = FmaParams { iters: 1024, total: 16384 };
        let mut probe = Self {
            out: crate::gpu::Tensor::zeros(gpu, &[params.total as usize])?,
            params,
            grid: crate::gpu::grid_1d(params.total as u64, 64)?,
            clock,
            calls: 1,
        };
        probe.sample(gpu, 1)?;
        probe.calls = calls_for(probe.flops() / (probe.sample(gpu, 1)? * 1e6), 50.0);
        Ok(probe)
    }

    /// FLOPs of one call.
    fn flops(&self) -> f64 {
        self.params.total as f64 * self.params.iters as f64 * FMA_FLOPS_PER_ITER
    }

    /// One sample of about 50 ms (1 call on lavapipe, 64 on a large GPU), in GFLOP/s: what
    /// `bench` times between a row's samples.
    pub fn sample_row(&self, gpu: &Gpu) -> Result<f64> {
        self.sample(gpu, self.calls)
    }

    /// The best of `samples` timings of 4 calls, in GFLOP/s: the ceiling a run reports.
    pub fn best(&self, gpu: &Gpu, samples: usize) -> Result<f64> {
        let mut best = 0.0f64;
        for _ in 0..samples.max(1) {
            best = best.max(self.sample(gpu, 4)?);
        }
        Ok(best)
    }

    /// GFLOP/s of one timing of `calls` calls in one pass.
    fn sample(&self, gpu: &Gpu, calls: u32) -> Result<f64> {
        use crate::gpu::Arg;
        let mut record = |pass: &mut wgpu::ComputePass<'_>| gpu.dispatch(pass, FMA_SHADER, "bench_fma", &self.params, &[Arg::W(&self.out)], self.grid);
        Ok(self.flops() / (time_calls(gpu, self.clock, calls, &mut record)? * 1e6))
    }
}

/// The adapter's FMA ceiling in GFLOP/s: the best of `samples` timings of [`FmaProbe`].
pub fn fma_ceiling(gpu: &Gpu, clock: Clock, samples: usize) -> Result<f64> {
    FmaProbe::new(gpu, clock)?.best(gpu, samples)
}

/// Records one (almost) empty dispatch: `bench_fma` with no iterations on one workgroup,
/// writing the first 64 floats of `out`. What [`dispatch_cost_us`] times, and what the
/// profiler puts after each timestamp (graph/profile.rs).
pub(crate) fn record_empty(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, out: &crate::gpu::Tensor) -> Result<()> {
    let params = FmaParams { iters: 0, total: 64 };
    gpu.dispatch(pass, FMA_SHADER, "bench_fma", &params, &[crate::gpu::Arg::W(out)], [1, 1, 1])
}

/// Microseconds one (almost) empty dispatch ([`record_empty`]) takes on the device, the best
/// of `samples` timings of 256 of them in one pass. On lavapipe this is the thread pool's
/// wake-up and wait around every dispatch, whatever the dispatch computes (see README
/// "Benchmarks").
pub fn dispatch_cost_us(gpu: &Gpu, clock: Clock, samples: usize) -> Result<f64> {
    let out = crate::gpu::Tensor::zeros(gpu, &[64])?;
    let mut record = |pass: &mut wgpu::ComputePass<'_>| record_empty(gpu, pass, &out);
    time_calls(gpu, clock, 1, &mut record)?; // compile
    let mut best = f64::INFINITY;
    for _ in 0..samples.max(1) {
        best = best.min(time_calls(gpu, clock, 256, &mut record)? * 1e3);
    }
    Ok(best)
}

/// The CPU model (Linux `/proc/cpuinfo`), which decides lavapipe's speed: a kernel's speed on
/// lavapipe is only meaningful next to it. `None` where it cannot be read.
pub fn cpu_model() -> Option<String> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let field = |name: &str| {
        let line = info.lines().find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))?;
        Some(line.split_once(':')?.1.trim().to_string())
    };
    let flags = field("flags").unwrap_or_default();
    let simd = if flags.split(' ').any(|f| f == "avx512f") {
        "AVX-512"
    } else if flags.split(' ').any(|f| f == "avx2") {
        "AVX2, no AVX-512"
    } else {
        "no AVX2"
    };
    let (family, model) = (field("cpu family").unwrap_or_default(), field("model").unwrap_or_default());
    Some(format!("{} (family {family} model {model}, {simd}, {} threads)", field("model name")?, info.matches("processor\t").count().max(1)))
}

#[cfg(test)]
mod tests {
    use super::plausible_ms;

    /// Timestamps are kept unless a long pass (wall time over 20 ms) is stamped at under 0.9
    /// of its wall time (a pass of 4 calls stamped at 3, as lavapipe did); short passes always
    /// keep them (the submit overhead would dominate the wall time).
    #[test]
    fn implausible_timestamps_fall_back_to_wall_time() {
        assert_eq!(plausible_ms(0.06, 2500.0), 2500.0);
        assert_eq!(plausible_ms(2400.0, 2500.0), 2400.0);
        assert_eq!(plausible_ms(0.05, 0.4), 0.05);
        assert_eq!(plausible_ms(150.0, 200.0), 200.0);
        assert_eq!(plausible_ms(19.0, 19.9), 19.0);
        assert_eq!(plausible_ms(10.0, 30.0), 30.0);
    }
}
