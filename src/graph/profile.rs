//! Per-op GPU time of an executor run ([`Executor::profile`]): a timestamp after every op,
//! written inside the run's compute passes (one, unless a packing ends it for a copy), so the
//! times are those of the real schedule
//! (same encoder, same scratch reuse), not of ops run one by one.
//!
//! lavapipe (Mesa 22.3.6) writes a timestamp at the next point where the pass has to wait,
//! not where it was recorded: an op whose successor starts with work that does not read its
//! output was stamped late, and the first op (the resampling, a third of a 128x128 forward)
//! read 0 ms, the ops adding to 67-81% of the wall time. So two empty dispatches on one
//! buffer follow each timestamp: the second waits for the first, and the pass stops there
//! (the ops then add to 89-109% of the wall time; README "Where a step spends its time").
//!
//! [`Executor::profile`]: super::Executor::profile

use crate::error::{Error, Result};
use crate::gpu::Gpu;

/// GPU time of one step of a profiled run.
#[derive(Clone, Debug, PartialEq)]
pub struct OpTime {
    /// The node's name and what ran: `"enc3d.conv1 forward"`, `"enc3d.conv1 backward"`,
    /// `"adam"`. A PReLU that the conv before it applied (see `Executor`'s PReLU fusion)
    /// keeps its row, with no dispatches and about 0 ns: its work is in the conv's time.
    pub name: String,
    /// The op's kind as [`super::Op`] names it (`"conv"`, `"prelu"`, ...; `"adam"`).
    pub kind: String,
    /// Nanoseconds between the timestamp before it and the one after it.
    pub ns: f64,
    /// Dispatches it recorded: on lavapipe each costs tens of microseconds of thread
    /// wake-ups whatever it computes (see README "Benchmarks").
    pub dispatches: u64,
}

/// The query set and buffers of one executor's profiled runs.
pub(crate) struct Profiler {
    set: wgpu::QuerySet,
    cap: u32,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// (name, kind, dispatches) of the op that ends at each timestamp after the first.
    marks: Vec<(String, String, u64)>,
    /// The device's dispatch count at the last timestamp.
    dispatched: u64,
    /// What the empty dispatches after each timestamp write.
    sink: crate::gpu::Tensor,
}

/// wgpu's limit on the queries of one set.
const MAX_QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;

impl Profiler {
    /// A profiler for runs of up to `ops` steps; an error where the device cannot write
    /// timestamps inside a pass.
    pub(crate) fn new(gpu: &Gpu, ops: usize) -> Result<Profiler> {
        if !gpu.has_timestamps() {
            return Err(Error::Invalid(format!("profiling needs timestamp queries inside compute passes, which {} lacks", gpu.info.name)));
        }
        let cap = u32::try_from(ops + 1).ok().filter(|&c| c <= MAX_QUERIES).ok_or_else(|| {
            Error::Invalid(format!("profiling: {ops} steps is more than one query set holds ({})", MAX_QUERIES - 1))
        })?;
        let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("profile"), ty: wgpu::QueryType::Timestamp, count: cap });
        let size = cap as u64 * 8;
        let resolve = gpu.new_buffer("profile resolve", size, wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
        let staging = gpu.new_buffer("profile readback", size, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        let sink = crate::gpu::Tensor::zeros(gpu, &[64])?;
        Ok(Profiler { set, cap, resolve, staging, marks: Vec::new(), dispatched: 0, sink })
    }

    /// The first timestamp of a run.
    pub(crate) fn begin(&mut self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>) {
        self.marks.clear();
        self.dispatched = gpu.dispatch_count();
        pass.write_timestamp(&self.set, 0);
        self.settle(gpu, pass);
    }

    /// Two empty dispatches on one buffer, the second waiting for the first: lavapipe writes
    /// the timestamp just recorded there. Not counted as dispatches of any op or step.
    fn settle(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>) {
        for _ in 0..2 {
            // Only fails on limits, which one workgroup and a 64-float buffer cannot pass.
            if crate::bench::record_empty(gpu, pass, &self.sink).is_ok() {
                gpu.uncount_dispatches(1);
            }
        }
    }

    /// A timestamp after the op just recorded; ops past the set's capacity are not timed.
    pub(crate) fn mark(&mut self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, name: String, kind: &str) {
        let i = self.marks.len() as u32 + 1;
        if i < self.cap {
            pass.write_timestamp(&self.set, i);
            self.settle(gpu, pass);
            let now = gpu.dispatch_count();
            self.marks.push((name, kind.to_string(), now - self.dispatched));
            self.dispatched = now;
        }
    }

    /// Copies the run's timestamps out, after its pass ended.
    pub(crate) fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        let n = self.marks.len() as u32 + 1;
        enc.resolve_query_set(&self.set, 0..n, &self.resolve, 0);
        enc.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, n as u64 * 8);
    }

    /// Each op's time, after the run's submit completed.
    pub(crate) fn read(&self, gpu: &Gpu) -> Result<Vec<OpTime>> {
        let words = crate::gpu::read_staging(gpu, &self.staging)?;
        let bytes: &[u8] = bytemuck::cast_slice(&words);
        let tick = |i: usize| bytemuck::pod_read_unaligned::<u64>(&bytes[i * 8..i * 8 + 8]);
        let period = gpu.queue.get_timestamp_period() as f64;
        Ok(self
            .marks
            .iter()
            .enumerate()
            .map(|(i, (name, kind, dispatches))| OpTime {
                name: name.clone(),
                kind: kind.clone(),
                ns: tick(i + 1).saturating_sub(tick(i)) as f64 * period,
                dispatches: *dispatches,
            })
            .collect())
    }
}

/// `times` summed per kind, largest first, with each kind's number of steps and dispatches.
pub fn by_kind(times: &[OpTime]) -> Vec<(String, f64, usize, u64)> {
    let mut sums: Vec<(String, f64, usize, u64)> = Vec::new();
    for t in times {
        match sums.iter_mut().find(|s| s.0 == t.kind) {
            Some(s) => {
                s.1 += t.ns;
                s.2 += 1;
                s.3 += t.dispatches;
            }
            None => sums.push((t.kind.clone(), t.ns, 1, t.dispatches)),
        }
    }
    sums.sort_by(|a, b| b.1.total_cmp(&a.1));
    sums
}
