//! A pool of storage buffers keyed by size, for the graph executor's memory planner.
//!
//! Reuse is explicit: the executor knows each tensor's last reader in the schedule and
//! releases its buffer only then. A released buffer may be handed out again within the same
//! encoder, which is safe because commands in one queue run in order; it is NOT safe to
//! release a buffer that a not-yet-submitted encoder reads and then `queue.write_buffer`
//! into it, since queued writes run before that submit's commands.

use super::{Gpu, Tensor};
use crate::error::Result;
use std::collections::HashMap;
use std::sync::Arc;

/// Buffers grouped by byte size (rounded up to 256 so near sizes share).
#[derive(Default)]
pub struct BufferPool {
    free: HashMap<u64, Vec<Arc<wgpu::Buffer>>>,
    allocated_bytes: u64,
}

impl BufferPool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// A tensor of `shape`, reusing a released buffer of the same size class if any.
    pub fn tensor(&mut self, gpu: &Gpu, shape: &[usize]) -> Result<Tensor> {
        let bytes = (shape.iter().product::<usize>() as u64 * 4).div_ceil(256) * 256;
        gpu.check_binding_size(&format!("tensor {shape:?}"), bytes)?;
        let buf = match self.free.get_mut(&bytes).and_then(|v| v.pop()) {
            Some(b) => b,
            None => {
                self.allocated_bytes += bytes;
                Arc::new(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pooled"),
                    size: bytes,
                    usage: Tensor::usage(),
                    mapped_at_creation: false,
                }))
            }
        };
        Tensor::from_buffer(buf, shape)
    }

    /// Returns a tensor's buffer for reuse (see the module note on when that is safe).
    pub fn release(&mut self, t: Tensor) {
        let size = t.buffer().size();
        let buf = t.into_buffer();
        self.free.entry(size).or_default().push(buf);
    }

    /// Total bytes this pool has ever allocated: the peak of what it held at once.
    pub fn allocated_bytes(&self) -> u64 {
        self.allocated_bytes
    }
}
