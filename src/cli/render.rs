//! `rendernet render`: the main job. A voxel grid through trained RenderNet to a PNG.

use super::truth::{SceneArgs, load};
use clap::Args;
use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::Preset;
use rendernet::ops::loss::psnr_from_mse;
use rendernet::reference::{self, Image, Options, Shader};
use rendernet::{Error, Gpu, Result};
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `rendernet render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Weights (safetensors from `rendernet train`); default: the embedded tiny Phong weights.
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Network size the weights belong to.
    #[arg(long, default_value = "tiny")]
    preset: String,
    /// Image side in pixels (a multiple of 8 for the tiny preset).
    #[arg(long, default_value_t = 128)]
    size: usize,
    /// Also render the reference renderer's image, write it beside the network's, and print
    /// the PSNR between them.
    #[arg(long)]
    compare: bool,
    /// Where to write the PNG.
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
}

fn side_by_side(a: &Image, b: &Image) -> Image {
    let s = a.size;
    let mut data = Vec::with_capacity(3 * s * 2 * s);
    for c in 0..3 {
        for y in 0..s {
            data.extend((0..s).map(|x| a.get(c.min(a.channels - 1), y, x)));
            data.extend((0..s).map(|x| b.get(c.min(b.channels - 1), y, x)));
        }
    }
    // A two-wide strip is stored as a 2s x s image: rows of 2s values.
    Image { channels: 3, size: s, data }
}

/// Loads the grid and weights, renders, writes the PNG and reports timings.
pub fn run(a: RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    let (grid, what) = load(&a.scene)?;
    let gpu = Gpu::new()?;
    let preset = Preset::by_name(&a.preset)?;
    let (bytes, name) = match &a.weights {
        Some(p) => (std::fs::read(p).map_err(|e| Error::Io { path: p.display().to_string(), source: e })?, p.display().to_string()),
        None => (TINY_PHONG_WEIGHTS.to_vec(), "embedded tiny-phong weights".to_string()),
    };
    let mut net = Renderer::new(&gpu, preset, &bytes, &name, a.size)?;
    let (view, light) = (a.scene.view(), a.scene.light());
    let t1 = Instant::now();
    let img = net.render(&gpu, &grid, &view, &light)?;
    let render_s = t1.elapsed().as_secs_f64();
    if a.compare {
        let opts = Options { supersample: 2, ..Options::default() };
        let truth = reference::Renderer::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, a.size as u32)?;
        let mse = img.data.iter().zip(&truth.data).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / img.data.len() as f64;
        println!("PSNR against the reference renderer: {:.2} dB", psnr_from_mse(mse as f32, 1.0));
        save_wide(&side_by_side(&img, &truth), &a.out)?;
    } else {
        img.save_png(&a.out)?;
    }
    println!("rendered {} with {name}", a.scene.describe(&what));
    println!(
        "wrote {} in {:.2} s (network forward {:.2} s, on {})",
        a.out.display(),
        t0.elapsed().as_secs_f64(),
        render_s,
        gpu.info.name
    );
    Ok(())
}

fn save_wide(img: &Image, path: &std::path::Path) -> Result<()> {
    let (w, h) = (2 * img.size as u32, img.size as u32);
    let plane = (w * h) as usize;
    let buf = image::RgbImage::from_fn(w, h, |x, y| {
        let i = (y * w + x) as usize;
        image::Rgb(std::array::from_fn(|c| (img.data[c * plane + i].clamp(0.0, 1.0) * 255.0).round() as u8))
    });
    buf.save(path).map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))
}
