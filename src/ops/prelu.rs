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

fn params([n, c, s]: [usize; 3]) -> Params {
    Params { n: (n * c * s) as u32, c: c as u32, s: s as u32 }
}

/// The entry point (`{stem}` or `{stem}_vec4`, four elements per invocation, where every
/// channel's run of `s` values splits into whole vec4s) and its invocation count.
fn entry([n, c, s]: [usize; 3], scalar: &'static str, vec4: &'static str) -> (&'static str, u64) {
    if s.is_multiple_of(4) { (vec4, (n * c * s / 4) as u64) } else { (scalar, (n * c * s) as u64) }
}

/// `y = x` where `x > 0`, else `alpha[c] * x`; `alpha` is `[C]`.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, alpha: &Tensor, y: &Tensor) -> Result<()> {
    let d = dims(x, alpha)?;
    expect_shape("prelu", "output", y, x.shape())?;
    let args = [Arg::R(x), Arg::R(alpha), Arg::W(y)];
    let (e, count) = entry(d, "prelu_forward", "prelu_forward_vec4");
    gpu.dispatch(pass, SHADER, e, &params(d), &args, grid_1d(count, 64)?)
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
    let contrib = gpu.scratch(x.shape())?;
    let args = [Arg::R(x), Arg::R(alpha), Arg::R(dy), Arg::W(dx), Arg::W(&contrib)];
    let (e, count) = entry(d, "prelu_backward", "prelu_backward_vec4");
    gpu.dispatch(pass, SHADER, e, &params(d), &args, grid_1d(count, 64)?)?;
    reduce::sum_outer_inner(gpu, pass, &contrib, d, 1.0, dalpha)
}
