//! A run's stale weight packings in one dispatch (`conv_fast_pack_weights_jobs` in
//! `shaders/conv_tex_pack.wgsl`). Inside a graph run that keeps its packings
//! (`gpu/constant.rs`), a texture packing whose weights changed since it was packed (every one
//! in a training step, whose Adam update changes them all) is not packed by its conv: the conv
//! defers it here, and before the run is submitted [`prologue`] records one dispatch that
//! packs every deferred packing into a staging buffer, then copies each into its texture,
//! in a command buffer the submit runs first. A training step of the tiny network made 27
//! weight-packing dispatches, at ~40-90 us each on lavapipe whatever their size.
//!
//! The dispatch is a plain gather: a map made on the CPU when the set of packings changes
//! (the same layout as `weight_index` / `weight_texel` in the shaders) gives each packed
//! float's parameter index, and the parameters are copied into a texture first. On lavapipe
//! a per-lane texel load costs a tenth of a storage-buffer load, and a per-packing parameter
//! block read at the workgroup's row was loaded lane by lane: that first version of this
//! dispatch took ~1.5 ms of a ~22 ms training step on an AMD Zen 5, the 27 dispatches it
//! replaced ~1.5-2 ms.

use super::conv::Params;
use super::conv_fast::TEX_SHADER;
use crate::error::Result;
use crate::gpu::{Arg, Deferred, Gpu, PrologueBuffers, Tensor, grid_1d};

/// Texels a row of the map and parameter textures (the shader's `JOB_TEX_W`; a power of two,
/// so the shader shifts and masks where a division by a row width took per-lane divides).
const TEX_WIDTH: usize = 4096;
/// The map holds parameter indices as f32: exact below 2^24.
const MAX_INDEX: usize = 1 << 24;

/// Defers packing `w` for the parameters `p` into `view` (`width` x `height` texels, the
/// weight texture's layout) to the run's prologue; false outside a run that keeps packings,
/// where the parameters are too many for the map's f32 indices or the device's textures, or
/// where the run's packings would outgrow one staging binding or the map texture.
pub(super) fn defer(gpu: &Gpu, mut p: Params, w: &Tensor, view: &wgpu::TextureView, [width, height]: [usize; 2]) -> bool {
    let rows = gpu.limits.max_texture_dimension_2d as usize;
    let params = (w.buffer().size() / 4) as usize;
    if params > MAX_INDEX || TEX_WIDTH > rows || (params / 4).div_ceil(TEX_WIDTH) > rows {
        return false;
    }
    let max_texels = (TEX_WIDTH * rows).min(gpu.limits.max_storage_buffer_binding_size as usize / 16);
    p.total = (width * height) as u32;
    let mut job: Vec<u32> = bytemuck::cast_slice(bytemuck::bytes_of(&p)).to_vec();
    job.push((w.offset() / 4) as u32);
    gpu.defer_packing(Deferred { job, view: view.clone(), size: [width as u32, height as u32] }, max_texels)
}

/// Size of a texture holding `texels` texels, `TEX_WIDTH` a row.
fn tex_size(texels: usize) -> [usize; 3] {
    [TEX_WIDTH, texels.div_ceil(TEX_WIDTH), 1]
}

