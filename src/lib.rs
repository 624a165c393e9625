//! rendernet: RenderNet (Nguyen-Phuoc et al., NeurIPS 2018), a differentiable neural
//! renderer from voxel grids to images, on wgpu compute shaders.
//!
//! The data's road: a voxel grid and a pose are resampled into a camera-aligned grid
//! ([`ops::resample`]), pass 3D convolutions ([`ops::conv`]), fold into 2D at the projection
//! unit ([`ops::projection`]), pass 2D convolutions and transposed convolutions, and come out
//! as images, optionally shaded by [`ops::phong`]. Every op has a forward and a backward
//! kernel so gradients reach weights, the grid, the pose and the light alike.
//!
//! Start with [`gpu::Gpu::new`], make [`gpu::Tensor`]s, and record ops into a compute pass.

pub mod bench;
pub mod chart;
pub mod data;
pub mod error;
pub mod gpu;
pub mod graph;
pub mod invert;
pub mod metrics;
pub mod nn;
pub mod ops;
pub mod reference;
pub mod rng;
pub mod stress;
pub mod train;
pub mod voxel;

pub use error::{Error, Result};
pub use gpu::{Gpu, Tensor};

/// The README's code blocks, compiled and run as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
