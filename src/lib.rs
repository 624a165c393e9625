//! RenderNet: a differentiable neural renderer for voxel grids, built on wgpu.

pub mod voxel;
