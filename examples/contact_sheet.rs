//! Voxelises a mesh file (OBJ, OFF or PLY; default: a procedural chair) and renders it with
//! every reference shader into one contact-sheet PNG, the way a dependent crate would.
//!
//! `cargo run --example contact_sheet -- [MESH] [OUT.png]`

mod common;

use clap::Parser;
use rendernet::Gpu;
use rendernet::reference::{Light, RayMarcher, Shader, View, write_png};
use rendernet::voxel::{self, Mesh, VoxelizeOptions, shapes};
use std::path::PathBuf;
use std::process::ExitCode;

/// Renders a mesh (voxelised at 64^3) with every reference shader into one PNG row.
#[derive(Parser)]
struct Args {
    /// Mesh (.obj, .off or .ply); default: a procedural chair.
    mesh: Option<PathBuf>,
    /// Where to write the PNG.
    #[arg(default_value = "contact-sheet.png", value_parser = common::png_out)]
    out: PathBuf,
}


fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let grid = match &a.mesh {
        Some(path) => voxel::voxelize(&Mesh::load(path)?, &VoxelizeOptions::smooth(64))?,
        None => shapes::chair(0).to_grid(64)?,
    };
    let gpu = Gpu::new()?;
    let renderer = RayMarcher::new(&gpu);
    let s = 128u32;
    let mut sheet = image::RgbImage::new(s * Shader::ALL.len() as u32, s);
    for (i, shader) in Shader::ALL.into_iter().enumerate() {
        let img = renderer.render(&gpu, &grid, &View::default(), &Light::default(), shader, s)?;
        image::imageops::replace(&mut sheet, &img.to_rgb8(), (i as u32 * s) as i64, 0);
    }
    write_png(&image::DynamicImage::ImageRgb8(sheet), &a.out)?;
    let names: Vec<&str> = Shader::ALL.iter().map(|s| s.name()).collect();
    println!("wrote {}: {}", a.out.display(), names.join(", "));
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
