//! ELU (binds `shaders/elu.wgsl`), the graph op `Op::Elu`; no network of this crate uses it
//! yet.

use super::elementwise;
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Shader, Tensor, wgsl};

const SHADER: Shader = wgsl!("elu");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    alpha: f32,
}

/// `y = x` for `x > 0`, `alpha (e^x - 1)` otherwise.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, alpha: f32, x: &Tensor, y: &Tensor) -> Result<()> {
    let n = x.numel();
    let p = Params { n: n as u32, alpha };
    elementwise(gpu, pass, SHADER, "elu_forward", &p, &[Arg::R(x), Arg::W(y)], n)
}

/// `dx = dy` for `x > 0`, `dy * alpha * e^x` otherwise, from the forward input `x`.
pub fn backward(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    alpha: f32,
    x: &Tensor,
    dy: &Tensor,
    dx: &Tensor,
) -> Result<()> {
    let n = x.numel();
    let p = Params { n: n as u32, alpha };
    elementwise(gpu, pass, SHADER, "elu_backward", &p, &[Arg::R(x), Arg::R(dy), Arg::W(dx)], n)
}
