//! Seeded inverted dropout (binds `shaders/dropout.wgsl`). In evaluation mode the caller
//! skips it (identity); in training each step passes a fresh seed, and backward the same one.

use super::elementwise;
use crate::error::{Error, Result};
use crate::gpu::{Arg, Gpu, Shader, Tensor, wgsl};

const SHADER: Shader = wgsl!("dropout");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    seed: u32,
    threshold: u32,
    scale: f32,
}

/// Dropout that keeps each value with probability `keep_prob` and scales kept ones by
/// `1 / keep_prob`, with the mask a pure function of `(seed, index)`.
#[derive(Clone, Copy, Debug)]
pub struct Dropout {
    /// Probability of keeping a value, in (0, 1].
    pub keep_prob: f32,
}

impl Dropout {
    fn params(&self, n: usize, seed: u32) -> Result<Params> {
        if !(self.keep_prob > 0.0 && self.keep_prob <= 1.0) {
            return Err(Error::Invalid(format!("dropout keep_prob {} must be in (0, 1]", self.keep_prob)));
        }
        // keep_prob = 1 saturates the threshold at u32::MAX, which the kernel reads as
        // "keep all" (evaluation mode runs the same graph with keep_prob 1).
        let threshold = (self.keep_prob as f64 * 4294967296.0).min(u32::MAX as f64) as u32;
        Ok(Params { n: n as u32, seed, threshold, scale: 1.0 / self.keep_prob })
    }

    /// `y = x * mask(seed) / keep_prob`.
    pub fn forward(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, seed: u32, x: &Tensor, y: &Tensor) -> Result<()> {
        let p = self.params(x.numel(), seed)?;
        elementwise(gpu, pass, SHADER, "dropout_apply", &p, &[Arg::R(x), Arg::W(y)], x.numel())
    }

    /// `dx = dy * mask(seed) / keep_prob`, the same mask as the forward with this seed.
    pub fn backward(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, seed: u32, dy: &Tensor, dx: &Tensor) -> Result<()> {
        let p = self.params(dy.numel(), seed)?;
        elementwise(gpu, pass, SHADER, "dropout_apply", &p, &[Arg::R(dy), Arg::W(dx)], dy.numel())
    }
}
