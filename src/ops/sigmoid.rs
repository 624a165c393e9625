//! Logistic sigmoid, the output heads' activation (binds `shaders/sigmoid.wgsl`).

use super::concat::range_params;
use super::{elementwise, expect_shape};
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("sigmoid": "channel_range", "sigmoid");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
}

/// `y = 1 / (1 + e^-x)`, elementwise; `y` has `x`'s shape.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, y: &Tensor) -> Result<()> {
    let n = x.numel();
    elementwise(gpu, pass, SHADER, "sigmoid_forward", &Params { n: n as u32 }, &[Arg::R(x), Arg::W(y)], n)
}

/// `dx = dy * y * (1 - y)` from the forward output `y`.
pub fn backward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, y: &Tensor, dy: &Tensor, dx: &Tensor) -> Result<()> {
    let n = y.numel();
    let args = [Arg::R(y), Arg::R(dy), Arg::W(dx)];
    elementwise(gpu, pass, SHADER, "sigmoid_backward", &Params { n: n as u32 }, &args, n)
}

/// `y = sigmoid(x[:, start .. start + len])` (`len` = `y`'s channels): a channel range then
/// the sigmoid in one dispatch, with no copy of the range.
pub fn forward_range(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, start: usize, y: &Tensor) -> Result<()> {
    let p = range_params("sigmoid_forward_range", "range", x.shape(), start, y)?;
    gpu.dispatch(pass, SHADER, "sigmoid_forward_range", &p, &[Arg::R(x), Arg::W(y)], grid_1d(y.numel() as u64, 64)?)
}

/// The gradient of `x` from [`forward_range`]'s output `y` and its gradient `dy`: written over
/// the whole of `dx` (`x`'s shape, zero outside the range), or with `add` added into its
/// range's channels, leaving the others as they are.
pub fn backward_range(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, y: &Tensor, dy: &Tensor, start: usize, dx: &Tensor, add: bool) -> Result<()> {
    let op = "sigmoid_backward_range";
    let p = range_params(op, "range", dx.shape(), start, y)?;
    expect_shape(op, "dy", dy, y.shape())?;
    let (entry, n) = if add { ("sigmoid_backward_range_add", y.numel()) } else { (op, dx.numel()) };
    gpu.dispatch(pass, SHADER, entry, &p, &[Arg::R(y), Arg::R(dy), Arg::W(dx)], grid_1d(n as u64, 64)?)
}
