//! A pool of storage buffers keyed by size, for the graph executor's memory planner.
//!
//! Reuse is explicit: the executor knows each tensor's last reader in the schedule and
//! releases its buffer only then. A released buffer may be handed out again within the same
//! encoder, which is safe because commands in one queue run in order; it is NOT safe to
//! release a buffer that a not-yet-submitted encoder reads and then `queue.write_buffer`
//! into it, since queued writes run before that submit's commands.
//!
//! Runs of one graph repeat: the pool remembers which buffer it handed out for each request
//! of the last run ([`BufferPool::begin_run`]) and hands the same one out again while it is
//! free, so every run of a graph binds the same buffers at the same places and the bind
//! groups built for the first run serve all later ones (see `memo`).

use super::{Gpu, Tensor};
use crate::error::Result;
use std::sync::Arc;

/// Free resources of kind `K`, handed out again in the order the last run took them.
pub(crate) struct Reuse<K, V> {
    free: Vec<(K, V)>,
    /// What each request of the last run got, and of this one so far.
    last_run: Vec<V>,
    this_run: Vec<V>,
}

impl<K, V> Default for Reuse<K, V> {
    fn default() -> Self {
        Reuse { free: Vec::new(), last_run: Vec::new(), this_run: Vec::new() }
    }
}

impl<K: PartialEq, V: Clone + PartialEq> Reuse<K, V> {
    /// Starts a run: its k-th request gets the last run's k-th resource while that is free.
    pub(crate) fn begin_run(&mut self) {
        self.last_run = std::mem::take(&mut self.this_run);
    }

    /// A free resource of kind `key` (preferring the replayed one), or `make`'s.
    pub(crate) fn take_or(&mut self, key: K, make: impl FnOnce() -> V) -> V {
        let replay = self.last_run.get(self.this_run.len());
        let i = replay
            .and_then(|r| self.free.iter().position(|(k, v)| *k == key && v == r))
            .or_else(|| self.free.iter().rposition(|(k, _)| *k == key));
        let v = match i {
            Some(i) => self.free.swap_remove(i).1,
            None => make(),
        };
        self.this_run.push(v.clone());
        v
    }

    /// Returns a resource for reuse.
    pub(crate) fn put(&mut self, key: K, v: V) {
        self.free.push((key, v));
    }
}

/// Buffers grouped by byte size (rounded up to 256 so near sizes share).
#[derive(Default)]
pub struct BufferPool {
    reuse: Reuse<u64, Arc<wgpu::Buffer>>,
    allocated_bytes: u64,
}

impl BufferPool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a run: its k-th request gets the last run's k-th buffer while that is free.
    pub fn begin_run(&mut self) {
        self.reuse.begin_run();
    }

    /// A tensor of `shape`, reusing a released buffer of the same size class if any.
    pub fn tensor(&mut self, gpu: &Gpu, shape: &[usize]) -> Result<Tensor> {
        let bytes = (shape.iter().product::<usize>() as u64 * 4).div_ceil(256) * 256;
        gpu.check_binding_size(&format!("tensor {shape:?}"), bytes)?;
        let buf = self.reuse.take_or(bytes, || {
            self.allocated_bytes += bytes;
            super::memo::note_created();
            Arc::new(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pooled"),
                size: bytes,
                usage: Tensor::usage(),
                mapped_at_creation: false,
            }))
        });
        Tensor::from_buffer(buf, shape)
    }

    /// Returns a tensor's buffer for reuse (see the module note on when that is safe).
    /// A view ([`Tensor::view`]) shares its buffer with other tensors and is never pooled.
    pub fn release(&mut self, t: Tensor) {
        if t.is_view() {
            return;
        }
        let size = t.buffer().size();
        self.reuse.put(size, t.into_buffer());
    }

    /// Total bytes this pool has ever allocated: the peak of what it held at once.
    pub fn allocated_bytes(&self) -> u64 {
        self.allocated_bytes
    }
}
