//! A turntable: RenderNet renders a grid from N azimuths into one PNG strip.
//!
//! `cargo run --example turntable -- [FRAMES] [OUT.png]` (default 8 frames of a chair).

mod common;

use clap::Parser;
use rendernet::Gpu;
use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{Light, View, write_png};
use rendernet::voxel::shapes;
use std::path::PathBuf;
use std::process::ExitCode;

/// Renders a procedural chair from evenly spaced azimuths into one 128-pixel-high PNG strip.
#[derive(Parser)]
struct Args {
    /// Number of frames (azimuths), at least 1.
    #[arg(default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=360))]
    frames: u32,
    /// Where to write the PNG.
    #[arg(default_value = "turntable.png", value_parser = common::png_out)]
    out: PathBuf,
}


fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let gpu = Gpu::new()?;
    let grid = shapes::chair(7).to_grid(64)?;
    let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128)?;
    let (s, frames) = (128u32, a.frames);
    let mut strip = image::RgbImage::new(s * frames, s);
    for f in 0..frames {
        let view = View { azimuth: 360.0 * f as f64 / frames as f64, elevation: 70.0, radius: 3.5 };
        let img = net.render(&gpu, &grid, &view, &Light::default())?;
        image::imageops::replace(&mut strip, &img.to_rgb8(), (f * s) as i64, 0);
        println!("frame {}/{frames}", f + 1);
    }
    write_png(&image::DynamicImage::ImageRgb8(strip), &a.out)?;
    println!("wrote {}", a.out.display());
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
