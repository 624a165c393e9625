//! rendernet: RenderNet (Nguyen-Phuoc et al., NeurIPS 2018), a differentiable neural
//! renderer from voxel grids to images, on wgpu compute shaders.
//!
//! The data's road: a voxel grid and a pose are resampled into a camera-aligned grid
//! ([`ops::resample`]), pass 3D convolutions ([`ops::conv`]), fold into 2D at the projection
//! unit ([`ops::projection`]), pass 2D convolutions and transposed convolutions, and come out
//! as images, optionally shaded by [`ops::phong`]. Every op has a forward and a backward
//! kernel so gradients reach weights, the grid, the pose and the light alike.
//!
//! The one path for most users, all at the crate root: load a scene ([`load`] any voxel or
//! mesh file, or the embedded [`bunny`]), render it with the network ([`Renderer`], weights
//! [`TINY_PHONG_WEIGHTS`]) or the conventional reference ([`RayMarcher`]) from a [`View`]
//! under a [`Light`], and save the [`Image`]:
//!
//! ```no_run
//! use rendernet::{Gpu, Light, Preset, RayMarcher, Renderer, Shader, View, TINY_PHONG_WEIGHTS};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let gpu = Gpu::new()?;
//! let grid = rendernet::load("chair.obj", 64)?; // .binvox .safetensors .vox .obj .off .ply
//! let (view, light) = (View::default(), Light::default());
//! let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128)?;
//! net.render(&gpu, &grid, &view, &light)?.save_png("net.png")?;
//! let truth = RayMarcher::new(&gpu).render(&gpu, &grid, &view, &light, Shader::Phong, 128)?;
//! truth.save_png("reference.png")?;
//! # Ok(()) }
//! ```
//!
//! Below that: [`gpu::Tensor`]s and ops recorded into a compute pass ([`ops`]), graphs with
//! autodiff ([`graph`]), training ([`train`]), inverse rendering ([`invert`]).

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
pub use nn::render::{Renderer, TINY_AO_WEIGHTS, TINY_CONTOUR_WEIGHTS, TINY_PHONG_WEIGHTS, TINY_TOON_WEIGHTS};
pub use nn::rendernet::Preset;
pub use reference::{Image, Light, RayMarcher, Shader, View};
pub use voxel::{VoxelGrid, bunny, load};

/// The README's code blocks, compiled and run as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
