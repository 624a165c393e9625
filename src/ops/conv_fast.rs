//! The tiled conv kernels of `shaders/conv_fast.wgsl` (see its header for the tiling and why
//! it suits lavapipe), behind `conv::dispatch_*`, in two families chosen by [`Operands`]:
//! storage buffers, or textures shared across a subgroup. Each call repacks its operands
//! (channels-last buffers or rgba32f textures, `conv_pack`) first, so callers keep PyTorch
//! layouts.

use super::conv::{Geometry, Params};
use crate::error::{Error, Result};
use super::conv_pack::{Packed, pack_w, pack_x, stage_x};
pub(crate) use super::conv_fast_weight::backward_weight;
use super::conv_fast_weight::{backward_weight_tex, weight_textures};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};
pub(crate) use super::conv_operands::{Operands, calibrated};

const SHADER: Shader = wgsl!("conv_fast");
/// The texture family: `conv_tex.wgsl` (forward tiles), `conv_tex_pack.wgsl` (the packings
/// into its textures) and `conv_tex_weight.wgsl` (weight-gradient tiles) use
/// `conv_fast.wgsl`'s parameters and helpers, `conv_direct.wgsl` (the direct kernels of convs
/// with few input channels, on x in its stage texture) those files', and
/// `conv_direct_weight.wgsl` (their weight gradients, and the heads') all five.
pub(super) const TEX_SHADER: Shader = wgsl!("conv_tex": "conv_fast", "conv_tex", "conv_tex_pack", "conv_tex_weight", "conv_direct", "conv_direct_weight");

/// The tiled kernels' parameters for dispatch geometry `g` with `cpad` packed channels.
pub(super) fn params(g: &Geometry, cpad: usize) -> Params {
    let p = g.params();
    Params {
        cpad: cpad as u32,
        co16: g.co.div_ceil(16) as u32,
        fold: 1,
        // Dense output layout.
        ycs: p.od * p.oh * p.ow,
        ysd: p.oh * p.ow,
        ysh: p.ow,
        ysw: 1,
        ..p
    }
}

pub(super) fn dispatch(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, entry: &'static str, mut p: Params, args: &[Arg], total: usize) -> Result<()> {
    p.total = total as u32;
    let shader = if entry.ends_with("_tex") { TEX_SHADER } else { SHADER };
    gpu.dispatch(pass, shader, entry, &p, args, grid_1d(total as u64, 64)?)
}

/// A conv with its innermost kernel axes folded into the input channels (see
/// `conv_fast_pack_folded`): the geometry the kernels run, and the fold sizes along H and W.
pub(super) struct Folded {
    pub(super) g: Geometry,
    pub(super) fh: usize,
    pub(super) fw: usize,
}

impl Folded {
    /// `g` with nothing folded.
    pub(super) fn none(g: Geometry) -> Folded {
        Folded { g, fh: 1, fw: 1 }
    }

    /// Taps per folded channel group.
    pub(super) fn fold(&self) -> usize {
        self.fh * self.fw
    }
}

