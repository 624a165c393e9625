//! Voxelises a mesh (.obj, .off, .ply) into a solid `N^3` grid file, the way
//! `datasets/fetch_real.sh` makes the committed fixtures: `.binvox` is binary (binvox's
//! conservative voxelisation); `.safetensors` is anti-aliased (`VoxelizeOptions::smooth`,
//! fractional occupancy at the surface, stored as u8 x 255).
//!
//! `cargo run --example voxelize -- MESH N OUT.binvox|OUT.safetensors`

use rendernet::voxel::{Binvox, Mesh, VoxelizeOptions, safetensors_io, voxelize};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [mesh, n, out] = args.as_slice() else {
        return Err("usage: voxelize MESH N OUT.binvox|OUT.safetensors".into());
    };
    let mesh = Mesh::load(mesh)?;
    let n: usize = n.parse()?;
    if out.ends_with(".safetensors") {
        let grid = voxelize(&mesh, &VoxelizeOptions::smooth(n))?;
        let filled = grid.fill_fraction();
        safetensors_io::write_u8(&grid, out)?;
        println!("wrote {out} ({n}^3 anti-aliased, {:.1}% filled)", 100.0 * filled);
        return Ok(());
    }
    let grid = voxelize(&mesh, &VoxelizeOptions { resolution: n, ..Default::default() })?;
    let filled = grid.fill_fraction();
    Binvox::from_grid(grid).write(out)?;
    println!("wrote {out} ({n}^3, {:.1}% filled)", 100.0 * filled);
    Ok(())
}
