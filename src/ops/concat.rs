//! Concatenation along the channel axis (binds `shaders/concat.wgsl`): `[N, C1, S...]` and
//! `[N, C2, S...]` into `[N, C1 + C2, S...]`, e.g. a shape code with pose and light vectors
//! (the EC baselines, the shape prior). Backward splits `dy` into the parts' gradients.

use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("concat");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
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

/// One dispatch per present part: `entry` copies between the part and its channel range of
/// `whole` (forward: part into whole; backward: whole into part).
fn per_part(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, forward: bool, whole: &Tensor, shapes: &[&[usize]], parts: &[Option<&Tensor>]) -> Result<()> {
    let want = output_shape(shapes)?;
    if whole.shape() != want {
        return Err(shape_err("concat", format!("the whole has shape {:?}, expected {want:?}", whole.shape())));
    }
    let mut c0 = 0;
    for (shape, part) in shapes.iter().zip(parts) {
        if let Some(t) = part {
            if t.shape() != *shape {
                return Err(shape_err("concat", format!("part {:?} where {shape:?} was expected", t.shape())));
            }
            let s: usize = shape[2..].iter().product();
            let p = Params { n: shape[0] as u32, cp: shape[1] as u32, cy: want[1] as u32, s: s as u32, c0: c0 as u32 };
            let (entry, args) = if forward {
                ("concat_forward", [Arg::R(t), Arg::W(whole)])
            } else {
                ("concat_backward", [Arg::R(whole), Arg::W(t)])
            };
            gpu.dispatch(pass, SHADER, entry, &p, &args, grid_1d(t.numel() as u64, 64)?)?;
        }
        c0 += shape[1];
    }
    Ok(())
}

/// `y = [a, b, ...]` along axis 1.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, parts: &[&Tensor], y: &Tensor) -> Result<()> {
    let shapes: Vec<&[usize]> = parts.iter().map(|t| t.shape()).collect();
    let parts: Vec<Option<&Tensor>> = parts.iter().map(|&t| Some(t)).collect();
    per_part(gpu, pass, true, y, &shapes, &parts)
}

/// Each part's gradient from `dy`. `shapes` are the parts' shapes, in order (they place the
/// parts); a part whose slot in `dparts` is `None` gets none.
pub fn backward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, shapes: &[&[usize]], dparts: &[Option<&Tensor>]) -> Result<()> {
    per_part(gpu, pass, false, dy, shapes, dparts)
}
