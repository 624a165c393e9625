//! The tiled conv kernels of `shaders/conv_fast.wgsl` (see its header for the tiling and why
//! it suits lavapipe), behind `conv::dispatch_*`. Each call repacks its operands into
//! channels-last scratch tensors first (a memory-bound pass, a few percent of the FLOPs'
//! time), so callers keep PyTorch layouts.

use super::conv::Geometry;
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d};

const SHADER: Shader = Shader { name: "conv_fast", source: include_str!("../../shaders/conv_fast.wgsl") };

/// Mirrors `Params` in `shaders/conv_fast.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    ci: u32,
    co: u32,
    id: u32,
    ih: u32,
    iw: u32,
    od: u32,
    oh: u32,
    ow: u32,
    kd: u32,
    kh: u32,
    kw: u32,
    sd: u32,
    sh: u32,
    sw: u32,
    pd: u32,
    ph: u32,
    pw: u32,
    cpad: u32,
    co16: u32,
    flip: u32,
    has_bias: u32,
    nchunks: u32,
    chunk: u32,
    total: u32,
    fold: u32,
}

fn params(g: &Geometry, cpad: usize) -> Params {
    let u = |v: usize| v as u32;
    let [id, ih, iw] = g.input.map(u);
    let [od, oh, ow] = g.output.map(u);
    let [kd, kh, kw] = g.kernel.map(u);
    let [sd, sh, sw] = g.stride.map(u);
    let [pd, ph, pw] = g.pad.map(u);
    Params {
        n: u(g.n),
        ci: u(g.ci),
        co: u(g.co),
        id, ih, iw, od, oh, ow, kd, kh, kw, sd, sh, sw, pd, ph, pw,
        cpad: u(cpad),
        co16: u(g.co.div_ceil(16)),
        fold: 1,
        ..Default::default()
    }
}

fn dispatch(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, entry: &'static str, mut p: Params, args: &[Arg], total: usize) -> Result<()> {
    p.total = total as u32;
    gpu.dispatch(pass, SHADER, entry, &p, args, grid_1d(total as u64, 64)?)
}

/// `t` ([N, c, src...]) repacked channels-last as [N, dst..., cpad], channels past `c` zero;
/// voxel v goes to v * stride (zeros between when the stride exceeds 1, see the shader).
#[allow(clippy::too_many_arguments)]
fn pack_input(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    t: &Tensor,
    n: usize,
    c: usize,
    src: [usize; 3],
    dst: [usize; 3],
    stride: [usize; 3],
    cpad: usize,
) -> Result<Tensor> {
    let out = Tensor::zeros(gpu, &[n, volume(dst), cpad])?;
    let u = |a: [usize; 3]| a.map(|v| v as u32);
    let ([id, ih, iw], [od, oh, ow], [sd, sh, sw]) = (u(src), u(dst), u(stride));
    let p = Params { n: n as u32, ci: c as u32, id, ih, iw, od, oh, ow, sd, sh, sw, cpad: cpad as u32, ..Default::default() };
    dispatch(gpu, pass, "conv_fast_pack_input", p, &[Arg::R(t), Arg::W(&out)], n * volume(dst))?;
    Ok(out)
}

/// A conv with its innermost kernel axes folded into the input channels (see
/// `conv_fast_pack_folded`): the geometry the kernels run, and the fold sizes along H and W.
struct Folded {
    g: Geometry,
    fh: usize,
    fw: usize,
}

impl Folded {
    /// Taps per folded channel group.
    fn fold(&self) -> usize {
        self.fh * self.fw
    }
}

