//! The differentiable op set. One file per op binds one `shaders/<op>.wgsl`, with forward
//! and backward entry points side by side; every function records into a caller's compute
//! pass and checks shapes and limits before anything is dispatched.
//!
//! Conventions: tensors NCDHW / NCHW, weights OIDHW / OIHW (PyTorch's), f32. Outputs are
//! caller-allocated so a memory planner can place them; backward functions write (never
//! accumulate into) their gradient outputs.

pub mod adam;
pub mod add;
pub mod composite;
pub mod concat;
pub mod conv;
pub mod conv_transpose;
mod conv_fast;
mod conv_fast_weight;
mod conv_nchw;
mod conv_operands;
mod conv_pack;
pub(crate) mod conv_pack_jobs;
mod conv_window;
pub mod dropout;
pub mod elu;
pub mod expand;
pub mod finite;
pub mod loss;
pub mod mul;
pub mod phong;
pub mod prelu;
pub mod projection;
pub mod reduce;
pub mod resample;
pub mod resize_conv;
pub mod sigmoid;

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d};

/// Dispatches an elementwise kernel of 64-wide workgroups over `n` values, after checking
/// that every tensor argument holds exactly `n` values.
pub(crate) fn elementwise<P: bytemuck::Pod>(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    shader: Shader,
    entry: &'static str,
    params: &P,
    args: &[Arg],
    n: usize,
) -> Result<()> {
    for a in args {
        if let Arg::R(t) | Arg::W(t) = a {
            if t.numel() != n {
                return Err(shape_err(entry, format!("tensor {:?} should hold {n} values", t.shape())));
            }
        }
    }
    let (entry, count) = vec4_or(entry, n);
    gpu.dispatch(pass, shader, entry, params, args, grid_1d(count as u64, 64)?)
}

/// `entry`'s `_vec4` twin and its invocation count where the shader has one and `n` (the
/// values it writes) is a multiple of 4, else `entry` itself with one value an invocation.
pub(crate) fn vec4_or(entry: &'static str, n: usize) -> (&'static str, usize) {
    match vec4_twin(entry) {
        Some(e4) if n.is_multiple_of(4) => (e4, n / 4),
        _ => (entry, n),
    }
}

/// The `_vec4` entry point that does `entry`'s work four values an invocation (their
/// shaders say why), for n a multiple of 4.
fn vec4_twin(entry: &str) -> Option<&'static str> {
    Some(match entry {
        "add_forward" => "add_forward_vec4",
        "add_accumulate" => "add_accumulate_vec4",
        "add_copy" => "add_copy_vec4",
        "sigmoid_forward" => "sigmoid_forward_vec4",
        "sigmoid_backward" => "sigmoid_backward_vec4",
        "sq_diff" => "sq_diff_vec4",
        "mse_backward" => "mse_backward_vec4",
        "adam_step" => "adam_step_vec4",
        "finite_check" => "finite_check_vec4",
        _ => return None,
    })
}

/// Checks that `t` has exactly `shape`, naming the op and the argument.
pub(crate) fn expect_shape(op: &str, arg: &str, t: &Tensor, shape: &[usize]) -> Result<()> {
    if t.shape() != shape {
        return Err(shape_err(op, format!("{arg} has shape {:?}, expected {shape:?}", t.shape())));
    }
    Ok(())
}

/// Checks that `t` has `rank` dimensions, naming the op and the argument.
pub(crate) fn expect_rank(op: &str, arg: &str, t: &Tensor, rank: usize) -> Result<()> {
    if t.shape().len() != rank {
        return Err(shape_err(op, format!("{arg} has shape {:?}, expected {rank} dimensions", t.shape())));
    }
    Ok(())
}
