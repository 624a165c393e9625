//! Elementwise product with a mask broadcast over channels (binds `shaders/mul.wgsl`):
//! `x [N, C, S...] * m [N, 1 or C, S...]`, e.g. a decoded texture times the occupancy grid
//! it paints (`nn::texture`). Backward: `dx = dy * m`, `dm = Σ_c dy * x`.

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("mul");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    c: u32,
    s: u32,
    cm: u32,
}

/// The output shape (`x`'s), or why `m` does not fit it: same rank >= 2, batch and spatial
/// sizes, and 1 or `C` channels.
pub fn output_shape(x: &[usize], m: &[usize]) -> Result<Vec<usize>> {
    if x.len() < 2 || m.len() != x.len() || m[0] != x[0] || m[2..] != x[2..] || (m[1] != 1 && m[1] != x[1]) {
        return Err(shape_err("mul", format!("the mask {m:?} must be [N, 1 or C, ...] of x {x:?}")));
    }
    Ok(x.to_vec())
}

fn params(x: &[usize], m: &[usize]) -> Result<Params> {
    output_shape(x, m)?;
    let u = |v: usize| u32::try_from(v).map_err(|_| shape_err("mul", format!("{x:?} is beyond u32 indexing")));
    Ok(Params { n: u(x[0])?, c: u(x[1])?, s: u(x[2..].iter().product())?, cm: u(m[1])? })
}

/// `y = x * m`.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, m: &Tensor, y: &Tensor) -> Result<()> {
    let p = params(x.shape(), m.shape())?;
    gpu.dispatch(pass, SHADER, "mul_forward", &p, &[Arg::R(x), Arg::R(m), Arg::W(y)], grid_1d(x.numel() as u64, 64)?)
}

/// `dx = dy * m`.
pub fn backward_x(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, m: &Tensor, dx: &Tensor) -> Result<()> {
    forward(gpu, pass, dy, m, dx)
}

/// `dm = Σ_c dy * x` (over the channels `m` was broadcast to).
pub fn backward_mask(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, dy: &Tensor, dm: &Tensor) -> Result<()> {
    let p = params(x.shape(), dm.shape())?;
    gpu.dispatch(pass, SHADER, "mul_backward_mask", &p, &[Arg::R(dy), Arg::R(x), Arg::W(dm)], grid_1d(dm.numel() as u64, 64)?)
}
