//! Running a graph: forward, backward and optimizer update recorded into one encoder and
//! submitted once, with buffers planned from tensor lifetimes.
//!
//! Memory plan: the schedule is the forward nodes in order, then their backward rules in
//! reverse. Every value's last reader in that schedule is known before recording, so its
//! buffer returns to the pool right after and a later tensor of the same size reuses it
//! (safe within one encoder: the queue runs commands in order). Forward activations are
//! kept only if some backward rule reads them. Inputs, parameters, optimizer state, values
//! the caller asked to [`Executor::keep`], and the gradients it asked for persist.

use super::op::Ctx;
use super::{Graph, Kind, Value};
use super::flat::Flat;
use super::fuse::{Fusions, produced_by_backward, sigmoid_range};
use super::profile::{OpTime, Profiler};
use crate::error::{Error, Result};
use crate::gpu::{BufferPool, Gpu, Memo, Tensor};
use crate::{ops, rng};

/// What one run recorded and allocated.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepStats {
    /// Compute dispatches recorded.
    pub dispatches: u64,
    /// Queue submits with their waits during the step, counted by the device (1 for a whole
    /// training step: the NaN guard is read back from that submit).
    pub submits: u64,
    /// Bytes the memory planner's pool has ever allocated (it keeps what it allocates, so
    /// this is also its peak).
    pub pool_bytes: u64,
    /// Bytes all forward values and gradients would take without reuse.
    pub tensor_bytes: u64,
    /// Bytes of the ops' scratch (packed conv operands, partial sums), uniform blocks and
    /// textures the run's [`crate::gpu::Memo`] holds: pooled per op, kept across runs.
    pub scratch_bytes: u64,
    /// GPU objects (buffers, textures, bind groups) created during the run: after a
    /// graph's first run of a kind (forward, backward, training step), none.
    pub created: u64,
    /// A training step's loss, read back by the step's own submit (with the NaN guard).
    pub loss: Option<f32>,
}

/// Owns the GPU tensors of one graph and runs it.
pub struct Executor {
    pub(super) graph: Graph,
    pub(super) values: Vec<Option<Tensor>>,
    pub(super) grads: Vec<Option<Tensor>>,
    keep: Vec<bool>,
    pub(super) grad_wanted: Vec<bool>,
    pub(super) pool: BufferPool,
    /// Dropout active (training) or identity (evaluation).
    pub training: bool,
    /// Optimizer steps taken; also seeds dropout so a resumed run repeats its masks.
    pub step: u64,
    pub(crate) seed: u64,
    pub(crate) adam_state: Vec<Option<(Tensor, Tensor)>>,
    /// Parameters, their gradients and Adam moments, each kind in one buffer.
    pub(crate) flat: Flat,
    /// Whether the last training step checked every gradient at once (its guard flags are
    /// then per chunk of the flat gradients, not per parameter).
    pub(super) guard_flat: bool,
    loss_one: Option<Tensor>,
    /// Gradient guard flags `[1 + params]` and the buffer they are copied to for reading.
    pub(super) guard: Option<(Tensor, wgpu::Buffer)>,
    /// What the last forward, backward and training run created, for the next one of the
    /// same kind (each records its own sequence of dispatches).
    memos: [Memo; 3],
    /// Bumped at every write to the parameters, so a run reuses the weight packings of an
    /// earlier run only while they are unchanged (see `gpu/constant.rs`).
    param_version: std::cell::Cell<u64>,
    /// Transposed-conv weights kept resize-convolutions after every Adam step, and the
    /// projector tensor (see [`Executor::keep_resize_conv`]).
    pub(super) resize_convs: Vec<Value>,
    pub(super) projector: Option<Tensor>,
    /// Whether runs reuse the memo's GPU objects (see [`Executor::reuse_gpu_objects`]).
    reuse: bool,
    /// Per-op timestamps of the next runs (see [`Executor::profile`]) and the last run's times.
    profiler: Option<Profiler>,
    op_times: Vec<OpTime>,
    /// Provenance written into the metadata of saved weights and checkpoints (the trainer
    /// records the preset, images seen and training seconds), read back by `frontier`.
    pub notes: std::collections::HashMap<String, String>,
}

pub(super) fn bytes(shape: &[usize]) -> u64 {
    shape.iter().product::<usize>() as u64 * 4
}