/// The fold of `g`'s W taps, or H and W taps, or none: whichever needs the fewest (tap,
/// channel group) iterations with channels padded to a multiple of `quantum` (4 for the
/// forward tile, 8 for the weight-gradient tile), the smaller fold on a tie. Only convs with
/// few input channels gain; the others keep `fh = fw = 1`.
pub(super) fn fold(g: &Geometry, quantum: usize) -> Folded {
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

pub(super) fn volume(s: [usize; 3]) -> usize {
    s.iter().product()
}

/// Whether `ops` asks for textures and the device can run the texture kernels.
pub(super) fn textures_wanted(gpu: &Gpu, ops: Operands) -> bool {
    ops == Operands::Textures && gpu.has_subgroups_of_8() && gpu.reads_rgba32f_storage()
}

/// Whether `n` items of `cpad` packed channels over `input` fit one 3D texture (`pack_x`).
pub(super) fn x_texture_fits(gpu: &Gpu, n: usize, cpad: usize, [id, ih, iw]: [usize; 3]) -> bool {
    iw.max(ih).max(n * cpad / 4 * id) <= gpu.limits.max_texture_dimension_3d as usize
}

/// Whether the packed weights of dispatch geometry `g` fit one 2D texture (`pack_w`).
fn w_texture_fits(gpu: &Gpu, g: &Geometry, cpad: usize) -> bool {
    (g.co.div_ceil(16) * 16).max(volume(g.kernel) * cpad / 4) <= gpu.limits.max_texture_dimension_2d as usize
}

/// Whether a forward-style conv of dispatch geometry `g` (`cpad` packed input channels) runs
/// on textures for `ops`.
fn textures_fit(gpu: &Gpu, ops: Operands, g: &Geometry, cpad: usize) -> bool {
    textures_wanted(gpu, ops) && x_texture_fits(gpu, g.n, cpad, g.input) && w_texture_fits(gpu, g, cpad)
}

/// Whether the conv `g` runs the direct texture kernels for `ops`: a conv the texture family
/// would fold (few input channels), whose staged input (`stage_x`) and unfolded packed
/// weights fit the device's textures.
pub(super) fn direct_fits(gpu: &Gpu, ops: Operands, g: &Geometry, f: &Folded) -> bool {
    f.fold() > 1 && textures_fit(gpu, ops, g, g.ci.div_ceil(4) * 4) && x_texture_fits(gpu, g.n, 4 * g.ci, g.input)
}

/// The tiled forward with parameters `p` (of the dispatch geometry, output layout included)
/// on packed operands: per invocation 8 outputs along W x 16 output channels (buffers), or
/// per subgroup of 8 lanes 8 outputs along W x 8 rows x 16 output channels (textures; 4 or 8
/// channels when there are no more; 32 outputs along W x 4 rows where [`cols4`] holds).
#[allow(clippy::too_many_arguments)]
fn forward_packed(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    p: Params,
    xp: &Packed,
    wp: &Packed,
    b: Option<&Tensor>,
    alpha: Option<&Tensor>,
    y: &Tensor,
) -> Result<()> {
    let p = Params { has_bias: b.is_some() as u32, ..p };
    let bias = b.map_or(Arg::Absent, Arg::R);
    let args = [xp.arg(), wp.arg(), bias, Arg::W(y), alpha.map_or(Arg::Absent, Arg::R)];
    if let Packed::Texture(..) = xp {
        if cols4(&p) {
            let tiles = (p.n * p.co16 * p.od * p.oh.div_ceil(4) * p.ow.div_ceil(32)) as usize;
            let p = Params { total: tiles as u32, ..p };
            let entry = if alpha.is_some() { "conv_fast_forward_tex_w4_prelu" } else { "conv_fast_forward_tex_w4" };
            return gpu.dispatch(pass, TEX_SHADER, entry, &p, &args, grid_1d(tiles as u64 * 8, 64)?);
        }
        let tiles = (p.n * p.co16 * p.od * p.oh.div_ceil(8) * p.ow.div_ceil(8)) as usize;
        let p = Params { total: tiles as u32, ..p };
        // At most 4 or 8 output channels: the 4- or 8-channel tile (co16 = 1, so the same
        // tile count); with 4 and 3 tap rows at row stride 1 (the 3x3 heads), `_rows3`
        // fetches each input row once for all three tap rows.
        // Each with a `_prelu` twin that applies the slopes `alpha` to what it writes.
        let entry = match (p.co, alpha.is_some()) {
            (..=4, false) if p.kh == 3 && p.sh == 1 => "conv_fast_forward_tex4_rows3",
            (..=4, true) if p.kh == 3 && p.sh == 1 => "conv_fast_forward_tex4_rows3_prelu",
            (..=4, false) => "conv_fast_forward_tex4",
            (..=4, true) => "conv_fast_forward_tex4_prelu",
            (5..=8, false) => "conv_fast_forward_tex8",
            (5..=8, true) => "conv_fast_forward_tex8_prelu",
            (_, false) => "conv_fast_forward_tex",
            (_, true) => "conv_fast_forward_tex_prelu",
        };
        return gpu.dispatch(pass, TEX_SHADER, entry, &p, &args, grid_1d(tiles as u64 * 8, 64)?);
    }
    if alpha.is_some() {
        return Err(Error::Invalid("internal: a PReLU fused into a conv needs the texture kernels (see conv_fast::fuses_prelu)".into()));
    }
    let tiles = (p.n * p.co16 * p.od * p.oh * p.ow.div_ceil(8)) as usize;
    dispatch(gpu, pass, "conv_fast_forward", p, &args[..4], tiles)
}

/// Whether the texture forward of `p` runs `conv_fast_forward_tex_w4` (a lane 4 columns x 4
/// rows x 16 channels, the 3 W taps in one loop step, each channel's 4 columns one vec4
/// store): more than 8 output channels, 3 W taps at column stride 1, and an output layout
/// whose rows hold whole, aligned quads of columns (the shader binds the output as vec4s);
/// and at most an eighth of the row's lanes idle past its end (28-32 columns, 56-64, 84-96,
/// 112-128, ...: at 16 columns half of them did, 1.6x slower than the 8-column tile).
fn cols4(p: &Params) -> bool {
    let whole = [p.ow, p.ycs, p.ysd, p.ysh, p.yoff].iter().all(|v| v % 4 == 0);
    p.co > 8 && p.kw == 3 && p.sw == 1 && p.ysw == 1 && whole && 8 * p.ow >= 7 * p.ow.div_ceil(32) * 32
}

/// Tiled `y = conv(x, w) + b` (any stride and padding), with taps folded into channels
/// where that fills the channel quads better (few input channels).
#[allow(clippy::too_many_arguments)]
pub(crate) fn forward(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    y: &Tensor,
    ops: Operands,
) -> Result<()> {
    forward_act(gpu, pass, g, x, w, b, None, y, ops)
}

/// Which kernels [`forward_act`] runs for `g` on `ops`, with `g`'s fold.
#[derive(PartialEq)]
enum ForwardPath {
    /// `conv_direct_forward*` on the staged input (a conv the texture family would fold).
    Direct,
    /// The unfolded texture tiles.
    Textures,
    /// The buffer tiles, folded or not.
    Buffers,
}

fn forward_path(gpu: &Gpu, g: &Geometry, ops: Operands) -> (ForwardPath, Folded) {
    let f = fold(g, 4);
    let path = if direct_fits(gpu, ops, g, &f) {
        ForwardPath::Direct
    } else if textures_fit(gpu, ops, &f.g, f.g.ci.div_ceil(4) * 4) && f.fold() == 1 {
        // A fold on textures runs the direct kernels or nothing: the texture packing never folds.
        ForwardPath::Textures
    } else {
        ForwardPath::Buffers
    };
    (path, f)
}

/// Whether [`forward_act`] can apply a PReLU to `g`'s output for `ops`: its forward runs the
/// texture kernels (the direct ones or the unfolded tiles), whose every forward entry point
/// has a `_prelu` twin.
pub(crate) fn fuses_prelu(gpu: &Gpu, g: &Geometry, ops: Operands) -> bool {
    forward_path(gpu, g, ops).0 != ForwardPath::Buffers
}

/// [`forward`] followed by PReLU with slopes `alpha` (`[Cout]`, one per output channel) in
/// the same dispatch, where [`fuses_prelu`] says the texture kernels run it; an error elsewhere.
#[allow(clippy::too_many_arguments)]
pub(crate) fn forward_act(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    alpha: Option<&Tensor>,
    y: &Tensor,
    ops: Operands,
) -> Result<()> {
    let (path, f) = forward_path(gpu, g, ops);
    if path == ForwardPath::Direct {
        return forward_direct(gpu, pass, g, x, w, b, alpha, y);
    }
    let (cpad, tex) = (f.g.ci.div_ceil(4) * 4, path == ForwardPath::Textures);
    let xp = pack_x(gpu, pass, g, &f, x, cpad, tex)?;
    let p = params(&f.g, cpad);
    let wp = pack_w(gpu, pass, Params { fold: f.fold() as u32, ..p }, w, tex)?;
    forward_packed(gpu, pass, p, &xp, &wp, b, alpha, y)
}

/// `forward` of a conv the texture family would fold (few input channels) without folding:
/// the input staged four voxels along W a texel, read in place by `conv_direct_forward`.
#[allow(clippy::too_many_arguments)]
fn forward_direct(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    alpha: Option<&Tensor>,
    y: &Tensor,
) -> Result<()> {
    let cpad = g.ci.div_ceil(4) * 4;
    let p = params(g, cpad);
    let stage = stage_x(gpu, pass, g, x, &p)?;
    let wp = pack_w(gpu, pass, p, w, true)?;
    let tiles = g.n * g.co.div_ceil(8) * volume([g.output[0], g.output[1].div_ceil(8), g.output[2].div_ceil(8)]);
    let p = Params { has_bias: b.is_some() as u32, total: tiles as u32, ..p };
    let args = [
        Arg::ReadStorageTexture(&stage, wgpu::TextureViewDimension::D3),
        wp.arg(),
        b.map_or(Arg::Absent, Arg::R),
        Arg::W(y),
        alpha.map_or(Arg::Absent, Arg::R),
    ];
    // A 5 x 5 kernel at row stride 2 (the first layer): each input row fetched once.
    let entry = match (g.kernel[1] == 5 && g.kernel[2] == 5 && g.stride[1] == 2, alpha.is_some()) {
        (true, false) => "conv_direct_forward_k5s2",
        (true, true) => "conv_direct_forward_k5s2_prelu",
        (false, false) => "conv_direct_forward",
        (false, true) => "conv_direct_forward_prelu",
    };
    gpu.dispatch(pass, TEX_SHADER, entry, &p, &args, grid_1d(tiles as u64 * 8, 64)?)
}

/// One output phase `r` of a backward-input conv along one axis (see the shader header):
/// dx positions `r + s*m` for `m < len` read dy through the sub-kernel of `taps` taps from
/// `k0` (step s; at least one tap, weights zero past the kernel) at padding `pad`.
struct StridePhase {
    len: usize,
    k0: usize,
    taps: usize,
    pad: i64,
}

/// Phase `r` on an axis with dx length `input`, kernel `k`, stride `s`, padding before `pad`.
fn stride_phase(r: usize, input: usize, k: usize, s: usize, pad: usize) -> StridePhase {
    let k0 = (r + pad) % s;
    let taps = k.saturating_sub(k0).div_ceil(s).max(1);
    let len = input.saturating_sub(r).div_ceil(s);
    StridePhase { len, k0, taps, pad: taps as i64 - 1 - ((r + pad) / s) as i64 }
}

/// Tiled `dx = conv^T(dy, w) (+ b)`: per output phase (one at stride 1), a stride-1 forward
/// conv of the packed dy with that phase's flipped, channel-swapped sub-kernel, writing every
/// stride-th dx value.
#[allow(clippy::too_many_arguments)]
pub(crate) fn backward_input(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    dy: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    dx: &Tensor,
    ops: Operands,
) -> Result<()> {
    backward_input_act(gpu, pass, g, dy, w, b, None, dx, ops)
}

/// [`backward_input`] followed by PReLU with slopes `alpha` (`[Cin]`) in the same dispatches:
/// a transposed conv's forward then its activation, where [`transposed_fuses_prelu`] holds.
#[allow(clippy::too_many_arguments)]
pub(crate) fn backward_input_act(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    dy: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    alpha: Option<&Tensor>,
    dx: &Tensor,
    ops: Operands,
) -> Result<()> {
    let (whole, cpad, tex) = dy_packing(gpu, g, ops);
    let dyp = pack_x(gpu, pass, &whole, &Folded::none(whole), dy, cpad, tex)?;
    backward_input_packed(gpu, pass, g, &dyp, w, b, alpha, dx, cpad, tex)
}

/// Whether [`backward_input_act`] can apply a PReLU to `g`'s input gradient (a transposed
/// conv's output) for `ops`: every phase then runs the texture tiles, which have `_prelu` twins.
pub(crate) fn transposed_fuses_prelu(gpu: &Gpu, g: &Geometry, ops: Operands) -> bool {
    let (_, _, tex) = dy_packing(gpu, g, ops);
    tex && !input_k5s2(gpu, g)
}

/// How `backward_input` packs dy: the dispatch geometry (dy as the input, at most the whole
/// kernel), its packed channels and whether on textures.
fn dy_packing(gpu: &Gpu, g: &Geometry, ops: Operands) -> (Geometry, usize, bool) {
    let cpad = g.co.div_ceil(4) * 4;
    let whole = Geometry { ci: g.co, co: g.ci, input: g.output, output: g.input, stride: [1; 3], pad: [0; 3], ..*g };
    (whole, cpad, textures_fit(gpu, ops, &whole, cpad))
}

/// Both gradients of one conv, `dx = conv^T(dy, w)` and `dw`, packing dy once where the two
/// would pack it alike (on textures, with at most 8 or a multiple of 16 output channels: the
/// 16-channel convs, the first layer and the heads of the RenderNet presets): one dispatch and
/// one pass over dy fewer than [`backward_input`] then [`backward_weight`], which it equals
/// exactly.
#[allow(clippy::too_many_arguments)]
pub(crate) fn backward(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    dy: &Tensor,
    w: &Tensor,
    dx: &Tensor,
    dw: &Tensor,
    ops: Operands,
) -> Result<()> {
    let (whole, cpad, tex) = dy_packing(gpu, g, ops);
    let wt = weight_textures(gpu, g, ops);
    if !(tex && wt.as_ref().is_some_and(|&(_, _, dy_cpad)| dy_cpad == cpad)) {
        backward_input(gpu, pass, g, dy, w, None, dx, ops)?;
        return backward_weight(gpu, pass, g, x, dy, dw, ops);
    }
    let dyp = pack_x(gpu, pass, &whole, &Folded::none(whole), dy, cpad, tex)?;
    backward_input_packed(gpu, pass, g, &dyp, w, None, None, dx, cpad, tex)?;
    let (f, xcpad, _) = wt.expect("checked");
    backward_weight_tex(gpu, pass, g, &f, x, &dyp, dw, xcpad)
}

/// [`backward_input`] on dy packed by [`dy_packing`]'s rule.
#[allow(clippy::too_many_arguments)]
fn backward_input_packed(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    dyp: &Packed,
    w: &Tensor,
    b: Option<&Tensor>,
    alpha: Option<&Tensor>,
    dx: &Tensor,
    cpad: usize,
    tex: bool,
) -> Result<()> {
    if tex && input_k5s2(gpu, g) {
        if alpha.is_some() {
            return Err(Error::Invalid("internal: the 1-channel 5^3 input gradient applies no PReLU (see transposed_fuses_prelu)".into()));
        }
        return backward_input_k5s2(gpu, pass, g, dyp, w, b, dx, cpad);
    }
    for (pack, p) in phases(g, cpad) {
        let wp = pack_w(gpu, pass, pack, w, tex)?;
        forward_packed(gpu, pass, p, dyp, &wp, b, alpha, dx)?;
    }
    Ok(())
}

/// The stride-1 convs of `g`'s input gradient on dy packed with `cpad` channels, one per output
/// phase that has positions: the weight packing's parameters (that phase's flipped,
/// channel-swapped sub-kernel) and the conv's, whose output layout writes every stride-th dx value.
fn phases(g: &Geometry, cpad: usize) -> Vec<(Params, Params)> {
    let [_, fh, fw] = g.input;
    let [sd, sh, sw] = g.stride;
    let mut out = Vec::new();
    for i in 0..volume(g.stride) {
        let r = [i / (sh * sw), (i / sw) % sh, i % sw];
        let ph = [0, 1, 2].map(|a| stride_phase(r[a], g.input[a], g.kernel[a], g.stride[a], g.pad[a]));
        if ph.iter().any(|q| q.len == 0) {
            continue;
        }
        let t = Geometry {
            ci: g.co,
            co: g.ci,
            input: g.output,
            output: ph.each_ref().map(|q| q.len),
            kernel: ph.each_ref().map(|q| q.taps),
            stride: [1; 3],
            pad: [0; 3],
            ..*g
        };
        let base = params(&t, cpad);
        let u = |v: usize| v as u32;
        let [id, ih, iw] = g.kernel.map(u);
        let [pd, ph_, pw] = ph.each_ref().map(|q| u(q.k0));
        let step = g.stride.map(u);
        let pack = Params { flip: 1, id, ih, iw, sd: step[0], sh: step[1], sw: step[2], pd, ph: ph_, pw, ..base };
        // Negative pads travel as two's complement; the shader reads them back with i32().
        let [pd, ph_, pw] = ph.each_ref().map(|q| q.pad as i32 as u32);
        let p = Params {
            pd,
            ph: ph_,
            pw,
            ycs: u(volume(g.input)),
            ysd: u(sd * fh * fw),
            ysh: u(sh * fw),
            ysw: u(sw),
            yoff: u((r[0] * fh + r[1]) * fw + r[2]),
            ..base
        };
        out.push((pack, p));
    }
    out
}

/// Whether [`backward_input_k5s2`] runs `g`'s input gradient: one input channel, a 5^3
/// kernel at stride 2 (the first layer), its forward weight texture within the device's limits.
fn input_k5s2(gpu: &Gpu, g: &Geometry) -> bool {
    g.ci == 1 && g.rank == 5 && g.kernel == [5; 3] && g.stride == [2; 3] && w_texture_fits(gpu, g, 4)
}

/// `dx = conv^T(dy, w) (+ b)` of a 1-channel conv with a 5^3 kernel at stride 2, every phase
/// in one dispatch (`conv_direct_backward_input_k5s2`), on dy packed by [`dy_packing`] and the
/// forward's weight texture.
#[allow(clippy::too_many_arguments)]
fn backward_input_k5s2(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    dyp: &Packed,
    w: &Tensor,
    b: Option<&Tensor>,
    dx: &Tensor,
    cpad: usize,
) -> Result<()> {
    let wp = pack_w(gpu, pass, params(g, 4), w, true)?;
    let t = Geometry { ci: g.co, co: g.ci, input: g.output, output: g.input, ..*g };
    let p = Params { has_bias: b.is_some() as u32, ..params(&t, cpad) };
    let args = [dyp.arg(), wp.arg(), b.map_or(Arg::Absent, Arg::R), Arg::W(dx)];
    // Workgroups: (tiles of 16 columns from x + pw = 2 * (pw / 2), so 15 + pw % 2 past the
    // last, x tiles of 16 rows; 8 depths; items).
    let [depth, rows, cols] = g.input;
    let grid = [((cols + g.pad[2] % 2).div_ceil(16) * rows.div_ceil(16)) as u32, depth.div_ceil(8) as u32, g.n as u32];
    gpu.dispatch(pass, TEX_SHADER, "conv_direct_backward_input_k5s2", &p, &args, grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A conv's geometry: `n` items, `ci` -> `co` channels, input and output sizes, kernel,
    /// stride and padding before.
    #[allow(clippy::too_many_arguments)]
    fn geometry(n: usize, ci: usize, co: usize, input: [usize; 3], output: [usize; 3], kernel: [usize; 3], stride: [usize; 3], pad: [usize; 3]) -> Geometry {
        Geometry { n, ci, co, input, output, kernel, stride, pad, rank: 5 }
    }

    /// `cols4` holds for the shapes of the kernel test `texture_forward_of_four_columns_a_lane`
    /// (kernels-tests/conv/cols4.rs), so that test runs `conv_fast_forward_tex_w4` and a narrower
    /// rule fails here; and not where a lane's vec4 stores or its 3 W taps do not fit.
    #[test]
    fn cols4_runs_the_kernel_tests_shapes() {
        // Unfolded (a fold runs the direct kernels instead), and cols4.
        let fwd = |g: &Geometry| fold(g, 4).fold() == 1 && cols4(&params(g, g.ci.div_ceil(4) * 4));
        let bwd = |g: &Geometry| phases(g, g.co.div_ceil(4) * 4).iter().all(|(_, p)| cols4(p));
        let c20 = geometry(1, 8, 20, [1, 7, 28], [1, 7, 28], [1, 3, 3], [1; 3], [0, 1, 1]);
        let c3d = geometry(1, 16, 12, [3, 5, 32], [3, 5, 32], [3; 3], [1; 3], [1; 3]);
        let s2 = geometry(2, 12, 3, [1, 9, 32], [1, 5, 32], [1, 3, 3], [1, 2, 1], [0, 0, 1]);
        assert!(fwd(&c20) && fwd(&c3d) && bwd(&c3d) && bwd(&s2));
        assert_eq!(phases(&s2, 4).len(), 2, "two row phases");
        // The transposed conv 4 -> 9 is the input gradient of a conv 9 -> 4.
        assert!(bwd(&geometry(1, 9, 4, [1, 5, 60], [1, 5, 60], [1, 3, 3], [1; 3], [0, 1, 1])));
        // Not: 8 output channels, 4 W taps, column stride 2, a width off the quads or too narrow.
        assert!(!fwd(&Geometry { co: 8, ..c20 }));
        assert!(!fwd(&Geometry { kernel: [1, 3, 4], ..c20 }));
        assert!(!fwd(&Geometry { stride: [1, 1, 2], output: [1, 7, 14], ..c20 }));
        assert!(!fwd(&Geometry { output: [1, 7, 30], ..c20 }));
        assert!(!fwd(&Geometry { output: [1, 7, 24], ..c20 }));
        assert!(!fwd(&Geometry { output: [1, 7, 48], ..c20 }), "a quarter of the lanes idle");
        assert!(!fwd(&Geometry { ci: 5, ..c20 }), "5 input channels fold: the direct kernels");
        assert!(!bwd(&geometry(1, 16, 16, [1, 8, 32], [1, 4, 32], [1, 3, 3], [1, 2, 2], [0, 1, 1])), "column phases");
        // A layout whose columns are not adjacent, or whose quads start off a multiple of 4.
        let p = params(&c20, 8);
        assert!(cols4(&p));
        assert!(!cols4(&Params { ysw: 2, ..p }) && !cols4(&Params { yoff: 2, ..p }) && !cols4(&Params { ysh: 30, ..p }));
    }
}

