//! Render a voxel grid with RenderNet from code, the way a dependent crate would.
//!
//! `cargo run --example render -- [GRID.binvox|.safetensors] [OUT.png]`
//! (default: a procedural chair, `render-example.png`).

use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{Light, View};
use rendernet::voxel::{Binvox, shapes, safetensors_io};
use rendernet::Gpu;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let grid = match args.next() {
        Some(p) if p.ends_with(".binvox") => Binvox::read(&p)?.grid,
        Some(p) => safetensors_io::read(&p)?,
        None => shapes::chair(42).to_grid(64)?,
    };
    let out = args.next().unwrap_or_else(|| "render-example.png".into());
    let gpu = Gpu::new()?;
    let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128)?;
    let view = View { azimuth: 45.0, elevation: 75.0, radius: 3.6 };
    let image = net.render(&gpu, &grid, &view, &Light::default())?;
    image.save_png(&out)?;
    println!("wrote {out}");
    Ok(())
}
