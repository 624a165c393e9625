//! The texture family's packings read through uniform windows on CPU adapters (see
//! `src/gpu/window.rs`: on lavapipe a per-lane uniform load costs ~1/16 of a storage load):
//! x or dy into its texture (`conv_fast_pack_tex_window`), the direct kernels' input stage
//! (`conv_direct_stage_window`) and the weights (`conv_fast_pack_weights_tex_window`). Each
//! entry records the windowed dispatches and returns true where they apply, false where the
//! caller records the storage-load packing instead.

use super::conv::{Geometry, Params};
use super::conv_fast::TEX_SHADER;
use crate::error::Result;
use super::conv_pack::write_texels;
use crate::gpu::{Arg, Gpu, Tensor, WINDOW4, align4, grid_1d, window, windows_pay};

/// Records `plan`'s dispatches into the texture `dst`: of `entry`, each binding its windows and
/// then `dst`, or (`conv_pack::write_texels`) of `entry`'s `_buf` twin `staged`, each binding
/// its windows and then the staging buffer.
#[allow(clippy::too_many_arguments)]
fn record<P: bytemuck::Pod>(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    (entry, staged): (&'static str, &'static str),
    plan: &Plan<P>,
    dst: &wgpu::TextureView,
    dim: wgpu::TextureViewDimension,
    invocations: impl Fn(&P) -> usize,
) -> Result<()> {
    let each = |pass: &mut wgpu::ComputePass<'_>, entry: &'static str, out: Arg| -> Result<()> {
        for (params, windows) in plan {
            let args: Vec<Arg> = windows.iter().map(Arg::U).chain([out]).collect();
            gpu.dispatch(pass, TEX_SHADER, entry, params, &args, grid_1d(invocations(params) as u64, 64)?)?;
        }
        Ok(())
    };
    write_texels(gpu, pass, dst, |pass, staging| each(pass, staged, Arg::W(staging)), |pass| each(pass, entry, Arg::StorageTexture(dst, dim)))
}

/// `conv_fast_pack_tex_window`: `x` ([N, C, input...] of `g`) into the texture `dst` as
/// `conv_fast_pack_tex_w4` packs it, where [`pack_windows`] applies.
pub(super) fn pack_x(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    cpad: usize,
    dst: &wgpu::TextureView,
    dim: wgpu::TextureViewDimension,
) -> Result<bool> {
    let Some(plan) = pack_windows(gpu, g, x, cpad)? else { return Ok(false) };
    let entries = ("conv_fast_pack_tex_window", "conv_fast_pack_tex_window_buf");
    record(gpu, pass, entries, &plan, dst, dim, |pk| pk.len4 as usize)?;
    Ok(true)
}

/// `conv_direct_stage_window`: `x` into the direct kernels' stage texture `dst`, where
/// [`stage_windows`] applies.
pub(super) fn stage_x(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    dst: &wgpu::TextureView,
    dim: wgpu::TextureViewDimension,
) -> Result<bool> {
    let Some(plan) = stage_windows(gpu, g, x)? else { return Ok(false) };
    record(gpu, pass, ("conv_direct_stage_window", "conv_direct_stage_window_buf"), &plan, dst, dim, |sw| sw.len as usize)?;
    Ok(true)
}

/// `conv_fast_pack_weights_tex_window`: `w` packed for the parameters `p` into the weight
/// texture `dst` of `texels` texels, where [`weight_windows`] applies.
pub(super) fn pack_w(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    p: Params,
    w: &Tensor,
    dst: &wgpu::TextureView,
    dim: wgpu::TextureViewDimension,
    texels: usize,
) -> Result<bool> {
    let Some((wat, windows)) = weight_windows(gpu, w)? else { return Ok(false) };
    let plan = vec![(Params { wat, total: texels as u32, ..p }, windows)];
    record(gpu, pass, ("conv_fast_pack_weights_tex_window", "conv_fast_pack_weights_tex_window_buf"), &plan, dst, dim, |_| texels)?;
    Ok(true)
}

/// The fewest vec4s of a channel plane that `pack_windows` packs through windows: each
/// dispatch then saves ~8x what it costs (~30 us; a storage vec4 load ~0.2 us per 8 lanes more
/// than a uniform one, `rendernet bench --operands` on a Zen 3).
const MIN_CHUNK4: usize = 2048;

/// Window dispatches: each one's parameters and the windows it binds, in binding order.
type Plan<P> = Vec<(P, Vec<Tensor>)>;

/// Parameters of one `conv_fast_pack_tex_window` dispatch (see the shader).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PackWin {
    at: [u32; 4],
    layer0: u32,
    row0: u32,
    len4: u32,
    w4n: u32,
    oh: u32,
    live: u32,
    pad: [u32; 2],
}