/// The fold of `g`'s W taps, or H and W taps, or none: whichever needs the fewest (tap,
/// channel group) iterations with channels padded to a multiple of `quantum` (4 for the
/// forward tile, 8 for the weight-gradient tile), the smaller fold on a tie. Only convs with
/// few input channels gain; the others keep `fh = fw = 1`.
fn fold(g: &Geometry, quantum: usize) -> Folded {
    let [kd, kh, kw] = g.kernel;
    let cost = |f: usize, taps: usize| taps * (g.ci * f).div_ceil(quantum);
    let (fh, fw) = [(1, 1), (1, kw), (kh, kw)].into_iter().min_by_key(|&(fh, fw)| cost(fh * fw, kd * (kh / fh) * (kw / fw))).unwrap();
    // Per folded axis: the folded value, else the conv's own.
    let on = |f: usize, folded: usize, plain: usize| if f > 1 { folded } else { plain };
    let g = Geometry {
        ci: g.ci * fh * fw,
        input: [g.input[0], on(fh, g.output[1], g.input[1]), on(fw, g.output[2], g.input[2])],
        kernel: [kd, on(fh, 1, kh), on(fw, 1, kw)],
        stride: [g.stride[0], on(fh, 1, g.stride[1]), on(fw, 1, g.stride[2])],
        pad: [g.pad[0], on(fh, 0, g.pad[1]), on(fw, 0, g.pad[2])],
        ..*g
    };
    Folded { g, fh, fw }
}

/// `x` ([N, C, input...] of the unfolded `g`) packed for the folded conv `f`, channels-last
/// with `cpad` channels (see `conv_fast_pack_folded`); without a fold, a plain packing.
fn pack_folded(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, f: &Folded, x: &Tensor, cpad: usize) -> Result<Tensor> {
    if f.fold() == 1 {
        return pack_input(gpu, pass, x, g.n, g.ci, g.input, g.input, [1; 3], cpad);
    }
    let out = Tensor::zeros(gpu, &[g.n, volume(f.g.input), cpad])?;
    let u = |v: usize| v as u32;
    let [id, ih, iw] = g.input.map(u);
    let [od, oh, ow] = f.g.input.map(u);
    // Along an unfolded axis: fold size 1, stride 1, no padding (a copy).
    let (sh, ph) = if f.fh > 1 { (u(g.stride[1]), u(g.pad[1])) } else { (1, 0) };
    let (sw, pw) = if f.fw > 1 { (u(g.stride[2]), u(g.pad[2])) } else { (1, 0) };
    let (kh, kw) = (u(f.fh), u(f.fw));
    let p = Params { n: u(g.n), ci: u(g.ci), id, ih, iw, od, oh, ow, kh, kw, sh, sw, ph, pw, cpad: u(cpad), ..Default::default() };
    dispatch(gpu, pass, "conv_fast_pack_folded", p, &[Arg::R(x), Arg::W(&out)], g.n * volume(f.g.input))?;
    Ok(out)
}

/// Weights repacked as [tap][cpad][co16 * 16] for the dispatch geometry `g`; `flip` reads a
/// forward conv's weights as those of its stride-1 backward-input conv; `fold` > 1 reads
/// them for `g` being a folded conv (see [`fold`]).
#[allow(clippy::too_many_arguments)]
fn pack_weights(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    w: &Tensor,
    cpad: usize,
    flip: bool,
    fold: usize,
) -> Result<Tensor> {
    let taps: usize = g.kernel.iter().product();
    let copad = g.co.div_ceil(16) * 16;
    let out = Tensor::zeros(gpu, &[taps, cpad, copad])?;
    let p = Params { flip: flip as u32, fold: fold as u32, ..params(g, cpad) };
    dispatch(gpu, pass, "conv_fast_pack_weights", p, &[Arg::R(w), Arg::W(&out)], out.numel())?;
    Ok(out)
}

fn volume(s: [usize; 3]) -> usize {
    s.iter().product()
}

/// The tiled forward of dispatch geometry `g` on packed operands: one invocation per 8
/// outputs along W x 16 output channels.
#[allow(clippy::too_many_arguments)]
fn forward_packed(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    xp: &Tensor,
    wp: &Tensor,
    cpad: usize,
    b: Option<&Tensor>,
    y: &Tensor,
) -> Result<()> {
    let [od, oh, ow] = g.output;
    let tiles = g.n * g.co.div_ceil(16) * od * oh * ow.div_ceil(8);
    let p = Params { has_bias: b.is_some() as u32, ..params(g, cpad) };
    let bias = b.map_or(Arg::Absent, Arg::R);
    dispatch(gpu, pass, "conv_fast_forward", p, &[Arg::R(xp), Arg::R(wp), bias, Arg::W(y)], tiles)
}