impl Executor {
    /// Allocates inputs (zeroed) and parameters (initialised from `seed`), and settles the
    /// device's conv kernel choice (a calibration with its own submits, the first time on a
    /// machine) so that no step pays for it.
    pub fn new(gpu: &Gpu, graph: Graph, seed: u64) -> Result<Executor> {
        crate::ops::conv::calibrate(gpu);
        let n = graph.values.len();
        let init = |v: Value| match &graph.values[v.0].kind {
            Kind::Param(init) => init.values(&graph.values[v.0].shape, seed, v.0 as u64),
            _ => Vec::new(),
        };
        let (flat, mut values) = Flat::new(gpu, &graph, init)?;
        for (i, v) in graph.values.iter().enumerate() {
            if matches!(v.kind, Kind::Input) {
                values[i] = Some(Tensor::zeros(gpu, &v.shape)?);
            }
        }
        let grad_wanted = graph.values.iter().map(|v| matches!(v.kind, Kind::Param(_))).collect();
        Ok(Executor {
            values,
            grads: vec![None; n],
            keep: vec![false; n],
            grad_wanted,
            pool: BufferPool::new(),
            training: true,
            step: 0,
            seed,
            adam_state: vec![None; n],
            flat,
            guard_flat: false,
            loss_one: None,
            guard: None,
            memos: Default::default(),
            param_version: Default::default(),
            resize_convs: Vec::new(),
            projector: None,
            reuse: true,
            profiler: None,
            op_times: Vec::new(),
            notes: Default::default(),
            graph,
        })
    }

    /// Times every op of the following runs on the GPU (a timestamp after each, in the run's
    /// own pass), readable after each run with [`Executor::op_times`]; `false` stops. An
    /// error where the device has no timestamps inside passes.
    pub fn profile(&mut self, gpu: &Gpu, on: bool) -> Result<()> {
        // Every forward and backward step of every node, one Adam step, and ample room.
        self.profiler = if on { Some(Profiler::new(gpu, 2 * self.graph.nodes.len() + 2)?) } else { None };
        self.op_times.clear();
        Ok(())
    }

    /// Each op's GPU time in the last profiled run, in schedule order (see
    /// [`Executor::profile`]; [`super::profile::by_kind`] sums them per op kind).
    pub fn op_times(&self) -> &[OpTime] {
        &self.op_times
    }

