//! Residual add and gradient accumulation (binds `shaders/add.wgsl`).
//!
//! The backward of `y = a + b` is `da = db = dy`: the executor [`copy`]s or [`accumulate`]s
//! `dy` into each input's gradient.

use super::{elementwise, expect_shape};
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Shader, Tensor, wgsl};

const SHADER: Shader = wgsl!("add");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
}

/// `y = a + b`; all three of one shape.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, a: &Tensor, b: &Tensor, y: &Tensor) -> Result<()> {
    expect_shape("add", "b", b, a.shape())?;
    expect_shape("add", "output", y, a.shape())?;
    let n = a.numel();
    elementwise(gpu, pass, SHADER, "add_forward", &Params { n: n as u32 }, &[Arg::R(a), Arg::R(b), Arg::W(y)], n)
}

/// `acc += x`, for summing gradients where a tensor feeds several nodes.
pub fn accumulate(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, acc: &Tensor) -> Result<()> {
    expect_shape("add_accumulate", "accumulator", acc, x.shape())?;
    let n = x.numel();
    elementwise(gpu, pass, SHADER, "add_accumulate", &Params { n: n as u32 }, &[Arg::R(x), Arg::W(acc)], n)
}

/// `dst = src` (a gradient handed on unchanged, as through a residual add).
pub fn copy(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, src: &Tensor, dst: &Tensor) -> Result<()> {
    expect_shape("add_copy", "destination", dst, src.shape())?;
    let n = src.numel();
    elementwise(gpu, pass, SHADER, "add_copy", &Params { n: n as u32 }, &[Arg::R(src), Arg::W(dst)], n)
}

/// `dst = src` with another shape of the same size (a reshape: memory is row-major, so the
/// values keep their order).
pub fn reshape(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, src: &Tensor, dst: &Tensor) -> Result<()> {
    if dst.numel() != src.numel() {
        return Err(crate::error::shape_err("reshape", format!("{:?} and {:?} differ in size", src.shape(), dst.shape())));
    }
    let n = src.numel();
    elementwise(gpu, pass, SHADER, "add_copy", &Params { n: n as u32 }, &[Arg::R(src), Arg::W(dst)], n)
}
