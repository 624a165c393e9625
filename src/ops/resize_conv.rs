//! The resize-convolution projection of transposed-conv weights on the GPU (binds
//! `shaders/resize_conv.wgsl`): the executor runs it after Adam, inside the training step's
//! one submit, on the weights the trainer marks (see [`crate::graph::resize_conv`], whose
//! f64 [`project`](crate::graph::resize_conv::project) is its reference).

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("resize_conv");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    kernels: u32,
}

/// The 16x16 projector as a tensor, for [`project`].
pub fn projector(gpu: &Gpu) -> Result<Tensor> {
    let p = crate::graph::resize_conv::projector_f32();
    Tensor::from_slice(gpu, &[16, 16], &p)
}

/// Projects every 4x4 kernel of `w` (`[Cin, Cout, 4, 4]`) onto the resize-convolution
/// subspace in place; `proj` is [`projector`]'s tensor.
pub fn project(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, proj: &Tensor, w: &Tensor) -> Result<()> {
    let op = "resize_conv_project";
    if w.shape().len() != 4 || w.shape()[2..] != [4, 4] {
        return Err(shape_err(op, format!("weight has shape {:?}, expected [Cin, Cout, 4, 4]", w.shape())));
    }
    super::expect_shape(op, "projector", proj, &[16, 16])?;
    let kernels = w.numel() / 16;
    gpu.dispatch(pass, SHADER, op, &Params { kernels: kernels as u32 }, &[Arg::R(proj), Arg::W(w)], grid_1d(kernels as u64, 64)?)
}