    /// The graph being run.
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Sets an input's (or a parameter's) contents. Rejects wrong lengths and NaN/Inf.
    pub fn feed(&self, gpu: &Gpu, v: Value, data: &[f32]) -> Result<()> {
        let info = self.graph.info(v);
        if matches!(info.kind, Kind::Node) {
            return Err(Error::Invalid(format!("'{}' is computed by the graph and cannot be fed", info.name)));
        }
        if let Some(i) = data.iter().position(|x| !x.is_finite()) {
            return Err(Error::Invalid(format!("'{}': value {i} is {} (NaN/Inf are not accepted)", info.name, data[i])));
        }
        if matches!(info.kind, Kind::Param(_)) {
            self.params_changed();
        }
        let t = self.values[v.0].as_ref().expect("inputs and params are always allocated");
        t.write(gpu, data).map_err(|e| Error::Invalid(format!("'{}': {e}", info.name)))
    }

    /// Invalidates the weight packings kept from earlier runs.
    fn params_changed(&self) {
        self.param_version.set(self.param_version.get() + 1);
    }

    /// Keeps a node's output after a run so [`Executor::read`] can return it.
    pub fn keep(&mut self, v: Value) {
        self.keep[v.0] = true;
    }

    /// Asks for the gradient of an input (voxels, pose, light, latent code...). Parameters
    /// always get one when training.
    pub fn want_grad(&mut self, v: Value) {
        self.grad_wanted[v.0] = true;
    }

    /// Stops computing parameter gradients (inverse rendering through a frozen network:
    /// only the inputs marked with [`Executor::want_grad`] get one, which saves the
    /// weight-gradient kernels). Training steps need them, so call this only for inference.
    pub fn freeze_params(&mut self) {
        for p in self.graph.params() {
            self.grad_wanted[p.0] = false;
        }
    }

    /// With `false`, every run makes fresh uniform buffers, bind groups and zeroed scratch
    /// instead of reusing the last run's (see [`crate::gpu::Memo`]): slower, for checking
    /// that reuse changes nothing (a kernel that read scratch it never wrote would differ).
    pub fn reuse_gpu_objects(&mut self, reuse: bool) {
        self.reuse = reuse;
    }

    /// Reads a value: an input, a parameter, or a node output marked with `keep`.
    pub fn read(&self, gpu: &Gpu, v: Value) -> Result<Vec<f32>> {
        let name = &self.graph.info(v).name;
        let t = self.values[v.0]
            .as_ref()
            .ok_or_else(|| Error::Invalid(format!("'{name}' was not kept; call keep() before running")))?;
        t.to_vec(gpu)
    }

    /// Reads the gradient of a parameter or a `want_grad` input after a backward run.
    pub fn grad(&self, gpu: &Gpu, v: Value) -> Result<Vec<f32>> {
        let name = &self.graph.info(v).name;
        let t = self.grads[v.0]
            .as_ref()
            .ok_or_else(|| Error::Invalid(format!("no gradient for '{name}': run backward, and want_grad() it")))?;
        t.to_vec(gpu)
    }

    /// Runs the forward pass only (one submit).
    pub fn forward(&mut self, gpu: &Gpu) -> Result<StepStats> {
        self.run(gpu, None, None)
    }

    /// Runs forward and backward from the scalar `loss` (one submit); gradients of
    /// parameters and `want_grad` inputs are then readable with [`Executor::grad`].
    pub fn backward(&mut self, gpu: &Gpu, loss: Value) -> Result<StepStats> {
        self.run(gpu, Some(loss), None)
    }

    /// One training step: forward, backward from `loss`, and an Adam update of every
    /// parameter at learning rate `adam.lr`, all in one submit.
    pub fn train_step(&mut self, gpu: &Gpu, loss: Value, adam: &ops::adam::Adam) -> Result<StepStats> {
        self.run(gpu, Some(loss), Some(adam))
    }

    pub(super) fn persistent(&self, v: Value) -> bool {
        !matches!(self.graph.values[v.0].kind, Kind::Node) || self.keep[v.0]
    }

    /// Which nodes run backward: those on a path from a value wanting a gradient to `loss`.
    fn backward_nodes(&self, loss: Value) -> Vec<bool> {
        let nodes = &self.graph.nodes;
        let mut needs = self.grad_wanted.clone(); // value depends on something wanting grad
        for n in nodes {
            if n.inputs.iter().any(|i| needs[i.0]) {
                needs[n.output.0] = true;
            }
        }
        let mut reaches = vec![false; self.graph.values.len()]; // value influences the loss
        reaches[loss.0] = true;
        let mut run = vec![false; nodes.len()];
        for (k, n) in nodes.iter().enumerate().rev() {
            if reaches[n.output.0] && needs[n.output.0] {
                run[k] = true;
                for i in &n.inputs {
                    reaches[i.0] = true;
                }
            }
        }
        run
    }

    fn run(&mut self, gpu: &Gpu, loss: Option<Value>, adam: Option<&ops::adam::Adam>) -> Result<StepStats> {
        if let Some(l) = loss {
            if self.graph.info(l).shape != [1] {
                return Err(Error::Invalid(format!(
                    "backward needs a scalar loss; '{}' has shape {:?}",
                    self.graph.info(l).name,
                    self.graph.info(l).shape
                )));
            }
        }
        if let Some(l) = loss {
            self.keep[l.0] = true;
        }
        let nodes = self.graph.nodes.clone();
        let f = nodes.len();
        let bw = loss.map(|l| self.backward_nodes(l)).unwrap_or_else(|| vec![false; f]);
        // Last schedule position reading each value (forward at k, backward of k at 2f-1-k).
        let nv = self.graph.values.len();
        let mut last = vec![0usize; nv];
        let mut last_grad = vec![0usize; nv];
        for (k, n) in nodes.iter().enumerate() {
            for i in &n.inputs {
                last[i.0] = last[i.0].max(k);
            }
            last[n.output.0] = last[n.output.0].max(k);
            if bw[k] {
                let pos = 2 * f - 1 - k;
                let (ins, out) = n.op.saves();
                for &j in ins {
                    last[n.inputs[j].0] = last[n.inputs[j].0].max(pos);
                }
                if out {
                    last[n.output.0] = last[n.output.0].max(pos);
                }
                last_grad[n.output.0] = last_grad[n.output.0].max(pos);
            }
        }
        let fusions = self.fusions(gpu, &nodes, &bw, &mut last);
        // Free what the previous run kept for reading: it has been read or never will be.
        for v in 0..nv {
            if matches!(self.graph.values[v].kind, Kind::Node) {
                if let Some(t) = self.values[v].take() {
                    self.pool.release(t);
                }
            }
            // Gradients are per run: last run's, read by now, must not be summed into.
            if let Some(t) = self.grads[v].take() {
                self.pool.release(t);
            }
        }
        let kind = match (loss, adam) {
            (None, _) => 0,
            (Some(_), None) => 1,
            (Some(_), Some(_)) => 2,
        };
        let (d0, s0, c0) = (gpu.dispatch_count(), gpu.submit_count(), gpu.created_count());
        self.pool.begin_run();
        let mut memo = std::mem::take(&mut self.memos[kind]);
        // A training step changes the parameters only in its last command (Adam): its packings
        // hold for the run and are stale for the next, whose prologue packs them again.
        let params = Some((self.flat.params_buffer().clone(), self.param_version.get()));
        memo.begin_constants(params);
        let tensor_bytes = if self.reuse {
            gpu.recording(&mut memo, || self.record_and_submit(gpu, &nodes, &bw, loss, adam, &last, &last_grad, &fusions))
        } else {
            self.record_and_submit(gpu, &nodes, &bw, loss, adam, &last, &last_grad, &fusions)
        };
        memo.end_constants(tensor_bytes.is_ok());
        if adam.is_some() {
            self.params_changed(); // by Adam
        }
        let scratch_bytes = memo.bytes();
        self.memos[kind] = memo;
        let tensor_bytes = tensor_bytes?;
        if let Some(p) = &self.profiler {
            self.op_times = p.read(gpu)?;
        }
        let mut step_loss = None;
        if adam.is_some() {
            step_loss = Some(self.check_guard(gpu)?);
            self.step += 1;
        }
        Ok(StepStats {
            dispatches: gpu.dispatch_count() - d0,
            submits: gpu.submit_count() - s0,
            pool_bytes: self.pool.allocated_bytes(),
            tensor_bytes,
            scratch_bytes,
            created: gpu.created_count() - c0,
            loss: step_loss,
        })
    }

    /// Records the run into one encoder and submits it; returns the bytes of every tensor
    /// placed (see [`Executor::record`]).
    #[allow(clippy::too_many_arguments)]
    fn record_and_submit(
        &mut self,
        gpu: &Gpu,
        nodes: &[super::Node],
        bw: &[bool],
        loss: Option<Value>,
        adam: Option<&ops::adam::Adam>,
        last: &[usize],
        last_grad: &[usize],
        fusions: &Fusions,
    ) -> Result<u64> {
        let enc = gpu.device.create_command_encoder(&Default::default());
        let (mut enc, recorded) = gpu.record_passes(enc, |pass| {
            if let Some(p) = &mut self.profiler {
                p.begin(gpu, pass);
            }
            let bytes = self.record(gpu, pass, nodes, bw, loss, last, last_grad, fusions)?;
            if let Some(adam) = adam {
                self.record_adam(gpu, pass, adam)?;
                if let Some(p) = &mut self.profiler {
                    p.mark(gpu, pass, "adam".into(), "adam");
                }
            }
            Ok(bytes)
        });
        let tensor_bytes = recorded?;
        if let Some(p) = &self.profiler {
            p.resolve(&mut enc);
        }
        if let (Some(_), Some((flags, staging)), Some(l)) = (adam, &self.guard, loss) {
            let fb = flags.buffer().size();
            enc.copy_buffer_to_buffer(flags.buffer(), 0, staging, 0, fb);
            let l = self.values[l.0].as_ref().expect("the loss is kept");
            enc.copy_buffer_to_buffer(l.buffer(), 0, staging, fb, 4);
        }
        // The weight packings this run's convs deferred, packed ahead of it.
        let prologue = ops::conv_pack_jobs::prologue(gpu)?;
        gpu.submit_after_and_wait(prologue, enc)?;
        Ok(tensor_bytes)
    }

    fn release_if_dead(&mut self, v: Value, pos: usize, last: &[usize]) {
        if last[v.0] == pos && !self.persistent(v) {
            if let Some(t) = self.values[v.0].take() {
                self.pool.release(t);
            }
        }
    }

    /// Records forward and (with a loss) backward; returns the bytes of every tensor it
    /// placed, the figure the pool's peak is compared with.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        nodes: &[super::Node],
        bw: &[bool],
        loss: Option<Value>,
        last: &[usize],
        last_grad: &[usize],
        fusions: &Fusions,
    ) -> Result<u64> {
        let f = nodes.len();
        let mut total = 0u64;
        let Fusions { prelu: fused, views, ranges, packs } = fusions;
        for (k, n) in nodes.iter().enumerate() {
            // Nodes that dispatch nothing (a profile shows them at about 0 ms): a PReLU the
            // conv before it wrote, a channel range the sigmoid after it reads in place or that
            // is a view of its input.
            let skipped = k > 0 && fused[k - 1] || ranges[k] || views[k].is_some();
            if let Some(offset) = views[k] {
                self.values[n.output.0] = Some(self.view_of(n, offset).map_err(|e| node_err(&n.name, e))?);
            }
            if skipped {
                if let Some(p) = &mut self.profiler {
                    p.mark(gpu, pass, format!("{} forward", n.name), n.op.name());
                }
                for v in n.inputs.iter().chain([&n.output]) {
                    self.release_if_dead(*v, k, last);
                }
                continue;
            }
            // A fused conv writes the PReLU's output; its own is never placed.
            let out = if fused[k] { nodes[k + 1].output } else { n.output };
            let shape = self.graph.values[out.0].shape.clone();
            let y = self.pool.tensor(gpu, &shape)?;
            total += bytes(&shape);
            if let Some((h, start)) = sigmoid_range(nodes, ranges, k) {
                let x = self.values[h.0].as_ref().expect("kept for the range's sigmoid");
                ops::sigmoid::forward_range(gpu, pass, x, start, &y).map_err(|e| node_err(&n.name, e))?;
            } else {
                let ins: Vec<&Tensor> = n.inputs.iter().map(|i| self.values[i.0].as_ref().expect("scheduled")).collect();
                gpu.recording_node(Some((k, packs[k])));
                let mut ctx = Ctx { gpu, pass: &mut *pass, seed: self.node_seed(k), training: self.training };
                let r = if fused[k] {
                    let alpha = self.values[nodes[k + 1].inputs[1].0].as_ref().expect("computed before the conv");
                    n.op.forward_prelu(&mut ctx, &ins, alpha, &y)
                } else {
                    n.op.forward(&mut ctx, &ins, &y)
                };
                gpu.recording_node(None);
                r.map_err(|e| node_err(&n.name, e))?;
            }
            crate::gpu::op_done();
            if let Some(p) = &mut self.profiler {
                p.mark(gpu, pass, format!("{} forward", n.name), n.op.name());
            }
            self.values[out.0] = Some(y);
            for v in n.inputs.iter().chain([&n.output]) {
                self.release_if_dead(*v, k, last);
            }
        }
        let Some(loss) = loss else { return Ok(total) };
        let seed = self.loss_seed(gpu)?;
        let g = self.pool.tensor(gpu, &[1])?;
        ops::add::copy(gpu, pass, &seed, &g)?;
        self.grads[loss.0] = Some(g);
        let produced_by_bw = produced_by_backward(nodes, bw, self.graph.values.len());
        for k in (0..f).rev().filter(|&k| bw[k]) {
            let pos = 2 * f - 1 - k;
            let n = &nodes[k];
            let Some(dy) = self.grads[n.output.0].clone() else { continue };
            // A channel range's gradient (a Narrow's, or a Sigmoid's run with the Narrow before
            // it) goes straight into its channels of the input's gradient.
            let range = match n.op {
                super::Op::Narrow(start, _) => Some((n.inputs[0], start)),
                _ => sigmoid_range(nodes, ranges, k),
            };
            if views[k].is_some() && matches!(n.op, super::Op::ConcatAxis0(_)) {
                // A joint of parameters: its gradient's view made its parts' (`first_grad`).
            } else if let Some((h, start)) = range {
                if self.grad_wanted[h.0] || produced_by_bw[h.0] {
                    self.range_backward(gpu, pass, n, h, start, &dy, &mut total).map_err(|e| node_err(&n.name, e))?;
                }
            } else {
                // Each input wanting a gradient gets its own tensor on first contribution;
                // later contributions go to a temporary and are summed in. An add hands dy itself
                // to one input whose gradient it starts (`hands_on`): a dispatch fewer.
                let mut targets: Vec<Option<(Tensor, bool)>> = Vec::new(); // (tensor, accumulate)
                let mut handed = false;
                for (j, i) in n.inputs.iter().enumerate() {
                    if !(self.grad_wanted[i.0] || produced_by_bw[i.0]) || !n.op.differentiable(j) {
                        targets.push(None);
                        continue;
                    }
                    let seen = self.grads[i.0].is_some() || n.inputs[..j].contains(i);
                    if !handed && !seen && self.hands_on(n, *i, &dy) {
                        self.grads[i.0] = Some(dy.clone());
                        // dy is the input's now: released at the input's last gradient use, not here.
                        self.grads[n.output.0] = None;
                        handed = true;
                        targets.push(None);
                        continue;
                    }
                    let t = if seen { self.pool.tensor(gpu, &self.graph.values[i.0].shape)? } else { self.first_grad(gpu, *i, &mut total)? };
                    targets.push(Some((t, seen)));
                }
                if matches!(n.op, super::Op::Add) {
                    for t in targets.iter().flatten() {
                        ops::add::copy(gpu, pass, &dy, &t.0)?;
                    }
                } else {
                    // Values a rule does not declare in `saves()` may be gone already; `dy` stands
                    // in for them (rules never read them). A declared one that is missing would
                    // mean a planner bug: refuse rather than compute with the wrong buffer.
                    let (saved, out_saved) = n.op.saves();
                    let missing = saved.iter().find(|&&j| self.values[n.inputs[j].0].is_none()).map(|&j| n.inputs[j])
                        .or((out_saved && self.values[n.output.0].is_none()).then_some(n.output));
                    if let Some(v) = missing {
                        return Err(Error::Invalid(format!("internal: node '{}' needs '{}' for backward but it was released", n.name, self.graph.info(v).name)));
                    }
                    let ins: Vec<&Tensor> = n.inputs.iter().map(|i| self.values[i.0].as_ref()).map(|t| t.unwrap_or(&dy)).collect();
                    let y = self.values[n.output.0].clone().unwrap_or_else(|| dy.clone());
                    let dx: Vec<Option<&Tensor>> = targets.iter().map(|t| t.as_ref().map(|t| &t.0)).collect();
                    let mut ctx = Ctx { gpu, pass: &mut *pass, seed: self.node_seed(k), training: self.training };
                    // Packings the node made are found again, and what it packs now is kept
                    // for the rest of its backward (gpu/kept.rs), then all released.
                    gpu.recording_node(Some((k, true)));
                    let r = n.op.backward(&mut ctx, &ins, &y, &dy, &dx);
                    gpu.recording_node(None);
                    gpu.release_kept(k);
                    r.map_err(|e| node_err(&n.name, e))?;
                }
                for (j, t) in targets.into_iter().enumerate() {
                    if let Some((t, true)) = t {
                        let acc = self.grads[n.inputs[j].0].as_ref().expect("first contribution made it");
                        ops::add::accumulate(gpu, pass, &t, acc)?;
                        self.pool.release(t);
                    }
                }
            }
            crate::gpu::op_done();
            if let Some(p) = &mut self.profiler {
                p.mark(gpu, pass, format!("{} backward", n.name), n.op.name());
            }
            if last_grad[n.output.0] == pos && !self.grad_wanted[n.output.0] {
                if let Some(t) = self.grads[n.output.0].take() {
                    self.pool.release(t);
                }
            }
            for v in n.inputs.iter().chain([&n.output]) {
                self.release_if_dead(*v, pos, last);
            }
        }
        Ok(total)
    }

    /// A constant 1 to start backward from, in a buffer of its own (never pooled, since
    /// it is written with `queue.write_buffer`).
    fn loss_seed(&mut self, gpu: &Gpu) -> Result<Tensor> {
        if self.loss_one.is_none() {
            self.loss_one = Some(Tensor::from_slice(gpu, &[1], &[1.0])?);
        }
        Ok(self.loss_one.clone().expect("just set"))
    }

    /// Dropout seed of node `k` at the current step: a pure function of (seed, step, node),
    /// so a resumed run draws the same masks as an uninterrupted one.
    fn node_seed(&self, k: usize) -> u32 {
        if !self.training {
            return 0;
        }
        // A one-shot hash on SplitMix64's constants, not its sequence: changing it would
        // change the masks of runs resumed from existing checkpoints.
        let mut z = self.seed ^ self.step.wrapping_mul(rng::GAMMA) ^ (k as u64).wrapping_mul(rng::MIX1);
        z = (z ^ (z >> 31)).wrapping_mul(rng::MIX2);
        (z ^ (z >> 29)) as u32
    }
}

fn node_err(node: &str, e: Error) -> Error {
    match e {
        Error::Shape { op, msg } => Error::Shape { op: format!("node '{node}' ({op})"), msg },
        other => other,
    }
}
