//! The GPU runtime: device, tensors, the pipeline cache and the one dispatch path every op
//! uses. Ops record into a caller's [`wgpu::ComputePass`] so a whole step shares one submit.

mod calibration;
mod constant;
mod context;
mod kept;
mod kernel;
mod memo;
mod passes;
mod pool;
mod tensor;
mod window;

pub use kernel::{Arg, Shader, grid_1d, MAX_WORKGROUPS_PER_DIM, SHADER_DIR_ENV};
pub(crate) use kernel::wgsl;
pub use memo::Memo;
pub(crate) use passes::staging_pitch;
pub(crate) use constant::{Deferred, Packing, PrologueBuffers};
pub(crate) use memo::op_done;
pub use pool::BufferPool;
pub use tensor::Tensor;
pub(crate) use tensor::read_staging;
pub(crate) use window::{WINDOW4, align4, window, windows_pay};

use crate::error::{Error, Result};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

thread_local! {
    static SUBMITS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    static DISPATCHES: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// A GPU (or lavapipe) device with its queue, limits and caches.
pub struct Gpu {
    /// The wgpu device.
    pub device: wgpu::Device,
    /// The queue all work is submitted to.
    pub queue: wgpu::Queue,
    /// Which adapter this is (name, backend, driver).
    pub info: wgpu::AdapterInfo,
    /// The adapter's real limits, which the device was opened with.
    pub limits: wgpu::Limits,
    /// Optional features that were enabled (timestamp queries when present).
    pub features: wgpu::Features,
    pipelines: Mutex<HashMap<(&'static str, &'static str), Arc<kernel::Pipeline>>>,
    modules: Mutex<HashMap<&'static str, wgpu::ShaderModule>>,
    /// Bound in place of an absent optional input (a conv without bias): wgpu forbids
    /// binding the same buffer as read and read-write in one dispatch, so aliasing is no option.
    dummy: wgpu::Buffer,
    /// Whether `ConvKernel::Auto` reads textures (decided once per device by
    /// `ops::conv_fast::calibrated`).
    pub(crate) conv_textures: std::sync::OnceLock<bool>,
    /// Whether `ConvKernel::Auto` runs the narrow heads' forward on the unpacked input, read
    /// from its buffer and from its stage texture (decided once per device by
    /// `ops::conv_nchw::wins`).
    pub(crate) conv_nchw: [std::sync::OnceLock<bool>; 2],
    /// The fewest texels of a texture packing that copies them in from a staging buffer
    /// rather than storing them (decided once per device by `ops::conv_operands::copy_min_texels`).
    pub(crate) pack_copies: std::sync::OnceLock<usize>,
}

impl Gpu {
    /// Opens the adapter chosen by `WGPU_BACKEND` / `WGPU_ADAPTER_NAME`, or the best present.
    /// With no adapter, the error says what was tried and how to install lavapipe.
    pub fn new() -> Result<Gpu> {
        let o = context::open()?;
        memo::note_created();
        let dummy = o.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("dummy"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Ok(Gpu {
            device: o.device,
            queue: o.queue,
            info: o.info,
            limits: o.limits,
            features: o.features,
            pipelines: Mutex::new(HashMap::new()),
            modules: Mutex::new(HashMap::new()),
            dummy,
            conv_textures: Default::default(),
            conv_nchw: Default::default(),
            pack_copies: Default::default(),
        })
    }

    /// Dispatches recorded by the calling thread, on any device (for per-step statistics: a
    /// step's count is then its own even while other threads share the device).
    pub fn dispatch_count(&self) -> u64 {
        DISPATCHES.with(|c| c.get())
    }

    /// Counts one recorded dispatch (see [`Gpu::dispatch_count`]).
    pub(crate) fn count_dispatch(&self) {
        DISPATCHES.with(|c| c.set(c.get() + 1));
    }

    /// Takes back `n` counted dispatches: the profiler's own, which are no op's work.
    pub(crate) fn uncount_dispatches(&self, n: u64) {
        DISPATCHES.with(|c| c.set(c.get() - n));
    }

    /// Queue submits (each followed by a wait) made by the calling thread, on any device: a
    /// step's count is then its own even while other threads share the device.
    pub fn submit_count(&self) -> u64 {
        SUBMITS.with(|c| c.get())
    }

    /// Whether subgroup operations are enabled with subgroups of a multiple of 8 lanes (what
    /// the texture conv kernels need; lavapipe has 8).
    pub fn has_subgroups_of_8(&self) -> bool {
        self.features.contains(wgpu::Features::SUBGROUP)
            && self.info.subgroup_min_size >= 8
            && self.info.subgroup_min_size % 8 == 0
            && self.info.subgroup_max_size % 8 == 0
    }

    /// Whether rgba32float textures can be bound as read-only storage textures (how the texture
    /// conv kernels read their operands).
    pub fn reads_rgba32f_storage(&self) -> bool {
        self.features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
    }

    /// Whether GPU timestamps can be taken inside compute passes.
    pub fn has_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES)
    }

    /// Records `f` into a compute pass of a fresh encoder ([`Gpu::record_passes`]: a texture
    /// packing may end it for a copy and begin another), submits it and waits. Convenient for
    /// tests and one-off ops; a training step records many ops into one encoder the same way.
    pub fn run<T>(&self, f: impl FnOnce(&mut wgpu::ComputePass<'_>) -> Result<T>) -> Result<T> {
        let enc = self.device.create_command_encoder(&Default::default());
        let (enc, out) = self.record_passes(enc, f);
        let out = out?;
        self.submit_and_wait(enc)?;
        Ok(out)
    }

    /// Submits one encoder and blocks until the device has finished it.
    pub fn submit_and_wait(&self, enc: wgpu::CommandEncoder) -> Result<()> {
        self.submit_after_and_wait(None, enc)
    }

    /// [`Gpu::submit_and_wait`] with `first` (a run's prologue) ahead of `enc` in the submit.
    pub(crate) fn submit_after_and_wait(&self, first: Option<wgpu::CommandBuffer>, enc: wgpu::CommandEncoder) -> Result<()> {
        self.flush_memo();
        let idx = self.queue.submit(first.into_iter().chain([enc.finish()]));
        SUBMITS.with(|c| c.set(c.get() + 1));
        self.device
            .poll(wgpu::PollType::Wait { submission_index: Some(idx), timeout: None })
            .map(|_| ())
            .map_err(|e| Error::Device(format!("waiting for the GPU failed: {e}")))
    }

    /// Checks that `bytes` fit one storage binding and one buffer on this device.
    pub fn check_binding_size(&self, what: &str, bytes: u64) -> Result<()> {
        let lim = self.limits.max_storage_buffer_binding_size as u64;
        if bytes > lim {
            return Err(Error::Limit {
                what: format!("{what} size in bytes"),
                value: bytes,
                limit: lim,
                name: "max_storage_buffer_binding_size",
            });
        }
        if bytes > self.limits.max_buffer_size {
            return Err(Error::Limit {
                what: format!("{what} size in bytes"),
                value: bytes,
                limit: self.limits.max_buffer_size,
                name: "max_buffer_size",
            });
        }
        Ok(())
    }
}