/// Records the active recording's deferred packings (see the module note) into a command
/// buffer to submit ahead of the run, or `None` if it deferred none.
pub(crate) fn prologue(gpu: &Gpu) -> Result<Option<wgpu::CommandBuffer>> {
    let (deferred, kept) = gpu.take_deferred();
    let Some((jobs, params)) = deferred else {
        gpu.keep_prologue_buffers(kept);
        return Ok(None);
    };
    let words: Vec<u32> = jobs.iter().flat_map(|d| d.job.iter().copied()).collect();
    let total: usize = jobs.iter().map(|d| (d.size[0] * d.size[1]) as usize).sum();
    let src_size = tex_size((params.size() / 16) as usize);
    let batch = match kept {
        Some(b) if b.jobs == words && b.src_size == src_size => b,
        _ => {
            let map_size = tex_size(total);
            let b = PrologueBuffers {
                jobs: words,
                staging: Tensor::zeros(gpu, &[total * 4])?,
                map: gpu.new_rgba32f_texture(map_size, wgpu::TextureDimension::D2),
                src: gpu.new_rgba32f_texture(src_size, wgpu::TextureDimension::D2),
                src_size,
            };
            let mut map = gather_map(&jobs);
            map.resize(map_size[0] * map_size[1] * 4, -1.0);
            write_rows(gpu, &b.map, &map, map_size);
            b
        }
    };
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    copy_params(&mut enc, &params, &batch.src, src_size);
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        let p = Params { total: total as u32, ..Default::default() };
        let d2 = wgpu::TextureViewDimension::D2;
        let args = [Arg::ReadStorageTexture(&batch.map, d2), Arg::ReadStorageTexture(&batch.src, d2), Arg::W(&batch.staging)];
        gpu.dispatch(&mut pass, TEX_SHADER, "conv_fast_pack_weights_jobs", &p, &args, grid_1d(total as u64, 64)?)?;
    }
    let mut offset = 0u64;
    for d in &jobs {
        // A weight texture's width is a multiple of 16 texels (co16 * 16): whole 256-byte rows.
        let [width, height] = d.size;
        enc.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: batch.staging.buffer(),
                layout: wgpu::TexelCopyBufferLayout { offset, bytes_per_row: Some(width * 16), rows_per_image: Some(height) },
            },
            d.view.texture().as_image_copy(),
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        offset += u64::from(width * height) * 16;
    }
    gpu.keep_prologue_buffers(Some(batch));
    Ok(Some(enc.finish()))
}

/// For every texel of every job in turn, the parameter index of each of its four floats
/// (-1: zero), as f32.
fn gather_map(jobs: &[Deferred]) -> Vec<f32> {
    let pw = std::mem::size_of::<Params>() / 4;
    let mut map = Vec::new();
    for d in jobs {
        let q: Params = bytemuck::pod_read_unaligned(bytemuck::cast_slice(&d.job[..pw]));
        let woff = d.job[pw] as usize;
        for i in 0..q.total {
            let (tap, c, o) = weight_texel(&q, i);
            map.extend((0..4).map(|k| weight_index(&q, tap, c, o + k).map_or(-1.0, |s| (woff + s) as f32)));
        }
    }
    map
}

/// Tap, input channel and first of the 4 output channels of weight texel `i` (the shader's
/// `weight_texel`, conv_tex_pack.wgsl).
fn weight_texel(q: &Params, i: u32) -> (u32, u32, u32) {
    let (width, cq) = (q.co16 * 16, q.cpad / 4);
    let (x, y) = (i % width, i / width);
    (y / cq, 4 * (y % cq) + (x % 16) / 4, (x / 16) * 16 + (x % 4) * 4)
}

/// Source index of the packed weight at (tap, c, o), `None` where it is zero (the shader's
/// `weight_index`, conv_fast.wgsl).
fn weight_index(q: &Params, tap: u32, c: u32, o: u32) -> Option<usize> {
    let taps = q.kd * q.kh * q.kw;
    if o >= q.co || c >= q.ci {
        return None;
    }
    if q.flip == 0 {
        let f = q.fold.max(1);
        return Some(((o * (q.ci / f) + c / f) * taps * f + tap * f + c % f) as usize);
    }
    let kd = q.pd + (q.kd - 1 - tap / (q.kh * q.kw)) * q.sd;
    let kh = q.ph + (q.kh - 1 - (tap / q.kw) % q.kh) * q.sh;
    let kw = q.pw + (q.kw - 1 - tap % q.kw) * q.sw;
    (kd < q.id && kh < q.ih && kw < q.iw).then(|| ((c * q.co + o) * q.id * q.ih * q.iw + (kd * q.ih + kh) * q.iw + kw) as usize)
}

