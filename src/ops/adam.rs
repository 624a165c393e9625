//! The Adam optimiser's update, in place on the GPU (binds `shaders/adam.wgsl`). Each
//! parameter tensor carries its own first and second moment tensors `m`, `v` (zeros at the
//! start, the parameter's shape), owned by the caller so they can be checkpointed.
//!
//! The update is Kingma & Ba's Algorithm 1 (PyTorch's form): `eps` is added to the
//! bias-corrected `sqrt(v̂)`. TensorFlow, which the original code used, adds it to the
//! uncorrected `sqrt(v)` instead; with `eps = 1e-8` the two differ only where `v` is ~1e-16.

use super::expect_shape;
use crate::error::{Error, Result};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("adam");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    lr: f32,
    beta1: f32,
    beta2: f32,
    eps: f32,
    bc1: f32,
    bc2: f32,
}

/// Adam's hyperparameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adam {
    /// Learning rate (the original code: 1e-5 with exponential decay 0.96, applied by the
    /// caller by changing `lr` between steps).
    pub lr: f32,
    /// First-moment decay; 0.5 in the original code (GAN-style), not the usual 0.9.
    pub beta1: f32,
    /// Second-moment decay.
    pub beta2: f32,
    /// Denominator guard.
    pub eps: f32,
}

impl Adam {
    /// The original RenderNet code's settings (beta1 0.5, beta2 0.999, eps 1e-8) at `lr`.
    pub fn new(lr: f32) -> Adam {
        Adam { lr, beta1: 0.5, beta2: 0.999, eps: 1e-8 }
    }

    /// Step `t` (1-based: the first step is 1) on `param` with gradient `grad`, updating
    /// `param`, `m` and `v` in place. All four tensors share one shape.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        t: u32,
        param: &Tensor,
        grad: &Tensor,
        m: &Tensor,
        v: &Tensor,
    ) -> Result<()> {
        self.step_guarded(gpu, pass, t, param, grad, m, v, None)
    }

    /// [`Adam::step`] that does nothing when `guard[0] != 0` (see `ops::finite`): the
    /// check happens on the GPU, so a training step stays one submit.
    #[allow(clippy::too_many_arguments)]
    pub fn step_guarded(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        t: u32,
        param: &Tensor,
        grad: &Tensor,
        m: &Tensor,
        v: &Tensor,
        guard: Option<&Tensor>,
    ) -> Result<()> {
        let op = "adam_step";
        if t == 0 {
            return Err(Error::Invalid(format!("{op}: step t is 1-based, got 0 (bias correction would divide by 0)")));
        }
        for (name, b) in [("beta1", self.beta1), ("beta2", self.beta2)] {
            if !(0.0..1.0).contains(&b) {
                return Err(Error::Invalid(format!("{op}: {name} = {b} must lie in [0, 1)")));
            }
        }
        expect_shape(op, "grad", grad, param.shape())?;
        expect_shape(op, "m", m, param.shape())?;
        expect_shape(op, "v", v, param.shape())?;
        let bc = |beta: f32| (1.0 - (beta as f64).powi(t.min(i32::MAX as u32) as i32)) as f32;
        let n = param.numel();
        let p = Params {
            n: n as u32,
            lr: self.lr,
            beta1: self.beta1,
            beta2: self.beta2,
            eps: self.eps,
            bc1: bc(self.beta1),
            bc2: bc(self.beta2),
        };
        let args = [Arg::R(grad), Arg::W(param), Arg::W(m), Arg::W(v), guard.map_or(Arg::Absent, Arg::R)];
        // Not `elementwise`: the guard is one value, not one per element.
        let (entry, count) = super::vec4_or(op, n);
        gpu.dispatch(pass, SHADER, entry, &p, &args, grid_1d(count as u64, 64)?)
    }
}
