//! The gradient guard (binds `shaders/finite.wgsl`): flags tensors holding NaN or Inf so the
//! optimizer can skip a poisoned step on the GPU, inside the step's single submit.

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, wgsl};

const SHADER: Shader = wgsl!("finite");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    slot: u32,
}

/// `flags[slot] = 1` if `x` holds a NaN or Inf, else 0. `slot` must be >= 1 (slot 0 is the
/// summary written by [`any`]).
pub fn check(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, flags: &Tensor, slot: usize) -> Result<()> {
    if slot == 0 || slot >= flags.numel() {
        return Err(shape_err("finite_check", format!("slot {slot} outside 1..{} of flags {:?}", flags.numel(), flags.shape())));
    }
    let n = x.numel();
    let p = Params { n: n as u32, slot: slot as u32 };
    // One workgroup whatever n: only the entry point depends on it.
    let (entry, _) = super::vec4_or("finite_check", n);
    gpu.dispatch(pass, SHADER, entry, &p, &[Arg::R(x), Arg::W(flags)], [1, 1, 1])
}

/// Checks all of `x` (a multiple of 4 values: the executor's flat gradient buffer) in up to
/// `chunks` workgroups of one dispatch, setting `flags[1 + g]` for chunk `g`; returns the
/// number of chunks, the `count` to pass to [`any`].
pub fn check_chunks(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, flags: &Tensor, chunks: usize) -> Result<usize> {
    let n = x.numel();
    if !n.is_multiple_of(4) || chunks == 0 || chunks >= flags.numel() {
        return Err(shape_err(
            "finite_check_chunks",
            format!("{n} values (must be a multiple of 4) in {chunks} chunks (1..{} for flags {:?})", flags.numel(), flags.shape()),
        ));
    }
    let per = (n / 4).div_ceil(chunks);
    let groups = (n / 4).div_ceil(per);
    let p = Params { n: n as u32, slot: per as u32 };
    gpu.dispatch(pass, SHADER, "finite_check_chunks_vec4", &p, &[Arg::R(x), Arg::W(flags)], [groups as u32, 1, 1])?;
    Ok(groups)
}

/// `flags[0] = 1` if any of `flags[1..=count]` is set, else 0.
pub fn any(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, flags: &Tensor, count: usize) -> Result<()> {
    if count + 1 > flags.numel() {
        return Err(shape_err("finite_any", format!("{count} slots do not fit flags {:?}", flags.shape())));
    }
    let p = Params { n: count as u32, slot: 0 };
    gpu.dispatch(pass, SHADER, "finite_any", &p, &[Arg::W(flags)], [1, 1, 1])
}
