//! Per-graph reuse of what a recording creates: uniform blocks, bind groups, scratch buffers
//! and textures. A graph records the same dispatches in the same order every step, so the
//! k-th dispatch of one step can reuse the k-th dispatch's bind group of the last step, and
//! the scratch an op takes can come from a pool the op hands back when it ends (the next op
//! of the same encoder may reuse it: commands run in order).
//!
//! The executor installs its [`Memo`] for the duration of a run ([`Gpu::recording`]); ops
//! never see it. Outside a recording, [`Gpu::dispatch`] makes a fresh uniform buffer and bind
//! group per call and [`Gpu::scratch`] a fresh zeroed buffer, as one-off work wants.
//!
//! Uniform blocks live in 256-byte slots (wgpu's largest `min_uniform_buffer_offset_alignment`)
//! of a few chunk buffers, bound with a dynamic offset; the recording's bytes are compared
//! with what the chunks hold and only changed chunks are written, once, just before the
//! submit (`queue.write_buffer` runs ahead of the submitted commands). The k-th bind group
//! is reused only if the k-th dispatch binds the very same pipeline, parameter size and
//! resources (wgpu's handles compare by identity, and the memo holds them, so an identity
//! cannot be recycled while compared).

use super::constant::{Constants, Deferred, Packing, PrologueBuffers};
use super::kept::KeptOperands;
use super::pool::Reuse;
use super::{BufferPool, Gpu, Tensor};
use crate::error::{Error, Result};
use std::cell::{Cell, RefCell};

/// Bytes per uniform slot.
pub(crate) const SLOT: u64 = 256;
/// Slots per uniform chunk buffer.
const CHUNK_SLOTS: usize = 64;

thread_local! {
    /// The memo of the recording this thread is making, if any.
    pub(super) static ACTIVE: RefCell<Option<Memo>> = const { RefCell::new(None) };
    /// GPU objects (buffers, textures, bind groups) this thread has created.
    static CREATED: Cell<u64> = const { Cell::new(0) };
}

/// Counts one created GPU object (for [`Gpu::created_count`]).
pub(crate) fn note_created() {
    CREATED.with(|c| c.set(c.get() + 1));
}

/// GPU objects created by the calling thread so far.
pub(crate) fn created() -> u64 {
    CREATED.with(|c| c.get())
}

/// One resource of a bind group, compared by identity.
#[derive(PartialEq)]
enum Res {
    /// A buffer and the offset it is bound at (views share buffers).
    Buffer(wgpu::Buffer, u64),
    View(wgpu::TextureView),
    Absent,
}

struct Bind {
    entry: (&'static str, &'static str),
    size: u64,
    resources: Vec<Res>,
    group: wgpu::BindGroup,
}

/// Size and dimension of a scratch texture (rgba32f).
pub(super) type TexKey = ([usize; 3], wgpu::TextureDimension);

/// What the recordings of one graph keep for the next (see the module note).
#[derive(Default)]
pub struct Memo {
    binds: Vec<Bind>,
    chunks: Vec<wgpu::Buffer>,
    /// This recording's uniform blocks, slot after slot.
    data: Vec<u8>,
    /// What the chunk buffers hold.
    written: Vec<u8>,
    scratch: BufferPool,
    live: Vec<Tensor>,
    textures: Reuse<TexKey, wgpu::TextureView>,
    live_textures: Vec<(TexKey, wgpu::TextureView)>,
    texture_bytes: u64,
    /// Weights packed once, while the parameters stay unchanged (see `constant.rs`).
    constants: Constants,
    /// Operand packings kept from an op's forward for its backward (see `kept.rs`).
    pub(super) kept: KeptOperands,
}

impl Memo {
    /// Bytes of scratch buffers, scratch textures and uniform chunks this memo holds.
    pub fn bytes(&self) -> u64 {
        self.scratch.allocated_bytes() + self.texture_bytes + self.constants.bytes() + self.chunks.len() as u64 * SLOT * CHUNK_SLOTS as u64
    }

    /// Before a run: `params` is the buffer holding the graph's parameters and the version of
    /// its contents, whose packings this run may reuse and keep (`None`: none; the executor
    /// passes its parameters for every run, a training step's too, since Adam changes them
    /// only in the run's last command).
    pub fn begin_constants(&mut self, params: Option<(wgpu::Buffer, u64)>) {
        self.constants.begin_run(params);
    }

    /// After a run: whether it was submitted, making the packings it recorded valid.
    pub fn end_constants(&mut self, submitted: bool) {
        self.constants.end_run(submitted);
    }

