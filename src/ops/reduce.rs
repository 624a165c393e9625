//! Deterministic sum over the outer and inner axes of a tensor viewed as [A, B, C]
//! (binds `shaders/reduce.wgsl`). A building block of other ops' backward passes; it has no
//! gradient of its own to register (a sum's backward is a broadcast, done by its callers).

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("reduce": "workgroup_sum", "reduce");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    a: u32,
    b: u32,
    c: u32,
    scale: f32,
}

/// `out[b] = scale * Σ_{a,c} x[a, b, c]` with `x` viewed as `[a, b, c]` (its element count
/// must be `a*b*c`) and `out` holding at least `b` values.
pub fn sum_outer_inner(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    [a, b, c]: [usize; 3],
    scale: f32,
    out: &Tensor,
) -> Result<()> {
    if a * b * c != x.numel() {
        return Err(shape_err("sum", format!("view [{a}, {b}, {c}] does not match input {:?}", x.shape())));
    }
    if out.numel() < b {
        return Err(shape_err("sum", format!("output {:?} holds fewer than {b} values", out.shape())));
    }
    let params = Params { a: a as u32, b: b as u32, c: c as u32, scale };
    // One workgroup per output value: grid_1d with a workgroup size of 1 counts groups.
    let wg = grid_1d(b as u64, 1)?;
    // Four values a load where every run along C splits into whole vec4s and is long enough
    // to keep the 64 invocations busy (a per-image MSE, a bias or PReLU gradient over space).
    let entry = if c.is_multiple_of(4) && c >= 256 { "sum_outer_inner_vec4" } else { "sum_outer_inner" };
    gpu.dispatch(pass, SHADER, entry, &params, &[Arg::R(x), Arg::W(out)], wg)
}
