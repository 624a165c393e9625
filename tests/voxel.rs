//! Voxel module: file formats, mesh loaders, voxeliser, resampling and procedural shapes.
//! Grids stay at or below 64^3 so the whole file runs in about a second.

use glam::{Mat3, Vec3};
use rendernet::voxel::voxelize::{Normalization, fill_from_outside};
use rendernet::voxel::{
    Binvox, Family, Mesh, VoxelError, VoxelGrid, VoxelizeOptions, safetensors_io, shapes, voxelize,
};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rendernet-voxel-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Asserts that a result is an error whose message names `file`, and returns the message.
fn err_naming<T: std::fmt::Debug>(r: Result<T, VoxelError>, file: &str) -> String {
    let msg = r.expect_err("malformed input must be rejected").to_string();
    assert!(msg.contains(file), "error {msg:?} does not name {file:?}");
    msg
}

/// A grid with an irregular pattern, so axis mix-ups cannot cancel out.
fn pattern_grid(dims: [usize; 3]) -> VoxelGrid {
    let n = dims.iter().product::<usize>();
    let occ = (0..n)
        .map(|i| ((i * 7919 + i / 3) % 5 < 2) as u8 as f32)
        .collect();
    VoxelGrid::new(dims, occ).unwrap()
}

#[path = "voxel/formats.rs"]
mod formats;
#[path = "voxel/geometry.rs"]
mod geometry;