/// Tiled `y = conv(x, w) + b` (any stride and padding), with taps folded into channels
/// where that fills the channel quads better (few input channels).
pub(crate) fn forward(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    y: &Tensor,
) -> Result<()> {
    let f = fold(g, 4);
    let cpad = f.g.ci.div_ceil(4) * 4;
    let xp = pack_folded(gpu, pass, g, &f, x, cpad)?;
    let wp = pack_weights(gpu, pass, &f.g, w, cpad, false, f.fold())?;
    forward_packed(gpu, pass, &f.g, &xp, &wp, cpad, b, y)
}

/// Whether [`backward_input`] handles `g`: padding before of at most `k - 1` on every axis
/// (so the flipped conv's padding `k - 1 - pad` is not negative).
pub(crate) fn supports_backward_input(g: &Geometry) -> bool {
    (0..3).all(|a| g.pad[a] < g.kernel[a])
}

/// Tiled `dx = conv^T(dy, w) (+ b)`: the stride-1 forward conv of `dy` dilated by the stride,
/// with the kernel flipped and its channel axes swapped, padded `k - 1 - pad` before.
pub(crate) fn backward_input(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    dy: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    dx: &Tensor,
) -> Result<()> {
    let t = Geometry {
        ci: g.co,
        co: g.ci,
        input: [0, 1, 2].map(|a| (g.output[a] - 1) * g.stride[a] + 1),
        output: g.input,
        stride: [1; 3],
        pad: [0, 1, 2].map(|a| g.kernel[a] - 1 - g.pad[a]),
        ..*g
    };
    let cpad = t.ci.div_ceil(4) * 4;
    let dyp = pack_input(gpu, pass, dy, t.n, t.ci, g.output, t.input, g.stride, cpad)?;
    let wp = pack_weights(gpu, pass, &t, w, cpad, true, 1)?;
    forward_packed(gpu, pass, &t, &dyp, &wp, cpad, b, dx)
}

/// Tiled `dw[co, ci, k] = Σ dy[n, co, o] x[n, ci, o*s - pad + k]`: partial sums per chunk of
/// output rows, then a fixed-order sum over chunks (deterministic, no atomics).
pub(crate) fn backward_weight(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    dy: &Tensor,
    dw: &Tensor,
) -> Result<()> {
    let f = fold(g, 8);
    let (cpad, copad) = (f.g.ci.div_ceil(8) * 8, g.co.div_ceil(16) * 16);
    let xp = pack_folded(gpu, pass, g, &f, x, cpad)?;
    let g = &f.g;
    let dyp = pack_input(gpu, pass, dy, g.n, g.co, g.output, g.output, [1; 3], copad)?;
    let taps = volume(g.kernel);
    let columns = taps * (cpad / 8) * (copad / 16);
    // Chunks of output rows (n, od, oh): enough for ~1024 invocations (lavapipe spreads
    // workgroups over its threads), and about 1024 positions or fewer each so the operands a
    // workgroup streams stay in cache (2x on the 512->256 projection's weight gradient),
    // never more chunks than there are rows.
    let rows = g.n * g.output[0] * g.output[1];
    let nchunks = 1024usize.div_ceil(columns).max((rows * g.output[2]).div_ceil(1024)).clamp(1, rows);
    let chunk = rows.div_ceil(nchunks);
    let nchunks = rows.div_ceil(chunk);
    let part = Tensor::zeros(gpu, &[nchunks, taps, cpad, copad])?;
    let p = Params { nchunks: nchunks as u32, chunk: chunk as u32, fold: f.fold() as u32, ..params(g, cpad) };
    dispatch(gpu, pass, "conv_fast_backward_weight", p, &[Arg::R(&xp), Arg::R(&dyp), Arg::W(&part)], nchunks * columns)?;
    dispatch(gpu, pass, "conv_fast_weight_sum", p, &[Arg::R(&part), Arg::W(dw)], dw.numel())
}
