//! One entry point for every scene file: voxel grids as stored, meshes voxelised.

use super::{Binvox, Mesh, VoxelError, VoxelGrid, VoxelizeOptions, safetensors_io, vox, voxelize};
use std::path::Path;

/// The Stanford bunny (public domain) voxelised anti-aliased at 64^3 (u8 occupancy,
/// `VoxelizeOptions::smooth(64)`): the CLI's default scene, a shape no training set contains.
pub const BUNNY64: &[u8] = include_bytes!("../../datasets/fixtures/bunny64.safetensors");

/// [`BUNNY64`] as a grid.
pub fn bunny() -> VoxelGrid {
    safetensors_io::from_bytes(BUNNY64, "embedded bunny64.safetensors").expect("the embedded bunny is a valid grid")
}

/// The extensions [`load`] reads (lower case).
pub const EXTENSIONS: [&str; 6] = ["binvox", "safetensors", "vox", "obj", "off", "ply"];

/// Loads any scene file, chosen by extension (case-insensitive): `.binvox`, `.safetensors`
/// and MagicaVoxel `.vox` grids as stored; `.obj`, `.off` and `.ply` meshes voxelised
/// anti-aliased (binary occupancy renders as stair-steps) into a `resolution`^3 grid.
pub fn load(path: impl AsRef<Path>, resolution: usize) -> Result<VoxelGrid, VoxelError> {
    let path = path.as_ref();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "binvox" => Ok(Binvox::read(path)?.grid),
        "safetensors" => safetensors_io::read(path),
        "vox" => vox::read(path),
        "obj" | "off" | "ply" => voxelize(&Mesh::load(path)?, &VoxelizeOptions::smooth(resolution)),
        _ => Err(VoxelError::Invalid {
            what: path.display().to_string(),
            msg: "unknown extension; expected .binvox, .safetensors, .vox, .obj, .off or .ply".into(),
        }),
    }
}
