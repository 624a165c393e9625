//! The optimizer step of [`Executor::train_step`]: Adam on every parameter, guarded against
//! NaN/Inf gradients on the GPU, recorded into the step's own pass, and the guard's readback.

use super::exec::Executor;
use super::Value;
use crate::error::{Error, Result};
use crate::gpu::{Gpu, Tensor};
use crate::ops;

/// Workgroups of the gradient check over the flat buffer: enough to spread it over the CPU
/// threads of lavapipe, few enough that each has a long loop.
const FLAT_CHUNKS: usize = 64;

impl Executor {
    /// Reads the guard flags and the loss copied out in the step's own submit; returns the
    /// loss, or on NaN/Inf names the first parameter whose gradient held it (the GPU
    /// already skipped the update).
    pub(super) fn check_guard(&self, gpu: &Gpu) -> Result<f32> {
        let (flags, staging) = self.guard.as_ref().expect("a training step sets the guard up");
        let read = crate::gpu::read_staging(gpu, staging)?;
        let n = flags.numel();
        let (flags, loss) = (&read[..n], read[(flags.buffer().size() / 4) as usize]);
        if flags[0] == 0.0 {
            return Ok(loss);
        }
        let params = self.graph.params();
        let bad = if self.guard_flat {
            // Flags per chunk of the flat gradients: read them back once, find the parameter.
            let all = self.flat.whole().expect("a flat step made them")[1].to_vec(gpu)?;
            let bad_in = |g: &Tensor| {
                let at = (g.offset() / 4) as usize;
                all[at..at + g.numel()].iter().any(|x| !x.is_finite())
            };
            params.iter().find(|v| self.grads[v.0].as_ref().is_some_and(bad_in)).map(|v| self.graph.info(*v).name.clone())
        } else {
            // A joint's parts share its first part's flag.
            let name = |v: Value| match self.flat.joint_of(v) {
                Some(j) => j.parts.iter().map(|p| self.graph.info(*p).name.clone()).collect::<Vec<_>>().join("' or '"),
                None => self.graph.info(v).name.clone(),
            };
            (1..flags.len()).find(|&k| flags[k] != 0.0).map(|k| name(params[k - 1]))
        };
        Err(Error::Invalid(format!(
            "step {}: the gradient of '{}' holds NaN or Inf; the update was skipped and the weights are unchanged",
            self.step + 1,
            bad.unwrap_or_else(|| "?".into())
        )))
    }

    /// Parameter `v`'s Adam moments, views of the flat moment buffers.
    pub(crate) fn moments_of(&mut self, gpu: &Gpu, v: Value) -> Result<(Tensor, Tensor)> {
        self.flat.moments(gpu, &self.graph, v)
    }

    /// Adam on every parameter that received a gradient, guarded: every gradient is checked
    /// for NaN/Inf first and, if any is bad, no parameter moves. Moments are created
    /// (zeroed) on first use and kept for checkpoints. When every parameter has a gradient
    /// (a training step), the check and the update each run once over the flat buffers.
    pub(super) fn record_adam(&mut self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, adam: &ops::adam::Adam) -> Result<()> {
        let t = u32::try_from(self.step + 1).map_err(|_| Error::Invalid("optimizer step beyond u32".into()))?;
        let params = self.graph.params();
        if self.guard.is_none() {
            let flags = Tensor::zeros(gpu, &[1 + params.len().max(FLAT_CHUNKS)])?;
            // The flags, then the loss.
            let staging = gpu.new_buffer("guard readback", flags.buffer().size() + 4, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
            self.guard = Some((flags, staging));
        }
        let flags = self.guard.as_ref().expect("just set").0.clone();
        for v in &params {
            if self.grads[v.0].is_some() && self.adam_state[v.0].is_none() {
                self.adam_state[v.0] = Some(self.flat.moments(gpu, &self.graph, *v)?);
            }
        }
        self.guard_flat = params.iter().all(|v| self.grads[v.0].as_ref().is_some_and(Tensor::is_view));
        if let Some([p, g, m, s]) = self.flat.whole().filter(|_| self.guard_flat) {
            let chunks = ops::finite::check_chunks(gpu, pass, &g, &flags, FLAT_CHUNKS)?;
            ops::finite::any(gpu, pass, &flags, chunks)?;
            adam.step_guarded(gpu, pass, t, &p, &g, &m, &s, Some(&flags))?;
        } else {
            // Each parameter on its own views, except a joint's parts (flat.rs), which may
            // start unaligned: those on the joint's, flagged at its first part, and only
            // when every part has a gradient (they move together or not at all).
            let mut units = Vec::new();
            for (k, v) in params.iter().enumerate() {
                let Some(g) = self.grads[v.0].clone() else { continue };
                let joint = self.flat.joint_of(*v).map(|j| (j.output, j.parts[0], j.parts.iter().all(|p| self.grads[p.0].is_some())));
                let unit = match joint {
                    Some((_, first, all)) if first != *v || !all => continue,
                    Some((joint, ..)) => self.flat.joint_views(gpu, &self.graph, joint)?,
                    None => {
                        let (m, s) = self.adam_state[v.0].clone().expect("made above");
                        [self.values[v.0].clone().expect("params are always allocated"), g, m, s]
                    }
                };
                ops::finite::check(gpu, pass, &unit[1], &flags, k + 1)?;
                units.push(unit);
            }
            ops::finite::any(gpu, pass, &flags, params.len())?;
            for [p, g, m, s] in &units {
                adam.step_guarded(gpu, pass, t, p, g, m, s, Some(&flags))?;
            }
        }
        if let Some(proj) = &self.projector {
            for v in &self.resize_convs {
                ops::resize_conv::project(gpu, pass, proj, self.values[v.0].as_ref().expect("params are always allocated"))?;
            }
        }
        Ok(())
    }
}
