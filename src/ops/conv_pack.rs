//! Packing the tiled conv kernels' operands (`ops::conv_fast`): the input or dy into a
//! channels-last buffer (folded or not) or an rgba32f texture, the first layer's input into the
//! direct kernels' stage texture, and the weights into a buffer or texture, each through
//! uniform windows where they pay (`conv_window`). A parameter's weight packing is kept from one
//! run of its graph to the next while the parameters do not change (`gpu/constant.rs`).

use super::conv::{Geometry, Params};
use super::conv_fast::{Folded, TEX_SHADER, dispatch, volume, x_texture_fits};
use super::{conv_pack_jobs, conv_window};
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Packing, Tensor, staging_pitch};

/// `t` ([N, c, sp...]) repacked channels-last as [N, sp..., cpad], channels past `c` zero.
pub(super) fn pack_input(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, t: &Tensor, n: usize, c: usize, sp: [usize; 3], cpad: usize) -> Result<Tensor> {
    let out = gpu.scratch(&[n, volume(sp), cpad])?;
    let [od, oh, ow] = sp.map(|v| v as u32);
    let p = Params { n: n as u32, ci: c as u32, od, oh, ow, cpad: cpad as u32, ..Default::default() };
    dispatch(gpu, pass, "conv_fast_pack_input", p, &[Arg::R(t), Arg::W(&out)], n * volume(sp))?;
    Ok(out)
}

/// `x` ([N, C, input...] of the unfolded `g`) packed for the folded conv `f`, channels-last
/// with `cpad` channels (see `conv_fast_pack_folded`); without a fold, a plain packing.
pub(super) fn pack_folded(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, f: &Folded, x: &Tensor, cpad: usize) -> Result<Tensor> {
    if f.fold() == 1 {
        return pack_input(gpu, pass, x, g.n, g.ci, g.input, cpad);
    }
    let out = gpu.scratch(&[g.n, volume(f.g.input), cpad])?;
    let p = folded_params(g, f, cpad);
    dispatch(gpu, pass, "conv_fast_pack_folded", p, &[Arg::R(x), Arg::W(&out)], g.n * volume(f.g.input))?;
    Ok(out)
}

/// Parameters of the folded packings (see `conv_fast_pack_folded`).
fn folded_params(g: &Geometry, f: &Folded, cpad: usize) -> Params {
    let u = |v: usize| v as u32;
    let [id, ih, iw] = g.input.map(u);
    let [od, oh, ow] = f.g.input.map(u);
    // Along an unfolded axis: fold size 1, stride 1, no padding (a copy).
    let (sh, ph) = if f.fh > 1 { (u(g.stride[1]), u(g.pad[1])) } else { (1, 0) };
    let (sw, pw) = if f.fw > 1 { (u(g.stride[2]), u(g.pad[2])) } else { (1, 0) };
    let (kh, kw) = (u(f.fh), u(f.fw));
    Params { n: u(g.n), ci: u(g.ci), id, ih, iw, od, oh, ow, kh, kw, sh, sw, ph, pw, cpad: u(cpad), ..Default::default() }
}

/// Weights repacked as [tap][cpad][co16 * 16] for the packing parameters `p` (those of the
/// dispatch geometry, with `flip` and `fold` or a phase's sub-kernel set: see the shader),
/// into `out`.
fn pack_weights(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, p: Params, w: &Tensor, out: &Tensor) -> Result<()> {
    dispatch(gpu, pass, "conv_fast_pack_weights", p, &[Arg::R(w), Arg::W(out)], out.numel())
}

/// A packed operand: a channels-last buffer or an rgba32f texture.
pub(super) enum Packed {
    Buffer(Tensor),
    Texture(wgpu::TextureView, wgpu::TextureViewDimension),
}

impl Packed {
    pub(super) fn arg(&self) -> Arg<'_> {
        match self {
            Packed::Buffer(t) => Arg::R(t),
            Packed::Texture(v, d) => Arg::ReadStorageTexture(v, *d),
        }
    }
}

/// An rgba32f scratch texture the kernels write as storage and then read (sizes already
/// checked against the device's limits by `x_texture_fits` / `w_texture_fits`).
fn texture(gpu: &Gpu, size: [usize; 3], dim: wgpu::TextureDimension) -> (wgpu::TextureView, wgpu::TextureViewDimension) {
    let view = if dim == wgpu::TextureDimension::D3 { wgpu::TextureViewDimension::D3 } else { wgpu::TextureViewDimension::D2 };
    (gpu.scratch_texture(size, dim), view)
}

