//! PReLU, one slope per channel (binds `shaders/prelu.wgsl`). Works on any rank >= 2
//! tensor with channels on axis 1 (NCDHW in the 3D trunk, NCHW in the 2D part).

use super::{expect_shape, reduce};
use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("prelu");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    c: u32,
    s: u32,
}

/// `[N, C, S]`: batch, channels, and the product of the spatial dimensions.
fn dims(x: &Tensor, alpha: &Tensor) -> Result<[usize; 3]> {
    let sh = x.shape();
    if sh.len() < 2 {
        return Err(shape_err("prelu", format!("input {sh:?} needs a channel axis (rank >= 2)")));
    }
    expect_shape("prelu", "alpha", alpha, &[sh[1]])?;
    Ok([sh[0], sh[1], sh[2..].iter().product()])
}

fn numel([n, c, s]: [usize; 3]) -> u64 {
    (n * c * s) as u64
}

fn params([n, c, s]: [usize; 3]) -> Params {
    Params { n: (n * c * s) as u32, c: c as u32, s: s as u32 }
}

/// Parameters of the row kernels (`S` a multiple of 4): see `shaders/prelu.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RowParams {
    rows: u32,
    c: u32,
    s4: u32,
    chunks: u32,
    per: u32,
}

/// vec4s per invocation in the row kernels: enough that the per-invocation channel lookup
/// and slope load cost little, few enough that a 64^3 row still spans several workgroups.
const PER: usize = 8;

/// The row kernels' parameters and workgroup count, where `S` splits into whole vec4s.
fn rows([n, c, s]: [usize; 3]) -> Option<(RowParams, usize)> {
    if !s.is_multiple_of(4) {
        return None;
    }
    let chunks = (s / 4).div_ceil(64 * PER).max(1);
    let p = RowParams { rows: (n * c) as u32, c: c as u32, s4: (s / 4) as u32, chunks: chunks as u32, per: PER as u32 };
    Some((p, n * c * chunks))
}

/// `y = x` where `x > 0`, else `alpha[c] * x`; `alpha` is `[C]`.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, alpha: &Tensor, y: &Tensor) -> Result<()> {
    let d = dims(x, alpha)?;
    expect_shape("prelu", "output", y, x.shape())?;
    let args = [Arg::R(x), Arg::R(alpha), Arg::W(y)];
    match rows(d) {
        Some((rp, groups)) => gpu.dispatch(pass, SHADER, "prelu_forward_rows", &rp, &args, grid_1d(groups as u64, 1)?),
        None => gpu.dispatch(pass, SHADER, "prelu_forward", &params(d), &args, grid_1d(numel(d), 64)?),
    }
}

/// Gradients to the input (`dx`, shape of `x`) and to the slopes (`dalpha`, `[C]`).
pub fn backward(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    alpha: &Tensor,
    dy: &Tensor,
    dx: &Tensor,
    dalpha: &Tensor,
) -> Result<()> {
    let d = dims(x, alpha)?;
    for (name, t) in [("dy", dy), ("dx", dx)] {
        expect_shape("prelu", name, t, x.shape())?;
    }
    expect_shape("prelu", "dalpha", dalpha, alpha.shape())?;
    let [n, c, _] = d;
    match rows(d) {
        Some((rp, groups)) => {
            // 64 partial sums of the slope gradient per workgroup, summed per channel below.
            let partial = gpu.scratch(&[groups * 64])?;
            let args = [Arg::R(x), Arg::R(alpha), Arg::R(dy), Arg::W(dx), Arg::W(&partial)];
            gpu.dispatch(pass, SHADER, "prelu_backward_rows", &rp, &args, grid_1d(groups as u64, 1)?)?;
            reduce::sum_outer_inner(gpu, pass, &partial, [n, c, rp.chunks as usize * 64], 1.0, dalpha)
        }
        None => {
            let contrib = gpu.scratch(x.shape())?;
            let args = [Arg::R(x), Arg::R(alpha), Arg::R(dy), Arg::W(dx), Arg::W(&contrib)];
            gpu.dispatch(pass, SHADER, "prelu_backward", &params(d), &args, grid_1d(numel(d), 64)?)?;
            reduce::sum_outer_inner(gpu, pass, &contrib, d, 1.0, dalpha)
        }
    }
}