    /// The bind group and dynamic offset of the next dispatch, reusing the last recording's
    /// when it bound the same things.
    fn bind(
        &mut self,
        gpu: &Gpu,
        entry: (&'static str, &'static str),
        layout: &wgpu::BindGroupLayout,
        params: &[u8],
        args: &[super::Arg],
    ) -> Result<(wgpu::BindGroup, u32)> {
        if params.len() as u64 > SLOT {
            return Err(Error::Invalid(format!("{}::{}: parameter block of {} bytes exceeds {SLOT}", entry.0, entry.1, params.len())));
        }
        let k = (self.data.len() as u64 / SLOT) as usize;
        let chunk = k / CHUNK_SLOTS;
        while self.chunks.len() <= chunk {
            self.chunks.push(gpu.new_buffer("uniform chunk", SLOT * CHUNK_SLOTS as u64, wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST));
        }
        self.data.extend_from_slice(params);
        self.data.resize((k + 1) * SLOT as usize, 0);
        let resources: Vec<Res> = args.iter().map(|a| match a {
            super::Arg::R(t) | super::Arg::W(t) | super::Arg::U(t) => Res::Buffer(t.buffer().clone(), t.offset()),
            super::Arg::Absent => Res::Absent,
            super::Arg::Texture(v, _) | super::Arg::StorageTexture(v, _) | super::Arg::ReadStorageTexture(v, _) => Res::View((*v).clone()),
        }).collect();
        let size = params.len() as u64;
        let offset = ((k % CHUNK_SLOTS) as u64 * SLOT) as u32;
        if let Some(b) = self.binds.get(k) {
            if b.entry == entry && b.size == size && b.resources == resources {
                return Ok((b.group.clone(), offset));
            }
        }
        let uniform = wgpu::BufferBinding { buffer: &self.chunks[chunk], offset: 0, size: std::num::NonZeroU64::new(size) };
        let group = gpu.bind_group(layout, uniform, args);
        let b = Bind { entry, size, resources, group: group.clone() };
        if k < self.binds.len() {
            self.binds[k] = b;
        } else {
            self.binds.push(b);
        }
        Ok((group, offset))
    }

    /// Writes the uniform chunks whose bytes changed since they were last written.
    fn flush(&mut self, gpu: &Gpu) {
        let chunk_bytes = SLOT as usize * CHUNK_SLOTS;
        if self.written.len() < self.data.len() {
            // Fresh slots: force their chunk to be written.
            self.written.resize(self.data.len(), 0xff);
        }
        for (c, range) in (0..self.data.len()).step_by(chunk_bytes).map(|s| s..(s + chunk_bytes).min(self.data.len())).enumerate() {
            if self.written[range.clone()] != self.data[range.clone()] {
                gpu.queue.write_buffer(&self.chunks[c], 0, &self.data[range.clone()]);
                self.written[range.clone()].copy_from_slice(&self.data[range]);
            }
        }
    }

    /// Hands node `node`'s kept packings (every node's with `None`) back to the texture pool.
    pub(super) fn release_kept(&mut self, node: Option<usize>) {
        for (k, v) in self.kept.take(node) {
            self.textures.put(k, v);
        }
    }

    /// Hands the scratch of the op that just ended back to the pools.
    fn op_done(&mut self) {
        for t in self.live.drain(..) {
            self.scratch.release(t);
        }
        for (k, v) in self.live_textures.drain(..) {
            self.textures.put(k, v);
        }
    }
}

