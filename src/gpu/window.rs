//! Uniform windows: a kernel reads a storage tensor through 64 KiB ranges of it bound as
//! uniform buffers. On lavapipe a per-lane uniform load costs ~1/16 of a storage-buffer load
//! (`rendernet bench --operands`: llvmpipe 22.3 runs every storage load as a loop over the 8
//! lanes with a bounds-checked branch per component), but one uniform binding holds at most
//! 64 KiB, so a kernel reads a tensor in windows of [`WINDOW4`] vec4s, a few per dispatch.

use super::{Gpu, Tensor};
use crate::error::Result;

/// Vec4s in one window: 64 KiB, the `max_uniform_buffer_binding_size` every WebGPU device has
/// at least; the shaders declare their windows `array<vec4<f32>, 4096>`.
pub(crate) const WINDOW4: usize = 4096;

/// Whether windows pay on `gpu` for a dispatch that binds `bindings` of them (besides its
/// parameters): a CPU adapter (lavapipe; a GPU's storage loads are fast, and a uniform read at
/// per-lane addresses may serialise there) whose limits take them.
pub(crate) fn windows_pay(gpu: &Gpu, bindings: usize) -> bool {
    let l = &gpu.limits;
    gpu.info.device_type == wgpu::DeviceType::Cpu
        && l.max_uniform_buffer_binding_size as usize >= WINDOW4 * 16
        && l.max_uniform_buffers_per_shader_stage as usize > bindings
}

/// A uniform binding's offset alignment, in vec4s.
pub(crate) fn align4(gpu: &Gpu) -> usize {
    (gpu.limits.min_uniform_buffer_offset_alignment as usize).div_ceil(16).max(1)
}

/// A window of `t` that holds its vec4s `[start4, start4 + len4)`: the 64 KiB view to bind and
/// the index of vec4 `start4` in it. The window starts at `start4` where the alignment allows,
/// else just before it, and no later than one window before the end of `t`'s buffer (so a
/// small view of a large buffer, as a parameter in the flat parameter buffer, has windows
/// too; the kernels never use what lies past `t`). `None` where that cannot be: a buffer under
/// one window, `t` not whole vec4s from a 16-byte offset, or the range past what one aligned
/// window reaches.
pub(crate) fn window(gpu: &Gpu, t: &Tensor, start4: usize, len4: usize) -> Result<Option<(Tensor, u32)>> {
    let (off4, buf4) = (t.offset() as usize / 16, t.buffer().size() as usize / 16);
    if !t.numel().is_multiple_of(4) || !t.offset().is_multiple_of(16) || buf4 < WINDOW4 || start4 + len4 > t.numel() / 4 {
        return Ok(None);
    }
    let align = align4(gpu);
    let first4 = (off4 + start4).min(buf4 - WINDOW4);
    let base4 = first4 - first4 % align;
    let at = off4 + start4 - base4;
    if at + len4 > WINDOW4 {
        return Ok(None);
    }
    let view = Tensor::view(t.clone().into_buffer(), base4 as u64 * 16, &[WINDOW4 * 4])?;
    Ok(Some((view, at as u32)))
}
