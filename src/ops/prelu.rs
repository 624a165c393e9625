//! PReLU, one slope per channel (binds `shaders/prelu.wgsl`). Works on any rank >= 2
//! tensor with channels on axis 1 (NCDHW in the 3D trunk, NCHW in the 2D part).

use super::{expect_shape, reduce};
use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, WINDOW4, align4, grid_1d, wgsl, windows_pay};

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

/// Windows a dispatch reads (the shader's bindings wx0..wx3 and wdy0..wdy3: nine uniform
/// buffers with the parameters, within WebGPU's default limit of 12).
const WINDOWS: usize = 4;

/// Parameters of one window dispatch: see `shaders/prelu.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct WinParams {
    base4: [u32; 4],
    c: u32,
    s4: u32,
    start4: u32,
    end4: u32,
    per: u32,
    pad: [u32; 3],
}

/// The window dispatches over a tensor of dims `[n, c, s]`, in order, where they apply: a
/// CPU adapter ([`windows_pay`]), `S` split into whole vec4s, the tensor holding at least
/// one window, and every window's offset within it suiting a uniform binding (the tensor's
/// own offset is [`window_aligned`]'s to check). The tensor's last window ends at its end
/// (so it may overlap the one before); `per`, the vec4s an invocation takes, divides both a
/// row and a window.
fn windows(gpu: &Gpu, [n, c, s]: [usize; 3]) -> Option<Vec<WinParams>> {
    let total4 = n * c * s / 4;
    let last_base = total4.checked_sub(WINDOW4)?;
    let fits = windows_pay(gpu, 2 * WINDOWS)
        && s.is_multiple_of(4)
        && (total4.is_multiple_of(WINDOW4) || last_base.is_multiple_of(align4(gpu)));
    if !fits {
        return None;
    }
    let s4 = s / 4;
    let per = [8, 4, 2, 1].into_iter().find(|p| s4.is_multiple_of(*p)).unwrap_or(1);
    let u = |v: usize| v as u32;
    let dispatch = |d: usize| {
        let start4 = d * WINDOWS * WINDOW4;
        let base4 = std::array::from_fn(|k| u((start4 + k * WINDOW4).min(last_base)));
        let end4 = u((start4 + WINDOWS * WINDOW4).min(total4));
        WinParams { base4, c: u(c), s4: u(s4), start4: u(start4), end4, per: u(per), pad: [0; 3] }
    };
    Some((0..total4.div_ceil(WINDOWS * WINDOW4)).map(dispatch).collect())
}

/// Whether `t` starts where a uniform binding may (its windows then do too).
fn window_aligned(gpu: &Gpu, t: &Tensor) -> bool {
    (t.offset() as usize).is_multiple_of(align4(gpu) * 16)
}

/// The four 64 KiB ranges of `t` that dispatch `w` reads, as tensors to bind as uniform
/// buffers (a window past the tensor's end repeats the last one; no invocation reads it).
fn windows_of(t: &Tensor, w: &WinParams) -> Result<Vec<Tensor>> {
    w.base4.iter().map(|&b| Tensor::view(t.clone().into_buffer(), t.offset() + b as u64 * 16, &[WINDOW4 * 4])).collect()
}

/// Invocations (and so the grid) of dispatch `w`.
fn window_grid(w: &WinParams) -> Result<[u32; 3]> {
    grid_1d(((w.end4 - w.start4) as u64).div_ceil(w.per as u64), 64)
}

/// `y = x` where `x > 0`, else `alpha[c] * x`; `alpha` is `[C]`.
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, alpha: &Tensor, y: &Tensor) -> Result<()> {
    let d = dims(x, alpha)?;
    expect_shape("prelu", "output", y, x.shape())?;
    if let Some(ws) = windows(gpu, d).filter(|_| window_aligned(gpu, x)) {
        for w in &ws {
            let xw = windows_of(x, w)?;
            let args: Vec<Arg> = xw.iter().map(Arg::U).chain([Arg::R(alpha), Arg::W(y)]).collect();
            gpu.dispatch(pass, SHADER, "prelu_forward_window", w, &args, window_grid(w)?)?;
        }
        return Ok(());
    }
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
    let [n, c, s] = d;
    // Both x and dy are read through the windows.
    if let Some(ws) = windows(gpu, d).filter(|_| window_aligned(gpu, x) && window_aligned(gpu, dy)) {
        let per = ws[0].per as usize;
        let partial = gpu.scratch(&[n * c * s / 4 / per])?;
        for w in &ws {
            let (xw, dyw) = (windows_of(x, w)?, windows_of(dy, w)?);
            let args: Vec<Arg> =
                xw.iter().map(Arg::U).chain([Arg::R(alpha)]).chain(dyw.iter().map(Arg::U)).chain([Arg::W(dx), Arg::W(&partial)]).collect();
            gpu.dispatch(pass, SHADER, "prelu_backward_window", w, &args, window_grid(w)?)?;
        }
        return reduce::sum_outer_inner(gpu, pass, &partial, [n, c, s / 4 / per], 1.0, dalpha);
    }
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
