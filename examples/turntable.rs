//! A turntable: RenderNet renders a grid from N azimuths into one PNG strip.
//!
//! `cargo run --example turntable -- [FRAMES] [OUT.png]` (default 8 frames of a chair).

use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{Light, View};
use rendernet::voxel::shapes;
use rendernet::Gpu;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let frames: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(8).max(1);
    let out = args.next().unwrap_or_else(|| "turntable.png".into());
    let gpu = Gpu::new()?;
    let grid = shapes::chair(7).to_grid(64)?;
    let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128)?;
    let s = 128u32;
    let mut strip = image::RgbImage::new(s * frames as u32, s);
    for f in 0..frames {
        let view = View { azimuth: 360.0 * f as f64 / frames as f64, elevation: 70.0, radius: 3.5 };
        let img = net.render(&gpu, &grid, &view, &Light::default())?;
        let rgb = img.to_rgb8();
        image::imageops::replace(&mut strip, &rgb, (f as u32 * s) as i64, 0);
        println!("frame {}/{frames}", f + 1);
    }
    strip.save(&out)?;
    println!("wrote {out}");
    Ok(())
}
