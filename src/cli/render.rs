//! `rendernet render`: the main job. A voxel grid through trained RenderNet to a PNG.

use super::truth::{SceneArgs, load};
use clap::Args;
use super::weights::{Loaded, MANY_RENDERS};
use rendernet::nn::render::{CROP_MARGIN, Renderer, SHIPPED, most_accurate_shipped};
use rendernet::metrics::Scores;
use rendernet::reference::{self, Image, Options, Shader};
use rendernet::{Gpu, Result};
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `rendernet render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    net: super::weights::WeightsArgs,
    /// The shader the weights were trained for: phong (default; embedded weights) or, with
    /// --weights from a dataset made with that --shader, albedo, normal, depth, mask, toon,
    /// contour or ao. --compare renders the same shader with the reference.
    #[arg(long, default_value = "phong", value_parser = super::truth::parse_shader)]
    shader: Shader,
    /// Image side in pixels (a multiple of 8 for the tiny preset). Above the side the network
    /// was trained at (128 for the shipped weights) it draws at that side and the image is
    /// upscaled: drawn at a denser camera grid than it learned, its picture falls apart.
    #[arg(long, default_value_t = 128, allow_negative_numbers = true)]
    size: usize,
    /// Also render the reference renderer's image, write it beside the network's, and print
    /// full-frame PSNR, object PSNR, SSIM and mask IoU, each beside an all-black image's.
    #[arg(long)]
    compare: bool,
    /// Where to write the PNG (a .png name; written atomically).
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    /// Run the network on the whole camera grid instead of the window around the object
    /// (the default crops empty space away; the picture changes by < 0.05 dB).
    #[arg(long)]
    no_crop: bool,
    /// Camera voxels of context kept around the object when cropping (each is 2 pixels for
    /// the tiny preset).
    #[arg(long, default_value_t = CROP_MARGIN)]
    crop_margin: usize,
}

/// Loads the grid and weights, renders, writes the PNG and reports timings.
pub fn run(a: RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    a.scene.validate(a.size)?;
    super::output::check_png_out(&a.out)?;
    let (grid, what) = load(&a.scene)?;
    let gpu = Gpu::new()?;
    let coloured = grid.colour().is_some();
    // Render draws one image: the most accurate shipped model is worth its cost here.
    let default = most_accurate_shipped(a.shader, coloured).unwrap_or(MANY_RENDERS);
    let Loaded { preset, bytes, name } = a.net.resolve(a.shader, coloured, default)?;
    let net_preset = preset.name;
    let mut net = Renderer::for_shader(&gpu, preset, a.shader, &bytes, &name, a.size)?.with_crop_margin((!a.no_crop).then_some(a.crop_margin));
    let (view, light) = (a.scene.view(), a.scene.light());
    let t1 = Instant::now();
    let img = net.render(&gpu, &grid, &view, &light)?;
    let render_s = t1.elapsed().as_secs_f64();
    if a.compare {
        let opts = Options { supersample: 2, ..Options::default() };
        let truth = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, a.shader, a.size as u32)?;
        let bg = a.shader.background();
        println!("against the reference renderer: {}", compare_line(&Scores::on_background(&img, &truth, bg), &Scores::background_floor(&truth, bg), rendernet::metrics::floor_name(bg)));
        save_pair(&img, &truth, &a.out)?;
    } else {
        img.save_png(&a.out)?;
    }
    let measured = SHIPPED.iter().find(|m| a.net.weights.is_none() && !coloured && a.shader == Shader::Phong && m.preset == net_preset).map(|m| format!(" (held-out object PSNR {:.2} dB)", m.object_psnr));
    println!("rendered {} with {name}{}", a.scene.describe(&what), measured.unwrap_or_default());
    println!(
        "wrote {} in {:.2} s (network forward {:.2} s, on {})",
        a.out.display(),
        t0.elapsed().as_secs_f64(),
        render_s,
        gpu.info.name
    );
    Ok(())
}

/// The network's image and the reference's, side by side in one PNG.
fn save_pair(net: &Image, truth: &Image, path: &std::path::Path) -> Result<()> {
    reference::write_png(&image::DynamicImage::ImageRgb8(Image::side_by_side(&[net, truth])?), path)
}

/// The four scores, each beside the background-only image's (all-black, or all-white for
/// contours; full-frame PSNR flatters it most).
fn compare_line(s: &Scores, black: &Scores, floor: &str) -> String {
    format!(
        "full-frame PSNR {:.2} dB ({floor} {:.2}), object PSNR {:.2} dB ({floor} {:.2}), SSIM {:.3} ({floor} {:.3}), mask IoU {:.3} ({floor} {:.3})",
        s.psnr, black.psnr, s.object_psnr, black.object_psnr, s.ssim, black.ssim, s.iou, black.iou
    )
}
