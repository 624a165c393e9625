//! A run's stale weight packings in one dispatch (`conv_fast_pack_weights_jobs` in
//! `shaders/conv_tex_pack.wgsl`). Inside a graph run that keeps its packings
//! (`gpu/constant.rs`), a texture packing whose weights changed since it was packed (every one
//! in a training step, whose Adam update changes them all) is not packed by its conv: the conv
//! defers it here, and before the run is submitted [`prologue`] records one dispatch that
//! packs every deferred packing into a staging buffer, then copies each into its texture,
//! in a command buffer the submit runs first. A training step of the tiny network made 27
//! weight-packing dispatches, at ~40-90 us each on lavapipe whatever their size, and as
//! many compute-pass splits where a packing copied its texels in.

use super::conv::Params;
use super::conv_fast::TEX_SHADER;
use crate::error::Result;
use crate::gpu::{Arg, Deferred, Gpu, Tensor};

/// u32 words of one job: the packing's parameters, its weights' offset, its staging offset.
const JOB_WORDS: usize = std::mem::size_of::<Params>() / 4 + 2;

/// Defers packing `w` for the parameters `p` into `view` (`width` x `height` texels, the
/// weight texture's layout) to the run's prologue; false outside a run that keeps packings.
pub(super) fn defer(gpu: &Gpu, mut p: Params, w: &Tensor, view: &wgpu::TextureView, [width, height]: [usize; 2]) -> bool {
    p.total = (width * height) as u32;
    let mut job: Vec<u32> = bytemuck::cast_slice(bytemuck::bytes_of(&p)).to_vec();
    job.extend([(w.offset() / 4) as u32, 0]);
    gpu.defer_packing(Deferred { job, weights: w.clone(), view: view.clone(), size: [width as u32, height as u32] })
}

/// Records the active recording's deferred packings (see the module note) into a command
/// buffer to submit ahead of the run, or `None` if it deferred none.
pub(crate) fn prologue(gpu: &Gpu) -> Result<Option<wgpu::CommandBuffer>> {
    let (jobs, kept) = gpu.take_deferred();
    let Some(first) = jobs.first() else {
        gpu.keep_prologue_buffers(kept);
        return Ok(None);
    };
    // Each job's texels in texel order from `at` on: a texture width is a multiple of 16
    // texels (co16 * 16), so its rows are whole 256-byte copy rows with no padding.
    let mut words = Vec::with_capacity(jobs.len() * JOB_WORDS);
    let mut at = 0usize;
    for d in &jobs {
        words.extend_from_slice(&d.job[..JOB_WORDS - 1]);
        words.push(at as u32);
        at += (d.size[0] * d.size[1]) as usize;
    }
    let most = jobs.iter().map(|d| d.size[0] * d.size[1]).max().unwrap_or(0);
    let fits = |t: &Tensor, len: usize| t.numel() >= len;
    let (job_buf, staging) = match kept {
        Some((j, s)) if fits(&j, words.len()) && fits(&s, at * 4) => (j, s),
        _ => (Tensor::zeros(gpu, &[words.len()])?, Tensor::zeros(gpu, &[at * 4])?),
    };
    gpu.queue.write_buffer(job_buf.buffer(), job_buf.offset(), bytemuck::cast_slice(&words));
    let src = first.weights.clone().into_buffer();
    let src = Tensor::from_buffer(src.clone(), &[(src.size() / 4) as usize])?;
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        let grid = [most.div_ceil(64), jobs.len() as u32, 1];
        gpu.dispatch(&mut pass, TEX_SHADER, "conv_fast_pack_weights_jobs", &Params::default(), &[Arg::R(&job_buf), Arg::R(&src), Arg::W(&staging)], grid)?;
    }
    let mut offset = 0u64;
    for d in &jobs {
        let [width, height] = d.size;
        enc.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: staging.buffer(),
                layout: wgpu::TexelCopyBufferLayout { offset, bytes_per_row: Some(width * 16), rows_per_image: Some(height) },
            },
            d.view.texture().as_image_copy(),
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        offset += u64::from(width * height) * 16;
    }
    gpu.keep_prologue_buffers(Some((job_buf, staging)));
    Ok(Some(enc.finish()))
}
