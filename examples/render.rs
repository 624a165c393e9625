//! Render a voxel grid with RenderNet from code, the way a dependent crate would.
//!
//! `cargo run --example render -- [GRID.binvox|.safetensors] [OUT.png]`
//! (default: a procedural chair, `render-example.png`).

mod common;

use clap::Parser;
use rendernet::Gpu;
use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{Light, View};
use rendernet::voxel::{Binvox, safetensors_io, shapes};
use std::path::PathBuf;
use std::process::ExitCode;

/// Renders a voxel grid with the embedded RenderNet weights to a 128-pixel PNG.
#[derive(Parser)]
struct Args {
    /// Voxel grid (.binvox or .safetensors); default: a procedural chair.
    grid: Option<PathBuf>,
    /// Where to write the PNG.
    #[arg(default_value = "render-example.png", value_parser = common::png_out)]
    out: PathBuf,
}


fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let grid = match &a.grid {
        Some(p) if p.extension().is_some_and(|e| e == "binvox") => Binvox::read(p)?.grid,
        Some(p) => safetensors_io::read(p)?,
        None => shapes::chair(42).to_grid(64)?,
    };
    let gpu = Gpu::new()?;
    let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128)?;
    let view = View { azimuth: 45.0, elevation: 75.0, radius: 3.6 };
    let image = net.render(&gpu, &grid, &view, &Light::default())?;
    image.save_png(&a.out)?;
    println!("wrote {}", a.out.display());
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
