//! Concatenation along the channel axis (binds `shaders/concat.wgsl`): `[N, C1, S...]` and
//! `[N, C2, S...]` into `[N, C1 + C2, S...]`, e.g. a shape code with pose and light vectors
//! (the EC baselines, the shape prior). Backward splits `dy` into the parts' gradients.
//! Also concatenation along axis 0 (sibling layers' weights and biases, so one conv computes
//! them all) and its inverse on channels, narrowing (`[N, C, S...]` to channels `start ..
//! start + len`).

use super::expect_shape;
use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("concat": "channel_range", "concat");

/// The uniform block of the channel kernels (`ChannelRange` in `shaders/channel_range.wgsl`):
/// a part or range of `cp` channels at channel `c0` of a whole of `cy`, `n` items of `s`
/// values a channel.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Params {
    n: u32,
    cp: u32,
    cy: u32,
    s: u32,
    c0: u32,
}

/// The shape of the concatenation of `parts` along axis 1, or why they do not fit (same
/// rank >= 2, same batch and spatial sizes).
pub fn output_shape(parts: &[&[usize]]) -> Result<Vec<usize>> {
    let first = parts.first().ok_or_else(|| shape_err("concat", "needs at least one input"))?;
    if first.len() < 2 {
        return Err(shape_err("concat", format!("inputs must be [N, C, ...]; got {first:?}")));
    }
    let mut out = first.to_vec();
    for p in &parts[1..] {
        if p.len() != first.len() || p[0] != first[0] || p[2..] != first[2..] {
            return Err(shape_err("concat", format!("{p:?} does not match {first:?} outside axis 1")));
        }
        out[1] += p[1];
    }
    Ok(out)
}

/// One dispatch per present part, concatenated along `axis` (0 or 1): `entry` copies between
/// the part and its range of `whole` (forward: part into whole; backward: whole into part).
/// Along axis 0 a part `[Op, rest...]` is the channel kernels' `[1, Op, rest]`.
fn per_part(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, forward: bool, axis: usize, whole: &Tensor, shapes: &[&[usize]], parts: &[Option<&Tensor>]) -> Result<()> {
    let want = if axis == 0 { output_shape_axis0(shapes)? } else { output_shape(shapes)? };
    if whole.shape() != want {
        return Err(shape_err("concat", format!("the whole has shape {:?}, expected {want:?}", whole.shape())));
    }
    let mut c0 = 0;
    for (shape, part) in shapes.iter().zip(parts) {
        // The part as [n, cp, s] of a whole with cy along the axis.
        let (n, cp) = if axis == 0 { (1, shape[0]) } else { (shape[0], shape[1]) };
        let s = shape[axis + 1..].iter().product::<usize>() as u32;
        if let Some(t) = part {
            if t.shape() != *shape {
                return Err(shape_err("concat", format!("part {:?} where {shape:?} was expected", t.shape())));
            }
            let p = Params { n: n as u32, cp: cp as u32, cy: want[axis] as u32, s, c0 };
            let (entry, args) = if forward {
                ("concat_forward", [Arg::R(t), Arg::W(whole)])
            } else {
                ("concat_backward", [Arg::R(whole), Arg::W(t)])
            };
            gpu.dispatch(pass, SHADER, entry, &p, &args, grid_1d(t.numel() as u64, 64)?)?;
        }
        c0 += cp as u32;
    }
    Ok(())
}

/// `y` = `parts` concatenated along `axis`.
fn forward_along(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, axis: usize, parts: &[&Tensor], y: &Tensor) -> Result<()> {
    let shapes: Vec<&[usize]> = parts.iter().map(|t| t.shape()).collect();
    let parts: Vec<Option<&Tensor>> = parts.iter().map(|&t| Some(t)).collect();
    per_part(gpu, pass, true, axis, y, &shapes, &parts)
}