/// `x` packed as the texture kernels read it (see `conv_fast_pack_tex`; never folded: a fold
/// runs the direct kernels), or as a buffer (folded by `f`).
pub(super) fn pack_x(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, f: &Folded, x: &Tensor, cpad: usize, tex: bool) -> Result<Packed> {
    if !tex {
        return Ok(Packed::Buffer(pack_folded(gpu, pass, g, f, x, cpad)?));
    }
    debug_assert_eq!(f.fold(), 1, "the texture packing does not fold");
    let [id, ih, iw] = g.input;
    let p = folded_params(g, &Folded::none(*g), cpad);
    let (view, packed) = gpu.operand_texture(x, b'x', bytemuck::bytes_of(&p), [iw, ih, g.n * cpad / 4 * id], wgpu::TextureDimension::D3);
    let dim = wgpu::TextureViewDimension::D3;
    if packed || conv_window::pack_x(gpu, pass, g, x, cpad, &view, dim)? {
        return Ok(Packed::Texture(view, dim));
    }
    // Grids: (h, w) or (h, w / 4) along x, depth along y, (item, channel quad) along z.
    let zq = (g.n * cpad / 4) as u32;
    let (entry, per) = if iw % 4 == 0 { ("conv_fast_pack_tex_w4", 4) } else { ("conv_fast_pack_tex", 1) };
    let grid = [(ih * iw / per).div_ceil(64) as u32, id as u32, zq];
    let buf_entry = if per == 4 { "conv_fast_pack_tex_w4_buf" } else { "conv_fast_pack_tex_buf" };
    write_texels(
        gpu,
        pass,
        &view,
        |pass, staging| gpu.dispatch(pass, TEX_SHADER, buf_entry, &p, &[Arg::R(x), Arg::W(staging)], grid),
        |pass| gpu.dispatch(pass, TEX_SHADER, entry, &p, &[Arg::R(x), Arg::StorageTexture(&view, dim)], grid),
    )?;
    Ok(Packed::Texture(view, dim))
}

/// Whether a packing of `texels` texels copies them in (`write_texels`): where one that large
/// measured faster (`conv_operands::copy_min_texels`: CPU adapters only), in a pass that can
/// be split.
fn copies_in(gpu: &Gpu, pass: &wgpu::ComputePass<'_>, texels: usize) -> bool {
    gpu.can_split(pass) && texels >= super::conv_operands::copy_min_texels(gpu)
}

