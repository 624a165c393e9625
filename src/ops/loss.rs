//! Training losses and the PSNR metric (binds `shaders/loss.wgsl`).
//!
//! Both losses are means over every element and write a one-element tensor; their backward
//! passes read the upstream gradient from a one-element tensor too, so a loss is an
//! ordinary node of a graph (weighted sums of losses, the face model's image + normal MSE).
//! Targets get no gradient.
//!
//! BCE takes probabilities, not logits: the paper's heads end in a sigmoid and the same head
//! output also feeds Phong shading, so the probability is what the graph holds. To keep
//! `ln` finite it clamps the prediction to `[BCE_EPS, 1 - BCE_EPS]`; like any clamp this
//! zeroes the gradient outside that range: a sigmoid saturated in f32 (exactly 0 or 1)
//! gets no push from BCE, a trade for a finite loss.

use super::{elementwise, expect_shape, reduce};
use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("loss": "workgroup_sum", "loss");

/// The clamp BCE applies to predictions, in f32 (`1 - BCE_EPS` rounds to 0.99999988).
pub const BCE_EPS: f32 = 1e-7;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    inv_n: f32,
    eps: f32,
}

/// A reconstruction loss, a mean over all elements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Loss {
    /// Mean squared error, `mean((p - t)^2)`: the colour images' loss.
    Mse,
    /// Binary cross-entropy of probabilities, `mean(-(t ln q + (1 - t) ln(1 - q)))` with
    /// `q = clamp(p, BCE_EPS, 1 - BCE_EPS)`: the greyscale images' loss.
    Bce,
}

impl Loss {
    fn params(n: usize) -> Params {
        Params { n: n as u32, inv_n: 1.0 / n as f32, eps: BCE_EPS }
    }

    /// Writes the loss of `pred` against `target` (same shapes) into `loss` `[1]`.
    pub fn forward(
        self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        pred: &Tensor,
        target: &Tensor,
        loss: &Tensor,
    ) -> Result<()> {
        let (op, entry, entry4) = match self {
            Loss::Mse => ("mse_forward", "mse_mean", "mse_mean_vec4"),
            Loss::Bce => ("bce_forward", "bce_mean", "bce_mean_vec4"),
        };
        expect_shape(op, "target", target, pred.shape())?;
        expect_shape(op, "loss", loss, &[1])?;
        let n = pred.numel();
        // One workgroup sums the terms as it makes them (`terms_from`, `write_mean` in loss.wgsl).
        let entry = if n.is_multiple_of(4) { entry4 } else { entry };
        gpu.dispatch(pass, SHADER, entry, &Self::params(n), &[Arg::R(pred), Arg::R(target), Arg::W(loss)], [1, 1, 1])
    }

    /// Writes `dpred` (the prediction's shape) from the upstream gradient `dloss` `[1]`.
    pub fn backward(
        self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        pred: &Tensor,
        target: &Tensor,
        dloss: &Tensor,
        dpred: &Tensor,
    ) -> Result<()> {
        let entry = match self {
            Loss::Mse => "mse_backward",
            Loss::Bce => "bce_backward",
        };
        expect_shape(entry, "target", target, pred.shape())?;
        expect_shape(entry, "loss gradient", dloss, &[1])?;
        expect_shape(entry, "prediction gradient", dpred, pred.shape())?;
        let n = pred.numel();
        // Not `elementwise`: it would demand n values of the one-element `dloss` too.
        let args = [Arg::R(pred), Arg::R(target), Arg::R(dloss), Arg::W(dpred)];
        let (entry, count) = super::vec4_or(entry, n);
        gpu.dispatch(pass, SHADER, entry, &Self::params(n), &args, grid_1d(count as u64, 64)?)
    }
}

/// Per-image mean squared error of `a` against `b` (same shapes, `[N, ...]`) into `mse`
/// `[N]`: the input of [`psnr_from_mse`], which is a per-image metric.
pub fn per_image_mse(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, a: &Tensor, b: &Tensor, mse: &Tensor) -> Result<()> {
    let op = "per_image_mse";
    expect_shape(op, "b", b, a.shape())?;
    if a.shape().len() < 2 {
        return Err(shape_err(op, format!("a has shape {:?}, expected [N, ...] with per-image values", a.shape())));
    }
    let n = a.shape()[0];
    expect_shape(op, "mse", mse, &[n])?;
    let per = a.numel() / n;
    let terms = gpu.scratch(a.shape())?;
    let args = [Arg::R(a), Arg::R(b), Arg::W(&terms)];
    elementwise(gpu, pass, SHADER, "sq_diff", &Loss::params(a.numel()), &args, a.numel())?;
    reduce::sum_outer_inner(gpu, pass, &terms, [1, n, per], 1.0 / per as f32, mse)
}

/// `10 log10(peak^2 / mse)` in dB. `mse = 0` (identical images) gives `+inf`, the usual
/// convention, so callers averaging PSNR over a set should report such images apart;
/// a negative or NaN `mse` gives NaN.
pub fn psnr_from_mse(mse: f32, peak: f32) -> f32 {
    if mse == 0.0 {
        return f32::INFINITY;
    }
    10.0 * (peak * peak / mse).log10()
}
