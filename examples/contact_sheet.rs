//! Voxelises a mesh file (OBJ, OFF or PLY; default: a procedural chair) and renders it with
//! every reference shader (top row) and, below each, RenderNet with the shipped weights
//! for that shader (mid grey where none are shipped), into one contact-sheet PNG, the way a
//! dependent crate would.
//!
//! `cargo run --example contact_sheet -- [MESH] [OUT.png]`

mod common;

use clap::Parser;
use rendernet::Gpu;
use rendernet::nn::render::{Renderer, shipped_weights};
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{Light, RayMarcher, Shader, View, write_png};
use rendernet::voxel::{self, Mesh, VoxelizeOptions, shapes};
use std::path::PathBuf;
use std::process::ExitCode;

/// Renders a mesh (voxelised at 64^3) with every reference shader and every learned one.
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
    let mut sheet = image::RgbImage::from_pixel(s * Shader::ALL.len() as u32, 2 * s, image::Rgb([128, 128, 128]));
    let (view, light) = (View::default(), Light::default());
    let mut learned = Vec::new();
    for (i, shader) in Shader::ALL.into_iter().enumerate() {
        let img = renderer.render(&gpu, &grid, &view, &light, shader, s)?;
        image::imageops::replace(&mut sheet, &img.to_rgb8(), (i as u32 * s) as i64, 0);
        if let Some(w) = shipped_weights(&Preset::tiny(), shader) {
            let mut net = Renderer::for_shader(&gpu, Preset::tiny(), shader, w, "embedded", s as usize)?;
            let img = net.render(&gpu, &grid, &view, &light)?;
            image::imageops::replace(&mut sheet, &img.to_rgb8(), (i as u32 * s) as i64, s as i64);
            learned.push(shader.name());
        }
    }
    write_png(&image::DynamicImage::ImageRgb8(sheet), &a.out)?;
    let names: Vec<&str> = Shader::ALL.iter().map(|s| s.name()).collect();
    println!("wrote {}: reference {} (top); RenderNet {} (below)", a.out.display(), names.join(", "), learned.join(", "));
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