/// The dispatches of `pack_x`'s texture packing through uniform windows, each with its four
/// windows (channels 4q..4q+3 of one item over a chunk of whole rows), where they apply: a
/// CPU adapter ([`windows_pay`]), a width of whole vec4s and every window placeable. Chunks
/// take as many rows as a window holds or, where the binding alignment moves a window's start
/// back, as many as fit beside that slack (usually one row fewer). Quads wholly past the channels (dy's padding to 16 channels for the
/// weight gradient) are not written: they only meet the padded output channels, whose partial
/// sums `conv_fast_weight_sum` drops, and each dispatch costs ~30 us.
fn pack_windows(gpu: &Gpu, g: &Geometry, x: &Tensor, cpad: usize) -> Result<Option<Plan<PackWin>>> {
    let [id, ih, iw] = g.input;
    if !iw.is_multiple_of(4) || !windows_pay(gpu, 4) || iw / 4 > WINDOW4 {
        return Ok(None);
    }
    let w4n = iw / 4;
    let (rows, plane4) = (id * ih, id * ih * iw / 4);
    // A dispatch per quad and chunk: where planes are small (the projection's 512 channels of
    // 32 x 32) their cost outweighs the loads saved.
    if plane4 < MIN_CHUNK4 {
        return Ok(None);
    }
    let fewer = (WINDOW4 + 1 - align4(gpu)) / w4n;
    'sizes: for chunk in [WINDOW4 / w4n, fewer] {
        if chunk == 0 {
            continue;
        }
        let mut plan = Vec::new();
        for row0 in (0..rows).step_by(chunk) {
            let len4 = (chunk.min(rows - row0) * w4n) as u32;
            for (n, q) in (0..g.n).flat_map(|n| (0..cpad / 4).map(move |q| (n, q))) {
                let live = g.ci.saturating_sub(4 * q).min(4);
                if live == 0 {
                    continue;
                }
                let mut at = [0; 4];
                let mut windows = Vec::with_capacity(4);
                for (k, at_k) in at.iter_mut().enumerate() {
                    let c = if k < live { 4 * q + k } else { 0 };
                    let Some((t, a)) = window(gpu, x, (n * g.ci + c) * plane4 + row0 * w4n, len4 as usize)? else { continue 'sizes };
                    *at_k = a;
                    windows.push(t);
                }
                let layer0 = ((n * cpad / 4 + q) * id) as u32;
                let pk = PackWin { at, layer0, row0: row0 as u32, len4, w4n: w4n as u32, oh: ih as u32, live: live as u32, pad: [0; 2] };
                plan.push((pk, windows));
            }
        }
        return Ok(Some(plan));
    }
    Ok(None)
}

/// Parameters of one `conv_direct_stage_window` dispatch (see the shader).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct StageWin {
    at: [u32; 4],
    first: u32,
    len: u32,
    w4n: u32,
    ih: u32,
}

/// The dispatches of `stage_x` through uniform windows (four consecutive windows each, a
/// window past the end binding the last again), where they apply: a CPU adapter, a width of whole
/// vec4s and every window placeable.
fn stage_windows(gpu: &Gpu, g: &Geometry, x: &Tensor) -> Result<Option<Plan<StageWin>>> {
    let [_, ih, iw] = g.input;
    if !iw.is_multiple_of(4) || !windows_pay(gpu, 4) {
        return Ok(None);
    }
    let total = x.numel() / 4;
    let mut plan = Vec::new();
    for first in (0..total).step_by(4 * WINDOW4) {
        let len = (4 * WINDOW4).min(total - first);
        let Some((at, windows)) = consecutive_windows(gpu, x, first, len)? else { return Ok(None) };
        plan.push((StageWin { at, first: first as u32, len: len as u32, w4n: (iw / 4) as u32, ih: ih as u32 }, windows));
    }
    Ok(Some(plan))
}

/// The (up to) four windows `conv_fast_pack_weights_tex_window` reads `w` through and where
/// each one's first vec4 lies in its binding, where they apply: a CPU adapter, `w` within four
/// windows (64k values; a window past its end binds the last again) and every window
/// placeable (a small `w` needs a buffer of at least 64 KiB, as the flat parameter buffer).
fn weight_windows(gpu: &Gpu, w: &Tensor) -> Result<Option<([u32; 4], Vec<Tensor>)>> {
    let total4 = w.numel() / 4;
    if !windows_pay(gpu, 4) || total4 == 0 || total4 > 4 * WINDOW4 || !w.numel().is_multiple_of(4) {
        return Ok(None);
    }
    consecutive_windows(gpu, w, 0, total4)
}

/// The four consecutive windows a dispatch reads over `t`'s vec4s `[first, first + len)` (`len`
/// at least 1 and at most four windows): window k holds vec4s from `first + 4096 k` on, a window
/// past the range binding the last one again. Each one's index of its first vec4 in its binding,
/// and the views; `None` where one cannot be placed.
fn consecutive_windows(gpu: &Gpu, t: &Tensor, first: usize, len: usize) -> Result<Option<([u32; 4], Vec<Tensor>)>> {
    let (mut at, mut windows) = ([0; 4], Vec::with_capacity(4));
    for (k, at_k) in at.iter_mut().enumerate() {
        let start = first + (k * WINDOW4).min(len - 1) / WINDOW4 * WINDOW4;
        let Some((view, a)) = window(gpu, t, start, WINDOW4.min(first + len - start))? else { return Ok(None) };
        *at_k = a;
        windows.push(view);
    }
    Ok(Some((at, windows)))
}
