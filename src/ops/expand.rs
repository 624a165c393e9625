//! Broadcast over space (binds `shaders/expand.wgsl`): `x [N, C, 1...]` repeated into
//! `y [N, C, S...]`, e.g. a colour read from a code painted over a whole grid
//! (`nn::texture`). Backward: `dx = Σ_s dy`, the deterministic sum of `ops::reduce`.

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("expand");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    rows: u32,
    s: u32,
}

/// The output shape `[N, C, to...]`, or why `x` cannot be broadcast to it: `x` must be
/// `[N, C]` or have only size-1 axes after the channels, and `to` no zero size.
pub fn output_shape(x: &[usize], to: &[usize]) -> Result<Vec<usize>> {
    if x.len() < 2 || x[2..].iter().any(|&d| d != 1) || to.is_empty() || to.contains(&0) {
        return Err(shape_err("expand", format!("{x:?} cannot be broadcast to [N, C, {to:?}]: it needs [N, C, 1...] and non-zero sizes")));
    }
    Ok([&x[..2], to].concat())
}

fn params(x: &[usize], y: &[usize]) -> Result<Params> {
    output_shape(x, &y[2.min(y.len())..])?;
    let u = |v: usize| u32::try_from(v).map_err(|_| shape_err("expand", format!("{y:?} is beyond u32 indexing")));
    let rows = x[0] * x[1];
    let s: usize = y[2..].iter().product();
    u(rows * s)?;
    Ok(Params { rows: u(rows)?, s: u(s)? })
}

/// `y[n, c, s] = x[n, c]`.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, y: &Tensor) -> Result<()> {
    let p = params(x.shape(), y.shape())?;
    gpu.dispatch(pass, SHADER, "expand_forward", &p, &[Arg::R(x), Arg::W(y)], grid_1d(y.numel() as u64, 64)?)
}

/// `dx[n, c] = Σ_s dy[n, c, s]`.
pub fn backward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, dx: &Tensor) -> Result<()> {
    let p = params(dx.shape(), dy.shape())?;
    super::reduce::sum_outer_inner(gpu, pass, dy, [1, p.rows as usize, p.s as usize], 1.0, dx)
}