/// The shape of the concatenation of `parts` along axis 0 (same rank >= 1, same sizes on
/// the other axes), or why they do not fit.
pub fn output_shape_axis0(parts: &[&[usize]]) -> Result<Vec<usize>> {
    let first = parts.first().ok_or_else(|| shape_err("concat_axis0", "needs at least one input"))?;
    if first.is_empty() {
        return Err(shape_err("concat_axis0", "inputs need at least one axis"));
    }
    let mut out = first.to_vec();
    for p in &parts[1..] {
        if p.len() != first.len() || p[1..] != first[1..] {
            return Err(shape_err("concat_axis0", format!("{p:?} does not match {first:?} outside axis 0")));
        }
        out[0] += p[0];
    }
    Ok(out)
}

/// `y = [a, b, ...]` along axis 0.
pub fn forward_axis0(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, parts: &[&Tensor], y: &Tensor) -> Result<()> {
    forward_along(gpu, pass, 0, parts, y)
}

/// Each part's gradient from `dy` of [`forward_axis0`]; `shapes` place the parts, and a part
/// whose slot in `dparts` is `None` gets none.
pub fn backward_axis0(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, shapes: &[&[usize]], dparts: &[Option<&Tensor>]) -> Result<()> {
    per_part(gpu, pass, false, 0, dy, shapes, dparts)
}

/// The shape of channels `start .. start + len` of `x` ([N, C, ...]), or why there are none.
pub fn narrow_shape(x: &[usize], start: usize, len: usize) -> Result<Vec<usize>> {
    if x.len() < 2 || len == 0 || start + len > x[1] {
        return Err(shape_err("narrow", format!("channels {start}..{} of {x:?} (needs [N, C, ...] with len >= 1 and start + len <= C)", start + len)));
    }
    let mut out = x.to_vec();
    out[1] = len;
    Ok(out)
}

/// The channel kernels' parameters of the range `range` (`[N, len, ...]`, named `what` in
/// errors of `op`) at channels `start .. start + len` of a whole of shape `whole`, its shape
/// checked.
pub(super) fn range_params(op: &str, what: &str, whole: &[usize], start: usize, range: &Tensor) -> Result<Params> {
    let len = range.shape().get(1).copied().unwrap_or(0);
    expect_shape(op, what, range, &narrow_shape(whole, start, len)?)?;
    let s = whole[2..].iter().product::<usize>() as u32;
    Ok(Params { n: whole[0] as u32, cp: len as u32, cy: whole[1] as u32, s, c0: start as u32 })
}

/// `y` = channels `start ..` of `x` (as many as `y` has).
pub fn narrow(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, start: usize, y: &Tensor) -> Result<()> {
    let p = range_params("narrow", "y", x.shape(), start, y)?;
    gpu.dispatch(pass, SHADER, "concat_backward", &p, &[Arg::R(x), Arg::W(y)], grid_1d(y.numel() as u64, 64)?)
}

/// The gradient of [`narrow`]: `dx` = `dy` on channels `start ..`, zero elsewhere.
pub fn narrow_backward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, start: usize, dx: &Tensor) -> Result<()> {
    let p = range_params("narrow", "dy", dx.shape(), start, dy)?;
    gpu.dispatch(pass, SHADER, "narrow_backward", &p, &[Arg::R(dy), Arg::W(dx)], grid_1d(dx.numel() as u64, 64)?)
}

/// Adds the gradient of [`narrow`] into `dx`: `dx` += `dy` on channels `start ..`, the
/// other channels untouched (a later channel range's gradient summed into the first's).
pub fn narrow_backward_add(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, start: usize, dx: &Tensor) -> Result<()> {
    let p = range_params("narrow", "dy", dx.shape(), start, dy)?;
    gpu.dispatch(pass, SHADER, "narrow_backward_add", &p, &[Arg::R(dy), Arg::W(dx)], grid_1d(dy.numel() as u64, 64)?)
}

/// `y = [a, b, ...]` along axis 1.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, parts: &[&Tensor], y: &Tensor) -> Result<()> {
    forward_along(gpu, pass, 1, parts, y)
}

/// Each part's gradient from `dy`. `shapes` are the parts' shapes, in order (they place the
/// parts); a part whose slot in `dparts` is `None` gets none.
pub fn backward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, shapes: &[&[usize]], dparts: &[Option<&Tensor>]) -> Result<()> {
    per_part(gpu, pass, false, 1, dy, shapes, dparts)
}
