//! `rendernet stress`: sweeps of corrupted, coarse, crowded and extreme scenes through
//! RenderNet and the reference renderer, scored against the clean scene (library:
//! `rendernet::stress`).

use super::truth::{SceneArgs, load};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::Preset;
use rendernet::reference;
use rendernet::stress::{self, Row};
use rendernet::{Error, Gpu, Result};
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `rendernet stress`.
#[derive(Args, Debug)]
pub struct StressArgs {
    /// The clean scene (default: the bunny at the default view and light).
    #[command(flatten)]
    scene: SceneArgs,
    /// Weights of a Phong RenderNet; default: the embedded tiny Phong weights.
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Network size the weights belong to.
    #[arg(long, default_value = "tiny")]
    preset: String,
    /// Seed of the random corruptions.
    #[arg(long, default_value_t = 0)]
    noise_seed: u64,
    /// Contact sheet: per sweep, a row of RenderNet images and a row of reference images of
    /// the corrupted grid, one column per level.
    #[arg(long, default_value = "stress.png")]
    out: PathBuf,
    /// Print JSON rows (sweep, level, label, method, scores) instead of tables.
    #[arg(long)]
    json: bool,
}

/// Runs the sweeps, prints the tables or JSON, writes the contact sheet.
pub fn run(a: StressArgs) -> Result<()> {
    let t0 = Instant::now();
    super::output::check_png_out(&a.out)?;
    let preset = Preset::by_name(&a.preset)?;
    let size = preset.image_for(preset.cam);
    a.scene.validate(size)?;
    let (grid, what) = load(&a.scene)?;
    let gpu = Gpu::new()?;
    let (bytes, name) = match &a.weights {
        Some(p) => (std::fs::read(p).map_err(|e| Error::Io { path: p.display().to_string(), source: e })?, p.display().to_string()),
        None => (TINY_PHONG_WEIGHTS.to_vec(), "embedded tiny-phong weights".to_string()),
    };
    let mut net = Renderer::new(&gpu, preset, &bytes, &name, size)?;
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} scenes [{elapsed_precise}]").expect("static template"));
    let rows = stress::run(&gpu, &mut net, &grid, &a.scene.view(), &a.scene.light(), a.noise_seed, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    reference::write_png(&image::DynamicImage::ImageRgb8(contact_sheet(&rows, size)), &a.out)?;
    if a.json {
        let j: Vec<serde_json::Value> = rows
            .iter()
            .map(|r| {
                serde_json::json!({
                    "sweep": r.sweep, "level": r.level, "label": r.label, "method": r.method,
                    "object_psnr": r.scores.object_psnr, "psnr": r.scores.psnr, "ssim": r.scores.ssim, "iou": r.scores.iou,
                })
            })
            .collect();
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    println!("{} with {name}; scores against the reference image of the clean scene", a.scene.describe(&what));
    let mut sweep = "";
    for pair in rows.chunks(2) {
        let (ours, theirs) = (&pair[0], &pair[1]);
        if ours.sweep != sweep {
            sweep = ours.sweep;
            println!("\n{sweep}: {:<16} {:>22} {:>22}", "level", "RenderNet obj/full/SSIM", "reference obj/full/SSIM");
        }
        let s = |r: &Row| format!("{:5.2} {:5.2} {:.3}", r.scores.object_psnr, r.scores.psnr, r.scores.ssim);
        println!("  {:<22} {:>22} {:>22}", ours.label, s(ours), s(theirs));
    }
    println!("\nwrote {} in {:.1} s on {}", a.out.display(), t0.elapsed().as_secs_f64(), gpu.info.name);
    Ok(())
}

/// Per sweep two rows (RenderNet, then the reference renderer on the same corrupted grid),
/// one column per level.
fn contact_sheet(rows: &[Row], size: usize) -> image::RgbImage {
    let mut sweeps: Vec<&str> = Vec::new();
    for r in rows {
        if !sweeps.contains(&r.sweep) {
            sweeps.push(r.sweep);
        }
    }
    let cols = sweeps.iter().map(|s| rows.iter().filter(|r| r.sweep == *s).count() / 2).max().unwrap_or(1);
    let mut sheet = image::RgbImage::new((cols * size) as u32, (2 * sweeps.len() * size) as u32);
    for (si, s) in sweeps.iter().enumerate() {
        for (k, r) in rows.iter().filter(|r| r.sweep == *s).enumerate() {
            let (col, row) = (k / 2, 2 * si + usize::from(r.method != "rendernet"));
            image::imageops::replace(&mut sheet, &r.image.to_rgb8(), (col * size) as i64, (row * size) as i64);
        }
    }
    sheet
}
