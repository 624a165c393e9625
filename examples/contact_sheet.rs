//! Voxelises a mesh file (OBJ, OFF or PLY; default: a procedural chair) and renders it with
//! every reference shader into one contact-sheet PNG, the way a dependent crate would.
//!
//! `cargo run --example contact_sheet -- [MESH] [OUT.png]`

use rendernet::Gpu;
use rendernet::reference::{Light, Renderer, Shader, View};
use rendernet::voxel::{self, Mesh, VoxelizeOptions, shapes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let grid = match args.next() {
        Some(path) => voxel::voxelize(&Mesh::load(&path)?, &VoxelizeOptions::smooth(64))?,
        None => shapes::chair(0).to_grid(64)?,
    };
    let out = args.next().unwrap_or_else(|| "contact-sheet.png".into());
    let gpu = Gpu::new()?;
    let renderer = Renderer::new(&gpu);
    let s = 128u32;
    let mut sheet = image::RgbImage::new(s * Shader::ALL.len() as u32, s);
    for (i, shader) in Shader::ALL.into_iter().enumerate() {
        let img = renderer.render(&gpu, &grid, &View::default(), &Light::default(), shader, s)?;
        image::imageops::replace(&mut sheet, &img.to_rgb8(), (i as u32 * s) as i64, 0);
    }
    sheet.save(&out)?;
    let names: Vec<&str> = Shader::ALL.iter().map(|s| s.name()).collect();
    println!("wrote {out}: {}", names.join(", "));
    Ok(())
}
