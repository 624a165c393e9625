//! Compute passes an op can interrupt for a copy. A texture can only be written by a
//! storage-texture store or a copy, and on lavapipe the store is the dear one: an rgba32f
//! `textureStore` cost ~130 ns per 8 lanes against ~40 for a vec4 storage-buffer store
//! (Intel Xeon family 6 model 167, Mesa 22.3.6, `rendernet bench --operands`), while
//! `copy_buffer_to_texture` moved 2 MiB into an rgba32f texture in ~0.16 ms (README
//! "Measured: Intel Xeon (family 6 model 167)"). So the texture family's packings write a
//! buffer in texel order and copy it in ([`Gpu::copy_to_texture`]), which means ending the
//! pass, copying and beginning the next one inside the same encoder and submit; since that
//! split costs the same for any size (~95 us on an AMD Zen 4), only packings from a size
//! where copying measured faster do so (`ops::conv_operands::copy_min_texels`).
//!
//! Ops only see `&mut wgpu::ComputePass`, so [`Gpu::record_passes`] keeps the encoder of the
//! pass it hands out (thread-local, a stack for recordings made inside recordings, e.g. a
//! calibration during a graph's first run) beside that pass's address; an op may split only
//! the pass on top, and any other pass (one a caller began on its own encoder) is refused, the
//! op then recording its texture stores as before.

use super::{Gpu, Tensor};
use crate::error::{Error, Result};
use std::cell::{Cell, RefCell};

/// An open recording: its pass's address, its encoder, and (from its first split) a spare
/// encoder whose throwaway passes stand in while the real one is ended.
struct Open {
    pass: usize,
    enc: wgpu::CommandEncoder,
    spare: Option<wgpu::CommandEncoder>,
}

/// Pops the recording's entry if `f` panics, so an outer recording still finds its own on top.
struct Unwind;

impl Drop for Unwind {
    fn drop(&mut self) {
        if std::thread::panicking() {
            OPEN.with(|o| o.borrow_mut().pop());
        }
    }
}

thread_local! {
    static OPEN: RefCell<Vec<Open>> = const { RefCell::new(Vec::new()) };
    /// Passes ended for a copy on this thread (see [`Gpu::pass_splits`]).
    static SPLITS: Cell<u64> = const { Cell::new(0) };
}

fn address(pass: &wgpu::ComputePass<'_>) -> usize {
    pass as *const wgpu::ComputePass<'_> as usize
}

impl Gpu {
    /// Records `f` into a compute pass of `enc` that ops may interrupt for copies
    /// ([`Gpu::copy_to_texture`]); returns the encoder, all passes ended, for more commands
    /// and the submit, with `f`'s result.
    pub fn record_passes<T>(
        &self,
        mut enc: wgpu::CommandEncoder,
        f: impl FnOnce(&mut wgpu::ComputePass<'_>) -> Result<T>,
    ) -> (wgpu::CommandEncoder, Result<T>) {
        let mut pass = enc.begin_compute_pass(&Default::default()).forget_lifetime();
        OPEN.with(|o| o.borrow_mut().push(Open { pass: address(&pass), enc, spare: None }));
        let unwind = Unwind;
        let out = f(&mut pass);
        drop(pass);
        std::mem::forget(unwind);
        let open = OPEN.with(|o| o.borrow_mut().pop()).expect("record_passes pops what it pushed");
        (open.enc, out)
    }

    /// Whether `pass` is the innermost pass of [`Gpu::record_passes`], which
    /// [`Gpu::copy_to_texture`] may end and begin again.
    pub(crate) fn can_split(&self, pass: &wgpu::ComputePass<'_>) -> bool {
        OPEN.with(|o| o.borrow().last().is_some_and(|open| open.pass == address(pass)))
    }

    /// Records a copy of `src` (texels in order x, then y, then layer, [`staging_pitch`] of the
    /// texture's width texels a row, 16 bytes a texel, from its first byte) into the whole
    /// rgba32f texture of `dst`, between
    /// the dispatches recorded into `pass` so far and those after: the pass is ended, the copy
    /// recorded, a new pass begun in its place. Only where [`Gpu::can_split`] holds: else an
    /// error (the caller checks first).
    pub(crate) fn copy_to_texture(&self, pass: &mut wgpu::ComputePass<'_>, src: &Tensor, dst: &wgpu::TextureView) -> Result<()> {
        if !self.can_split(pass) {
            return Err(Error::Invalid("copy_to_texture: this pass was not begun by Gpu::record_passes".into()));
        }
        if !src.offset().is_multiple_of(16) {
            return Err(Error::Invalid(format!("copy_to_texture: the source starts at byte {}, not a multiple of a texel's 16", src.offset())));
        }
        let tex = dst.texture();
        let size = tex.size();
        OPEN.with(|o| {
            let mut o = o.borrow_mut();
            let open = o.last_mut().expect("can_split found it");
            let spare = open.spare.get_or_insert_with(|| self.device.create_command_encoder(&Default::default()));
            let stand_in = spare.begin_compute_pass(&Default::default()).forget_lifetime();
            // Ends the real pass: its encoder takes commands again.
            drop(std::mem::replace(pass, stand_in));
            open.enc.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: src.buffer(),
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: src.offset(),
                        bytes_per_row: Some(staging_pitch(size.width as usize) as u32 * 16),
                        rows_per_image: Some(size.height),
                    },
                },
                tex.as_image_copy(),
                size,
            );
            let fresh = open.enc.begin_compute_pass(&Default::default()).forget_lifetime();
            drop(std::mem::replace(pass, fresh));
            open.pass = address(pass);
        });
        SPLITS.with(|s| s.set(s.get() + 1));
        Ok(())
    }

    /// Settles which texture packings on a CPU adapter copy their texels in: those of at
    /// least `min_texels` texels (0: every one, `usize::MAX`: none; the others store them),
    /// instead of the `conv-pack-copies` calibration on first use: for tests that must take
    /// one path whatever the machine measures. False if it was already settled otherwise.
    pub fn settle_pack_copies(&self, min_texels: usize) -> bool {
        *self.pack_copies.get_or_init(|| min_texels) == min_texels
    }

    /// Passes this thread has ended for a copy ([`Gpu::copy_to_texture`]) so far.
    pub fn pass_splits(&self) -> u64 {
        SPLITS.with(|s| s.get())
    }
}

/// Texels a staging buffer's row holds for a texture `width` texels wide: buffer-to-texture
/// copies take rows of a multiple of 256 bytes (16 texels).
pub(crate) fn staging_pitch(width: usize) -> usize {
    width.div_ceil(16) * 16
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::panic::{AssertUnwindSafe, catch_unwind};

    /// Only the innermost pass of `record_passes` can be split, a pass begun elsewhere never,
    /// and a recording that panics inside another (caught there) leaves the outer one's pass
    /// splittable again.
    #[test]
    fn only_the_innermost_recorded_pass_splits_even_after_a_panic() {
        let gpu = Gpu::new().unwrap();
        let enc = || gpu.device.create_command_encoder(&Default::default());
        let (_, outer) = gpu.record_passes(enc(), |pass| {
            let (_, inner) = gpu.record_passes(enc(), |inner| Ok(gpu.can_split(inner) && !gpu.can_split(pass)));
            let caught = catch_unwind(AssertUnwindSafe(|| gpu.record_passes(enc(), |_| -> Result<()> { panic!("inside a recording") })));
            Ok(inner? && caught.is_err() && gpu.can_split(pass))
        });
        assert!(outer.unwrap());
        let mut own = enc();
        assert!(!gpu.can_split(&own.begin_compute_pass(&Default::default())));
    }
}
