//! Front-to-back compositing of a camera grid along depth (binds `shaders/composite.wgsl`):
//! `x [N, C, D, H, W]` (channel 0 the occupancy, the others premultiplied by it) to
//! `y [N, C, H, W]`, each pixel the channels seen through its column, nearer voxels hiding
//! farther ones: `y_c = Σ_k T_k x_{c,k}`, `T_k = Π_{j<k} (1 - o_j)`, k counted from the
//! camera (depth index D-1). `y_0` is the coverage. It hands a coloured RenderNet the visible
//! colour directly, which its convs otherwise learn only slowly (colour times visibility).
//! Backward: one kernel writes the gradient of every input value.

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("composite");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    c: u32,
    d: u32,
    hw: u32,
}

/// The output shape `[N, C, H, W]` for `x` `[N, C, D, H, W]`, or why `x` does not fit.
pub fn output_shape(x: &[usize]) -> Result<Vec<usize>> {
    match x {
        [n, c, d, h, w] if *c > 0 && *d > 0 => Ok(vec![*n, *c, *h, *w]),
        _ => Err(shape_err("composite", format!("needs a grid [N, C >= 1, D >= 1, H, W], got {x:?}"))),
    }
}

fn params(x: &[usize]) -> Result<(Params, u64)> {
    output_shape(x)?;
    let u = |v: usize| u32::try_from(v).map_err(|_| shape_err("composite", format!("{x:?} is beyond u32 indexing")));
    let hw = x[3] * x[4];
    Ok((Params { n: u(x[0])?, c: u(x[1])?, d: u(x[2])?, hw: u(hw)? }, (x[0] * hw) as u64))
}

/// `y = composite(x)`.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, y: &Tensor) -> Result<()> {
    let (p, columns) = params(x.shape())?;
    super::expect_shape("composite_forward", "y", y, &output_shape(x.shape())?)?;
    gpu.dispatch(pass, SHADER, "composite_forward", &p, &[Arg::R(x), Arg::W(y)], grid_1d(columns, 64)?)
}

/// `dx` (x's shape) from `dy` (y's shape).
pub fn backward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, dy: &Tensor, dx: &Tensor) -> Result<()> {
    let (p, columns) = params(x.shape())?;
    super::expect_shape("composite_backward", "dy", dy, &output_shape(x.shape())?)?;
    super::expect_shape("composite_backward", "dx", dx, x.shape())?;
    gpu.dispatch(pass, SHADER, "composite_backward", &p, &[Arg::R(x), Arg::R(dy), Arg::W(dx)], grid_1d(columns, 64)?)
}
