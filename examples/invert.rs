//! Inverse rendering of an unseen chair from one image: shape, camera and light together,
//! through the shipped RenderNet and the shipped chair prior.
//!
//! `cargo run --release --example invert -- [SEED] [OUT.png]`: the reference renderer draws
//! procedural chair SEED (not one the prior was trained on) at a fixed view and light; the
//! search recovers them from that image alone. The PNG shows the input, the network's
//! render at the estimate, and the recovered and true shapes seen from 90 degrees further
//! round.

mod common;

use clap::Parser;
use rendernet::Gpu;
use rendernet::invert::{InvertOptions, Inverter, ShapeOptions, angle_between, light_direction, view_direction};
use rendernet::nn::prior::{PRIOR_CHAIRS_WEIGHTS, PriorPreset};
use rendernet::nn::render::TINY_PHONG_WEIGHTS;
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{Image, Light, RayMarcher, Shader, View, write_png};
use rendernet::voxel::shapes;
use std::path::PathBuf;
use std::process::ExitCode;

/// Recovers a chair's shape, camera and light from one reference image.
#[derive(Parser)]
struct Args {
    /// Seed of the procedural chair (the prior trained on seed 21's chairs).
    #[arg(default_value_t = 900_001)]
    seed: u64,
    /// Where to write the PNG.
    #[arg(default_value = "invert.png", value_parser = common::png_out)]
    out: PathBuf,
}

fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let gpu = Gpu::new()?;
    let truth = shapes::chair(a.seed).to_grid(32)?;
    let (view, light) = (View { azimuth: 40.0, elevation: 70.0, radius: 3.3 }, Light { azimuth: 30.0, elevation: 60.0, ..Light::default() });
    let rm = RayMarcher::new(&gpu);
    let target = rm.render(&gpu, &truth, &view, &light, Shader::Phong, 128)?;
    let inv = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", Light::default())?;
    let t = std::time::Instant::now();
    let est = inv.invert_unknown_shape(&gpu, &PriorPreset::small(), PRIOR_CHAIRS_WEIGHTS, &target, &InvertOptions::default(), &ShapeOptions::default(), 2, |r, n| {
        println!("round {r}/{n} done ({:.0} s)", t.elapsed().as_secs_f64())
    })?;
    let turned = |v: &View| View { azimuth: v.azimuth + 90.0, ..*v };
    let mine = rm.render(&gpu, &est.shape.grid, &turned(&est.pose.view), &est.pose.light, Shader::Phong, 128)?;
    let theirs = rm.render(&gpu, &truth, &turned(&view), &light, Shader::Phong, 128)?;
    write_png(&image::DynamicImage::ImageRgb8(Image::side_by_side(&[&target, &est.pose.image, &mine, &theirs])?), &a.out)?;
    println!(
        "camera direction off by {:.1} deg, light by {:.1} deg, voxel IoU {:.3}",
        angle_between(view_direction(&view), view_direction(&est.pose.view)),
        angle_between(light_direction(&light), light_direction(&est.pose.light)),
        est.shape.grid.iou(&truth).unwrap_or(0.0)
    );
    println!("wrote {} (input | network at the estimate | recovered shape | true shape, both turned 90 degrees)", a.out.display());
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