/// Writes `data` (whole rows of `size[0]` texels) into the texture of `view`.
fn write_rows(gpu: &Gpu, view: &wgpu::TextureView, data: &[f32], size: [usize; 3]) {
    gpu.queue.write_texture(
        view.texture().as_image_copy(),
        bytemuck::cast_slice(data),
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(size[0] as u32 * 16), rows_per_image: None },
        wgpu::Extent3d { width: size[0] as u32, height: size[1] as u32, depth_or_array_layers: 1 },
    );
}

/// Copies the parameter buffer `src` into the texture `dst` of `size`, `TEX_WIDTH` texels a
/// row: the whole rows, then the rest of the last.
fn copy_params(enc: &mut wgpu::CommandEncoder, src: &wgpu::Buffer, dst: &wgpu::TextureView, size: [usize; 3]) {
    let texels = (src.size() / 16) as u32;
    let w = size[0] as u32;
    let (rows, rest) = (texels / w, texels % w);
    for (y, width, height) in [(0, w, rows), (rows, rest, 1)] {
        if width == 0 || height == 0 {
            continue;
        }
        enc.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo { buffer: src, layout: wgpu::TexelCopyBufferLayout { offset: u64::from(y * w) * 16, bytes_per_row: Some(w * 16), rows_per_image: None } },
            wgpu::TexelCopyTextureInfo { texture: dst.texture(), mip_level: 0, origin: wgpu::Origin3d { x: 0, y, z: 0 }, aspect: wgpu::TextureAspect::All },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Packing parameters of a [co][ci][3][3][3] weight (dispatch sizes `k`, steps, starts).
    fn params(co: u32, ci: u32, k: [u32; 3], flip: u32, step: [u32; 3], start: [u32; 3]) -> Params {
        let [kd, kh, kw] = k;
        let ([sd, sh, sw], [pd, ph, pw]) = (step, start);
        Params { co, ci, kd, kh, kw, id: 3, ih: 3, iw: 3, flip, sd, sh, sw, pd, ph, pw, cpad: ci.div_ceil(4) * 4, co16: co.div_ceil(16), fold: 1, ..Default::default() }
    }

    #[test]
    fn packed_weights_map_to_their_source_or_to_zero() {
        // Forward: [co][ci][taps] in order; channels past the real ones are zero.
        let q = params(5, 2, [3, 3, 3], 0, [1; 3], [0; 3]);
        assert_eq!(weight_index(&q, 4, 1, 3), Some((3 * 2 + 1) * 27 + 4));
        assert_eq!(weight_index(&q, 4, 2, 3), None, "input channel past ci");
        assert_eq!(weight_index(&q, 4, 1, 5), None, "output channel past co");
        // Backward input, one phase of a stride-2 kernel: 2 taps an axis from tap 1 on with
        // step 2, flipped (dispatch tap t is source tap 1 + (1 - t) * 2): tap 0 is source tap
        // 3, past the 3-tap kernel's edge, so zero; tap 1 of each axis is source tap 1. The
        // source is the forward conv's [ci][co][taps] (here ci = 5 of the backward = co above).
        let q = params(2, 5, [2, 2, 2], 1, [2; 3], [1; 3]);
        assert_eq!(weight_index(&q, 0, 3, 1), None, "past the kernel's edge");
        assert_eq!(weight_index(&q, 7, 3, 1), Some((3 * 2 + 1) * 27 + 13));
        assert_eq!(weight_index(&q, 6, 3, 1), None, "W tap 0 is past the edge");
    }

    #[test]
    fn weight_texels_hold_four_output_channels_of_one_input_channel_and_tap() {
        // 16 output channels a 16-texel group; texel x: input channel 4q + (x % 16) / 4,
        // output channels (x / 16) * 16 + (x % 4) * 4 + 0..3; row y: tap y / cq, quad y % cq.
        let q = params(20, 6, [3, 3, 3], 0, [1; 3], [0; 3]);
        let width = q.co16 * 16;
        assert_eq!(weight_texel(&q, 0), (0, 0, 0));
        assert_eq!(weight_texel(&q, 16 + 6), (0, 1, 16 + 8));
        assert_eq!(weight_texel(&q, 3 * width + 13), (1, 4 + 3, 4));
    }
}
