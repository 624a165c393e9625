//! Voxelises a mesh (.obj, .off, .ply) into a solid `N^3` grid file, the way
//! `datasets/fetch_real.sh` makes the committed fixtures: `.binvox` is binary (binvox's
//! conservative voxelisation); `.safetensors` is anti-aliased (`VoxelizeOptions::smooth`,
//! fractional occupancy at the surface, stored as u8 x 255).
//!
//! `cargo run --example voxelize -- MESH N OUT.binvox|OUT.safetensors`

mod common;

use clap::Parser;
use rendernet::voxel::{Binvox, Mesh, VoxelizeOptions, safetensors_io, voxelize};
use std::path::PathBuf;
use std::process::ExitCode;

/// Voxelises a mesh into a solid N^3 grid: .binvox binary, .safetensors anti-aliased.
#[derive(Parser)]
struct Args {
    /// Mesh to voxelise (.obj, .off or .ply).
    mesh: PathBuf,
    /// Grid side N.
    #[arg(value_parser = clap::value_parser!(u32).range(1..))]
    n: u32,
    /// Output grid: a .binvox or .safetensors name.
    out: PathBuf,
}

fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let ext = a.out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext != "binvox" && ext != "safetensors" {
        return Err(format!("{}: the output must end in .binvox or .safetensors", a.out.display()).into());
    }
    let mesh = Mesh::load(&a.mesh)?;
    let (n, out) = (a.n as usize, a.out.display());
    if ext == "safetensors" {
        let grid = voxelize(&mesh, &VoxelizeOptions::smooth(n))?;
        let filled = grid.fill_fraction();
        safetensors_io::write_u8(&grid, &a.out)?;
        println!("wrote {out} ({n}^3 anti-aliased, {:.1}% filled)", 100.0 * filled);
        return Ok(());
    }
    let grid = voxelize(&mesh, &VoxelizeOptions { resolution: n, ..Default::default() })?;
    let filled = grid.fill_fraction();
    Binvox::from_grid(grid).write(&a.out)?;
    println!("wrote {out} ({n}^3, {:.1}% filled)", 100.0 * filled);
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