/// Records a packing into the rgba32f texture `view`: `staged` writing its texels into a
/// staging buffer (in texel order, `staging_pitch` texels a row), which is then copied in,
/// where that pays and can be done: a CPU adapter where copies of that many texels measured
/// faster (on an Intel Xeon a texture store costs ~3x a vec4 buffer store, see
/// `gpu/passes.rs`; each copy splits the pass, which costs the same for any size), a pass
/// that can be split, and the buffer within one storage binding. Else `stores`, writing the
/// texture with texture stores.
pub(super) fn write_texels(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    view: &wgpu::TextureView,
    staged: impl FnOnce(&mut wgpu::ComputePass<'_>, &Tensor) -> Result<()>,
    stores: impl FnOnce(&mut wgpu::ComputePass<'_>) -> Result<()>,
) -> Result<()> {
    let size = view.texture().size();
    let rows = (size.height * size.depth_or_array_layers) as usize;
    let floats = staging_pitch(size.width as usize) * rows * 4;
    let bytes = floats as u64 * 4;
    if !copies_in(gpu, pass, size.width as usize * rows) || bytes > gpu.limits.max_storage_buffer_binding_size || bytes > gpu.limits.max_buffer_size {
        return stores(pass);
    }
    let staging = gpu.scratch(&[floats])?;
    staged(pass, &staging)?;
    gpu.copy_to_texture(pass, &staging, view)
}

/// Whether [`stage_x`] copies `x` into its stage with no dispatch: rows of whole staging rows
/// (width a multiple of 64), where the stage's texels are x's vec4s in order (the first layer on
/// a 64^3 grid, the heads at 64 or 128 wide), on a CPU adapter in a pass that can be split.
/// There this pays whatever `copy_min_texels` says of packings, which store each texel either way:
/// the copy replaces a dispatch, its loads and its stores.
pub(super) fn stage_copies(gpu: &Gpu, pass: &wgpu::ComputePass<'_>, g: &Geometry, x: &Tensor) -> bool {
    let iw = g.input[2];
    let cpu = gpu.info.device_type == wgpu::DeviceType::Cpu;
    iw.is_multiple_of(4) && staging_pitch(iw / 4) == iw / 4 && x.offset().is_multiple_of(16) && cpu && gpu.can_split(pass)
}

/// Whether kernels that can read `x` in its stage should: [`stage_copies`], and the stage fits
/// one 3D texture (the heads' forward and weight gradient, `conv_nchw`, `conv_fast_weight`).
pub(super) fn stage_in_place(gpu: &Gpu, pass: &wgpu::ComputePass<'_>, g: &Geometry, x: &Tensor) -> bool {
    stage_copies(gpu, pass, g, x) && x_texture_fits(gpu, g.n, 4 * g.ci, g.input)
}

/// `x` ([N, C, input...] of `g`) copied into a 3D texture of 4 voxels along W a texel, which
/// the direct kernels read (see `conv_direct.wgsl`); `p` has `g`'s sizes.
pub(super) fn stage_x(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, x: &Tensor, p: &Params) -> Result<wgpu::TextureView> {
    let [id, ih, iw] = g.input;
    let (view, staged) = gpu.operand_texture(x, b's', bytemuck::bytes_of(p), [iw.div_ceil(4), ih, g.n * g.ci * id], wgpu::TextureDimension::D3);
    let dim = wgpu::TextureViewDimension::D3;
    if staged {
        return Ok(view);
    }
    if stage_copies(gpu, pass, g, x) {
        gpu.copy_to_texture(pass, x, &view)?;
        return Ok(view);
    }
    if conv_window::stage_x(gpu, pass, g, x, &view, dim)? {
        return Ok(view);
    }
    let entry = if iw % 4 == 0 { "conv_direct_stage_w4" } else { "conv_direct_stage" };
    let buf_entry = if iw % 4 == 0 { "conv_direct_stage_w4_buf" } else { "conv_direct_stage_buf" };
    let grid = [(iw.div_ceil(4) * ih).div_ceil(64) as u32, id as u32, (g.n * g.ci) as u32];
    write_texels(
        gpu,
        pass,
        &view,
        |pass, staging| gpu.dispatch(pass, TEX_SHADER, buf_entry, p, &[Arg::R(x), Arg::W(staging)], grid),
        |pass| gpu.dispatch(pass, TEX_SHADER, entry, p, &[Arg::R(x), Arg::StorageTexture(&view, dim)], grid),
    )?;
    Ok(view)
}

/// Weights packed for the packing parameters `p` (see `pack_weights`), as a texture or buffer.
/// A parameter's packing is kept from the last run of its graph while the parameters are
/// unchanged, and then not recorded again (`gpu/constant.rs`); a kept texture that is stale
/// is packed ahead of the run with the run's others, in one dispatch (`conv_pack_jobs`).
pub(super) fn pack_w(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, p: Params, w: &Tensor, tex: bool) -> Result<Packed> {
    let taps = (p.kd * p.kh * p.kw) as usize;
    let (width, height) = (p.co16 as usize * 16, taps * p.cpad as usize / 4);
    let size = [width, height, 1];
    let dim = wgpu::TextureDimension::D2;
    let mut key = bytemuck::bytes_of(&p).to_vec();
    key.push(tex as u8);
    let kept = gpu.constant_packing(w, &key, (width * height * 16) as u64, || {
        Ok(if tex { Packing::Texture(gpu.new_rgba32f_texture(size, dim)) } else { Packing::Buffer(Tensor::zeros(gpu, &[taps, p.cpad as usize, width])?) })
    })?;
    let kept_texture = matches!(kept, Some((Packing::Texture(_), _)));
    let (out, valid) = match kept {
        Some((Packing::Texture(v), valid)) => (Packed::Texture(v, wgpu::TextureViewDimension::D2), valid),
        Some((Packing::Buffer(t), valid)) => (Packed::Buffer(t), valid),
        None if tex => (Packed::Texture(texture(gpu, size, dim).0, wgpu::TextureViewDimension::D2), false),
        None => (Packed::Buffer(gpu.scratch(&[taps, p.cpad as usize, width])?), false),
    };
    if valid {
        return Ok(out);
    }
    match &out {
        // A kept texture is packed with the run's others in one dispatch ahead of it.
        Packed::Texture(view, _) if kept_texture && conv_pack_jobs::defer(gpu, p, w, view, [width, height]) => {}
        Packed::Buffer(t) => pack_weights(gpu, pass, p, w, t)?,
        Packed::Texture(view, d) => {
            if !conv_window::pack_w(gpu, pass, p, w, view, *d, width * height)? {
                dispatch(gpu, pass, "conv_fast_pack_weights_tex", p, &[Arg::R(w), Arg::StorageTexture(view, *d)], width * height)?;
            }
        }
    }
    Ok(out)
}
