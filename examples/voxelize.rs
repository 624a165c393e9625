//! Voxelises a mesh (.obj, .off, .ply) into a solid `N^3` binvox file, the way
//! `datasets/fetch_real.sh` makes the committed fixtures.
//!
//! `cargo run --example voxelize -- MESH N OUT.binvox`

use rendernet::voxel::{Binvox, Mesh, VoxelizeOptions, voxelize};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [mesh, n, out] = args.as_slice() else {
        return Err("usage: voxelize MESH N OUT.binvox".into());
    };
    let mesh = Mesh::load(mesh)?;
    let grid = voxelize(
        &mesh,
        &VoxelizeOptions {
            resolution: n.parse()?,
            ..Default::default()
        },
    )?;
    let filled = grid.fill_fraction();
    Binvox::from_grid(grid).write(out)?;
    println!("wrote {out} ({n}^3, {:.1}% filled)", 100.0 * filled);
    Ok(())
}
