//! A dense f32 tensor in one GPU storage buffer, row-major, NCDHW / NCHW by convention.

use super::Gpu;
use crate::error::{Error, Result};
use std::sync::Arc;

/// A shape-checked f32 tensor living in a GPU buffer, or in a range of one shared with
/// other tensors (a [`Tensor::view`]). Cloning shares the buffer.
#[derive(Clone)]
pub struct Tensor {
    buffer: Arc<wgpu::Buffer>,
    shape: Vec<usize>,
    /// Where the tensor starts in `buffer`, in bytes (0 unless a view).
    offset: u64,
    /// Whether it is a view: bound as its own range rather than the whole buffer.
    view: bool,
}

impl std::fmt::Debug for Tensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Tensor{:?}", self.shape)
    }
}

impl Tensor {
    /// A zero-filled tensor. Errors if the shape is empty, has a zero dimension, or is
    /// larger than one storage binding on this device.
    pub fn zeros(gpu: &Gpu, shape: &[usize]) -> Result<Tensor> {
        let bytes = Self::checked_bytes(gpu, shape)?;
        super::memo::note_created();
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: bytes,
            usage: Self::usage(),
            mapped_at_creation: false,
        });
        Ok(Tensor { buffer: Arc::new(buffer), shape: shape.to_vec(), offset: 0, view: false })
    }

    /// Uploads `data` as a tensor of `shape`; the element counts must agree.
    pub fn from_slice(gpu: &Gpu, shape: &[usize], data: &[f32]) -> Result<Tensor> {
        let bytes = Self::checked_bytes(gpu, shape)?;
        if data.len() as u64 * 4 != bytes {
            return Err(Error::Invalid(format!(
                "tensor data has {} values but shape {:?} needs {}",
                data.len(),
                shape,
                bytes / 4
            )));
        }
        super::memo::note_created();
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: bytes,
            usage: Self::usage(),
            mapped_at_creation: true,
        });
        buffer
            .slice(..)
            .get_mapped_range_mut()
            .map_err(|e| Error::Device(format!("mapping a new buffer failed: {e}")))?
            .copy_from_slice(bytemuck::cast_slice(data));
        buffer.unmap();
        Ok(Tensor { buffer: Arc::new(buffer), shape: shape.to_vec(), offset: 0, view: false })
    }

    /// Wraps an existing storage buffer (e.g. from a [`super::BufferPool`]) of at least
    /// `shape`'s size.
    pub fn from_buffer(buffer: Arc<wgpu::Buffer>, shape: &[usize]) -> Result<Tensor> {
        let need = shape.iter().product::<usize>() as u64 * 4;
        if shape.is_empty() || need == 0 || buffer.size() < need {
            return Err(Error::Invalid(format!(
                "buffer of {} bytes cannot hold a tensor of shape {shape:?}",
                buffer.size()
            )));
        }
        Ok(Tensor { buffer, shape: shape.to_vec(), offset: 0, view: false })
    }

    /// A tensor of `shape` at byte `offset` of `buffer`, which other tensors may share (the
    /// executor keeps all parameters, all their gradients and each Adam moment in one buffer
    /// apiece, so the optimizer updates them in one dispatch). `offset` must be a multiple of
    /// the device's storage offset alignment.
    pub fn view(buffer: Arc<wgpu::Buffer>, offset: u64, shape: &[usize]) -> Result<Tensor> {
        let need = shape.iter().product::<usize>() as u64 * 4;
        if shape.is_empty() || need == 0 || offset.checked_add(need).is_none_or(|end| end > buffer.size()) {
            return Err(Error::Invalid(format!(
                "a buffer of {} bytes cannot hold a tensor of shape {shape:?} at byte {offset}",
                buffer.size()
            )));
        }
        Ok(Tensor { buffer, shape: shape.to_vec(), offset, view: true })
    }

    /// Whether this tensor is a range of a buffer shared with others ([`Tensor::view`]).
    pub fn is_view(&self) -> bool {
        self.view
    }

    /// How a dispatch binds it: the whole buffer, or a view's own range.
    pub(crate) fn binding(&self) -> wgpu::BindingResource<'_> {
        if !self.view {
            return self.buffer.as_entire_binding();
        }
        let size = std::num::NonZeroU64::new(self.numel() as u64 * 4);
        wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: &self.buffer, offset: self.offset, size })
    }

    /// Where it starts in its buffer, in bytes.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// Overwrites the tensor's contents (queued; takes effect at the next submit, before
    /// the commands of that submit).
    pub fn write(&self, gpu: &Gpu, data: &[f32]) -> Result<()> {
        if data.len() != self.numel() {
            return Err(Error::Invalid(format!(
                "writing {} values into tensor of shape {:?} ({} values)",
                data.len(),
                self.shape,
                self.numel()
            )));
        }
        gpu.queue.write_buffer(&self.buffer, self.offset, bytemuck::cast_slice(data));
        Ok(())
    }

    /// Copies the tensor back to the host (one submit and wait).
    pub fn to_vec(&self, gpu: &Gpu) -> Result<Vec<f32>> {
        let bytes = self.numel() as u64 * 4;
        super::memo::note_created();
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.buffer, self.offset, &staging, 0, bytes);
        gpu.submit_and_wait(enc)?;
        read_staging(gpu, &staging)
    }

    /// The dimensions.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// Number of elements.
    pub fn numel(&self) -> usize {
        self.shape.iter().product()
    }

    /// Gives up the tensor, returning its (possibly shared) buffer.
    pub fn into_buffer(self) -> Arc<wgpu::Buffer> {
        self.buffer
    }

    /// The underlying buffer.
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Usage flags every tensor buffer carries (UNIFORM so that a kernel may read a tensor of
    /// at most 64 KiB through [`crate::gpu::Arg::U`]).
    pub(crate) fn usage() -> wgpu::BufferUsages {
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST
    }

    fn checked_bytes(gpu: &Gpu, shape: &[usize]) -> Result<u64> {
        if shape.is_empty() || shape.contains(&0) {
            return Err(Error::Invalid(format!("tensor shape {shape:?} has no elements")));
        }
        let n = shape
            .iter()
            .try_fold(1u64, |acc, &d| acc.checked_mul(d as u64))
            .and_then(|n| n.checked_mul(4))
            .ok_or_else(|| Error::Invalid(format!("tensor shape {shape:?} overflows")))?;
        gpu.check_binding_size(&format!("tensor {shape:?}"), n)?;
        Ok(n)
    }
}

/// Maps a MAP_READ buffer whose copy has been submitted and completed, and reads it as f32.
pub(crate) fn read_staging(gpu: &Gpu, staging: &wgpu::Buffer) -> Result<Vec<f32>> {
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Readback(e.to_string()))?;
    rx.recv().map_err(|e| Error::Readback(e.to_string()))?.map_err(|e| Error::Readback(e.to_string()))?;
    let view = slice.get_mapped_range().map_err(|e| Error::Readback(e.to_string()))?;
    let out = bytemuck::cast_slice(&view).to_vec();
    drop(view);
    staging.unmap();
    Ok(out)
}
