//! Weights packed once. The tiled conv kernels read their weights repacked (an rgba32f
//! texture or a channels-last buffer, `ops::conv_fast`), and every run of a graph used to
//! repack them: a dispatch per conv and pass, with its loads. While the parameters do not
//! change (rendering, inverse rendering through a frozen network, benchmarks) the last run's
//! packing is still valid, so the executor tells its recording which buffer holds the
//! parameters and a version it bumps at every write to them (`Executor::feed`, a training
//! step), and a packing of a tensor in that buffer made at that version is reused with no
//! dispatch. Other tensors never qualify: a computed value or an input may hold other
//! contents at the same place next run.
//!
//! A kept texture packing that is stale (a training step's, or a run's after a parameter was
//! fed) is not packed by its op either: the op defers it ([`Deferred`]), and the executor
//! packs all of a run's deferred packings in one dispatch recorded ahead of the run
//! (`ops/conv_pack_jobs.rs`), as the same submit's first command buffer. The parameters do
//! not change before the run's optimizer update, its last command.

use super::{Gpu, Tensor};
use crate::error::Result;
use std::collections::HashMap;

/// Where a packing lives: a texture the kernels read as a storage texture, or a buffer.
#[derive(Clone)]
pub(crate) enum Packing {
    Texture(wgpu::TextureView),
    Buffer(Tensor),
}

/// A weight packing deferred to the run's prologue (`ops/conv_pack_jobs.rs`): its job (the
/// packing's parameters with `total` its texels, then the offset of its weights in the
/// run's parameter buffer, in u32 words), and its texture and size in texels.
pub(crate) struct Deferred {
    pub(crate) job: Vec<u32>,
    pub(crate) view: wgpu::TextureView,
    pub(crate) size: [u32; 2],
}

/// What the prologue keeps from run to run (`ops/conv_pack_jobs.rs`): the jobs it was made
/// for, the staging buffer its texels go to, the map of each packed float's parameter index,
/// and the texture the parameters are copied into, with its size.
pub(crate) struct PrologueBuffers {
    pub(crate) jobs: Vec<u32>,
    pub(crate) staging: Tensor,
    pub(crate) map: wgpu::TextureView,
    pub(crate) src: wgpu::TextureView,
    pub(crate) src_size: [usize; 3],
}

struct Entry {
    packing: Packing,
    /// The parameter version its contents were packed from; `None` until a run that packed
    /// them has been submitted.
    version: Option<u64>,
}

/// The packings one graph's runs keep for the next (held by its [`super::Memo`]).
#[derive(Default)]
pub(crate) struct Constants {
    /// The buffer of the graph's parameters and the version of its contents, for this run;
    /// `None`: nothing is reused (a training step, which changes them, or a one-off call).
    params: Option<(wgpu::Buffer, u64)>,
    entries: HashMap<Vec<u8>, Entry>,
    /// Keys packed by the run being recorded.
    pending: Vec<Vec<u8>>,
    /// Packings deferred to this run's prologue.
    deferred: Vec<Deferred>,
    /// The prologue's buffers, kept from run to run (made anew when the packings change).
    pub(crate) batch: Option<PrologueBuffers>,
    bytes: u64,
}

impl Constants {
    /// Sets what the next run may reuse (see [`Constants::params`]).
    pub(crate) fn begin_run(&mut self, params: Option<(wgpu::Buffer, u64)>) {
        self.params = params;
        self.pending.clear();
        self.deferred.clear();
    }

    /// Marks the packings recorded by this run valid for its version when the run was
    /// submitted (`ok`); otherwise they hold nothing reliable and are packed again.
    pub(crate) fn end_run(&mut self, ok: bool) {
        self.deferred.clear();
        let version = self.params.take().map(|p| p.1).filter(|_| ok);
        for k in self.pending.drain(..) {
            if let Some(e) = self.entries.get_mut(&k) {
                e.version = version;
            }
        }
    }

    /// Bytes of the packings kept, and of the prologue's buffers.
    pub(crate) fn bytes(&self) -> u64 {
        let prologue = |b: &PrologueBuffers| {
            // The map holds the staging buffer's texels in whole rows as wide as the source's.
            let row = b.src_size[0];
            b.staging.numel() + 4 * ((b.staging.numel() / 4).div_ceil(row) * row + row * b.src_size[1])
        };
        self.bytes + self.batch.as_ref().map_or(0, prologue) as u64 * 4
    }

    /// Defers the packing into `d.view` to this run's prologue (once, however often asked);
    /// false if the run's deferred packings would then hold more than `max_texels` texels.
    pub(crate) fn defer(&mut self, d: Deferred, max_texels: usize) -> bool {
        if self.deferred.iter().any(|e| e.view == d.view) {
            return true;
        }
        let texels = |d: &Deferred| d.size[0] as usize * d.size[1] as usize;
        if self.deferred.iter().map(texels).sum::<usize>() + texels(&d) > max_texels {
            return false;
        }
        self.deferred.push(d);
        true
    }

    /// The packings deferred so far, handed to the prologue with the buffer of the
    /// parameters they read (`None` with none deferred).
    pub(crate) fn take_deferred(&mut self) -> Option<(Vec<Deferred>, wgpu::Buffer)> {
        let jobs = std::mem::take(&mut self.deferred);
        let params = self.params.as_ref().map(|p| p.0.clone());
        params.filter(|_| !jobs.is_empty()).map(|b| (jobs, b))
    }

    /// The packing of `w` by `key` (whatever else decides its layout), and whether it already
    /// holds `w`'s current values (the caller then records nothing); made by `make` (a
    /// dedicated object of `bytes` bytes) the first time. `None` where `w` is not a parameter
    /// of the run or the run reuses nothing.
    pub(crate) fn packing(&mut self, w: &Tensor, key: &[u8], bytes: u64, make: impl FnOnce() -> Result<Packing>) -> Result<Option<(Packing, bool)>> {
        let Some((buffer, version)) = self.params.as_ref() else { return Ok(None) };
        if w.buffer() != buffer {
            return Ok(None);
        }
        let mut k = Vec::with_capacity(key.len() + 8 + 8 * w.shape().len());
        k.extend_from_slice(&w.offset().to_le_bytes());
        for &d in w.shape() {
            k.extend_from_slice(&(d as u64).to_le_bytes());
        }
        k.extend_from_slice(key);
        if !self.entries.contains_key(&k) {
            self.entries.insert(k.clone(), Entry { packing: make()?, version: None });
            self.bytes += bytes;
        }
        let e = &self.entries[&k];
        let valid = e.version == Some(*version);
        let packing = e.packing.clone();
        if !valid {
            self.pending.push(k);
        }
        Ok(Some((packing, valid)))
    }
}

impl Gpu {
    /// An rgba32f texture the kernels write as storage and read back, counted in
    /// [`Gpu::created_count`].
    pub(crate) fn new_rgba32f_texture(&self, size: [usize; 3], dim: wgpu::TextureDimension) -> wgpu::TextureView {
        super::memo::note_created();
        let tex = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("rgba32f texture"),
            size: wgpu::Extent3d { width: size[0] as u32, height: size[1] as u32, depth_or_array_layers: size[2] as u32 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: dim,
            format: wgpu::TextureFormat::Rgba32Float,
            // COPY_DST: the packings copy their texels in on CPU adapters (gpu/passes.rs).
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        tex.create_view(&Default::default())
    }
}