impl Gpu {
    /// Runs `f` (which records one graph run and submits it) with `memo` installed: the
    /// dispatches and scratch of `f` reuse what the memo kept from the last run and leave
    /// what they create in it.
    pub fn recording<T>(&self, memo: &mut Memo, f: impl FnOnce() -> T) -> T {
        struct Restore<'a>(&'a mut Memo, Option<Memo>);
        impl Drop for Restore<'_> {
            fn drop(&mut self) {
                let mut m = ACTIVE.with(|a| a.replace(self.1.take())).unwrap_or_default();
                m.op_done();
                m.release_kept(None);
                m.kept.node = None;
                m.data.clear();
                *self.0 = m;
            }
        }
        let mut m = std::mem::take(memo);
        m.data.clear();
        m.scratch.begin_run();
        m.textures.begin_run();
        let prev = ACTIVE.with(|a| a.replace(Some(m)));
        let _restore = Restore(memo, prev);
        f()
    }

    /// A scratch tensor for the op being recorded. Inside a [`Gpu::recording`] it comes from
    /// the memo's pool with undefined contents (the kernel must write all it reads) and goes
    /// back when the executor calls [`op_done`]; otherwise it is a fresh zeroed tensor.
    pub fn scratch(&self, shape: &[usize]) -> Result<Tensor> {
        let pooled = ACTIVE.with(|a| {
            a.borrow_mut().as_mut().map(|m| {
                let t = m.scratch.tensor(self, shape)?;
                m.live.push(t.clone());
                Ok(t)
            })
        });
        pooled.unwrap_or_else(|| Tensor::zeros(self, shape))
    }

    /// An rgba32f texture of `size` (width, height, depth or layers) the op being recorded
    /// writes as storage and then samples; pooled like [`Gpu::scratch`].
    pub(crate) fn scratch_texture(&self, size: [usize; 3], dim: wgpu::TextureDimension) -> wgpu::TextureView {
        let view = self.pooled_texture(size, dim);
        ACTIVE.with(|a| {
            if let Some(m) = a.borrow_mut().as_mut() {
                m.live_textures.push(((size, dim), view.clone()));
            }
        });
        view
    }

    /// A texture from the active recording's pool (a fresh one outside a recording) that the
    /// caller hands back: [`Gpu::scratch_texture`] at the op's end, a kept packing later.
    pub(super) fn pooled_texture(&self, size: [usize; 3], dim: wgpu::TextureDimension) -> wgpu::TextureView {
        let make = || self.new_rgba32f_texture(size, dim);
        ACTIVE.with(|a| match a.borrow_mut().as_mut() {
            Some(m) => m.textures.take_or((size, dim), || {
                m.texture_bytes += size.iter().product::<usize>() as u64 * 16;
                make()
            }),
            None => make(),
        })
    }

    /// The bind group and dynamic offset of a dispatch: the memo's inside a recording, else
    /// `None` (the caller makes a one-off uniform buffer).
    pub(crate) fn memo_bind(
        &self,
        entry: (&'static str, &'static str),
        layout: &wgpu::BindGroupLayout,
        params: &[u8],
        args: &[super::Arg],
    ) -> Option<Result<(wgpu::BindGroup, u32)>> {
        ACTIVE.with(|a| a.borrow_mut().as_mut().map(|m| m.bind(self, entry, layout, params, args)))
    }

    /// The kept packing of weights `w` by `key` inside a recording whose parameters are
    /// unchanged since a packing, and whether it is valid (see [`Constants::packing`]).
    pub(crate) fn constant_packing(&self, w: &Tensor, key: &[u8], bytes: u64, make: impl FnOnce() -> Result<Packing>) -> Result<Option<(Packing, bool)>> {
        ACTIVE.with(|a| a.borrow_mut().as_mut().map_or(Ok(None), |m| m.constants.packing(w, key, bytes, make)))
    }

    /// Inside a recording that keeps packings, defers `d` to the run's prologue (see
    /// `constant.rs`) and returns true, unless the run's deferred packings would then hold
    /// more than `max_texels` texels; else false (the caller packs it itself).
    pub(crate) fn defer_packing(&self, d: Deferred, max_texels: usize) -> bool {
        ACTIVE.with(|a| a.borrow_mut().as_mut().is_some_and(|m| m.constants.defer(d, max_texels)))
    }

    /// The active recording's deferred packings with the parameter buffer they read (`None`
    /// with none), and its kept prologue buffers (taken: hand them back with
    /// [`Gpu::keep_prologue_buffers`]).
    pub(crate) fn take_deferred(&self) -> (Option<(Vec<Deferred>, wgpu::Buffer)>, Option<PrologueBuffers>) {
        ACTIVE.with(|a| a.borrow_mut().as_mut().map_or((None, None), |m| (m.constants.take_deferred(), m.constants.batch.take())))
    }

    /// Hands the prologue's buffers back to the active recording.
    pub(crate) fn keep_prologue_buffers(&self, b: Option<PrologueBuffers>) {
        ACTIVE.with(|a| {
            if let Some(m) = a.borrow_mut().as_mut() {
                m.constants.batch = b;
            }
        });
    }

    /// Writes the active recording's changed uniform blocks (called right before a submit).
    pub(crate) fn flush_memo(&self) {
        ACTIVE.with(|a| {
            if let Some(m) = a.borrow_mut().as_mut() {
                m.flush(self);
            }
        });
    }

    /// A buffer, counted in [`Gpu::created_count`].
    pub(crate) fn new_buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        note_created();
        self.device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
    }

    /// GPU objects (buffers, textures, bind groups) the calling thread has created on any
    /// device: a step's count is its own even while other threads share the device.
    pub fn created_count(&self) -> u64 {
        created()
    }
}

/// Ends the current op of the active recording: its scratch may serve the next op.
pub(crate) fn op_done() {
    ACTIVE.with(|a| {
        if let Some(m) = a.borrow_mut().as_mut() {
            m.op_done();
        }
    });
}
