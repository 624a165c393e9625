//! Logistic sigmoid, the output heads' activation (binds `shaders/sigmoid.wgsl`).

use super::elementwise;
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Shader, Tensor, wgsl};

const SHADER: Shader = wgsl!("sigmoid");

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
