//! `rendernet eval-texture`: texture recovery through the texture decoder on painted
//! procedural shapes, camera and light known, scored from a view no input image had
//! (library: `rendernet::invert::evaluate_textures`).

use super::weights::{Loaded, MANY_RENDERS};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rendernet::invert::{Inverter, TextureOptions, evaluate_textures};
use rendernet::nn::texture::TexturePreset;
use rendernet::reference::{Light, Shader};
use rendernet::train::eval::Interval;
use rendernet::{Error, Gpu, Result};
use std::path::{Path, PathBuf};

/// `--texture FILE`: the texture decoder's weights.
#[derive(Args, Debug)]
pub struct TextureSearchArgs {
    /// Texture decoder weights from `rendernet train-texture` (`<out>.weights.safetensors`);
    /// the shipped decoder without it.
    #[arg(long = "texture-weights", value_name = "FILE")]
    pub texture_weights: Option<PathBuf>,
    /// Adam steps on the texture code per refined start.
    #[arg(long, default_value_t = TextureOptions::default().steps)]
    pub texture_steps: usize,
    /// Paints of the training distribution scored as starting texture codes.
    #[arg(long = "texture-starts", value_name = "N", default_value_t = TextureOptions::default().candidates)]
    pub candidates: usize,
    /// Best-scoring texture starts refined by Adam.
    #[arg(long = "texture-keep", value_name = "N", default_value_t = TextureOptions::default().keep)]
    pub keep: usize,
}

impl TextureSearchArgs {
    /// The search settings these flags give.
    pub fn options(&self) -> TextureOptions {
        TextureOptions { steps: self.texture_steps, candidates: self.candidates, keep: self.keep, ..TextureOptions::default() }
    }

    /// The decoder's weights and a name for messages.
    pub fn load(&self) -> Result<(Vec<u8>, String)> {
        load_texture(self.texture_weights.as_deref())
    }
}

/// Texture decoder weights from `path`, or the shipped ones.
pub fn load_texture(path: Option<&Path>) -> Result<(Vec<u8>, String)> {
    let Some(path) = path else {
        return Ok((rendernet::nn::texture::TEXTURE_SMALL_WEIGHTS.to_vec(), "the shipped texture decoder".into()));
    };
    let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.display().to_string(), source: e })?;
    Ok((bytes, path.display().to_string()))
}

/// The coloured RenderNet of `net` (its shipped colour weights without --weights).
pub fn colour_inverter(net: &super::weights::WeightsArgs) -> Result<(Inverter, String)> {
    let Loaded { preset, bytes, name } = net.resolve(Shader::Phong, true, MANY_RENDERS)?;
    if !rendernet::nn::render::weights_take_colour(&bytes, &name)? {
        return Err(Error::Invalid(format!(
            "{name} take grey grids; texture recovery needs a network trained on coloured voxels (shipped for --preset tiny; or --weights from `rendernet train` on a `dataset --colour` set)"
        )));
    }
    Ok((Inverter::new(preset.with_colour(), &bytes, &name, Light::default())?, name))
}

/// Flags of `rendernet eval-texture`.
#[derive(Args, Debug)]
pub struct EvalTextureArgs {
    /// Painted shapes (the four families of `dataset --shapes mixed` in turn, each with a
    /// paint the decoder never trained on).
    #[arg(long, default_value_t = 16)]
    samples: usize,
    /// Images of each shape the texture is recovered from (random cameras and lights, known).
    #[arg(long, default_value_t = 1)]
    views: usize,
    #[command(flatten)]
    search: TextureSearchArgs,
    #[command(flatten)]
    net: super::weights::WeightsArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Recovers the paints of painted shapes and summarises how close they come.
pub fn run(a: EvalTextureArgs) -> Result<()> {
    if a.samples == 0 {
        return Err(Error::Invalid("--samples 0: evaluate at least one painted shape".into()));
    }
    let gpu = Gpu::new()?;
    let (inv, name) = colour_inverter(&a.net)?;
    let (tex, tex_name) = a.search.load()?;
    let bar = ProgressBar::new(a.samples as u64);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} shapes [{elapsed_precise}<{eta_precise}]").expect("static template"));
    let errs = evaluate_textures(&gpu, &inv, &TexturePreset::small(), &tex, a.samples, a.views, &a.search.options(), |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let of = |f: fn(&rendernet::invert::TextureError) -> f64| Interval::of(&errs.iter().map(f).collect::<Vec<_>>());
    let (psnr, start, white, secs) = (of(|e| e.novel_view_psnr), of(|e| e.start_psnr), of(|e| e.white_psnr), of(|e| e.seconds));
    let colour = rendernet::bench::median(&errs.iter().map(|e| e.colour_error).collect::<Vec<_>>());
    let right = errs.iter().filter(|e| e.pattern_right).count();
    if a.json {
        let j = serde_json::json!({
            "shapes": errs.len(), "views": a.views, "novel_view_object_psnr_mean": psnr.mean, "novel_view_object_psnr_ci95": psnr.ci95,
            "start_object_psnr_mean": start.mean, "white_object_psnr_mean": white.mean, "colour_error_median": colour,
            "pattern_right": right, "seconds_per_shape": secs.mean,
            "per_shape": errs.iter().map(|e| serde_json::json!({"shape": e.shape, "paint": describe(&e.paint), "recovered": describe(&e.recovered), "novel_view_object_psnr": e.novel_view_psnr, "start_object_psnr": e.start_psnr,
                "white_object_psnr": e.white_psnr, "colour_error": e.colour_error, "pattern_right": e.pattern_right, "seconds": e.seconds})).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    println!("{} painted shapes, {} view(s) each, camera and light known, {} with {}", errs.len(), a.views, name, tex_name);
    println!(
        "object PSNR from a new view, recovered paint against the true one: {:.2} ± {:.2} (95%); best start before descent {:.2}; left white {:.2}",
        psnr.mean, psnr.ci95, start.mean, white.mean
    );
    println!("colour error median {:.3} (0..1 per channel); pattern right in {right} of {}", colour, errs.len());
    println!("{:.1} s per shape (mean)", secs.mean);
    Ok(())
}

/// A paint in words: its pattern and colours as hex.
fn describe(p: &rendernet::voxel::shapes::Paint) -> String {
    use rendernet::voxel::shapes::Pattern;
    let hex = |c: glam::Vec3| format!("#{:02x}{:02x}{:02x}", (c.x * 255.0).round() as u8, (c.y * 255.0).round() as u8, (c.z * 255.0).round() as u8);
    match p.pattern {
        Pattern::Plain => format!("plain {}", hex(p.a)),
        Pattern::Stripes { axis, period } => format!("stripes along {} (period {period:.2}) of {} and {}", ["x", "y", "z"][axis], hex(p.a), hex(p.b)),
        Pattern::Checker { period } => format!("checkerboard (period {period:.2}) of {} and {}", hex(p.a), hex(p.b)),
    }
}

/// `invert --texture`: the paint of a known shape from one image at a known camera and light;
/// writes the painted grid and the picture, and scores it when the truth is known.
#[allow(clippy::too_many_arguments)]
pub fn invert_texture(
    s: &TextureSearchArgs,
    net: &super::weights::WeightsArgs,
    gpu: &Gpu,
    grid: &rendernet::voxel::VoxelGrid,
    what: &str,
    image: Option<&Path>,
    scene: &super::truth::SceneArgs,
    out: &Path,
    out_voxels: &Path,
    json: bool,
    t0: std::time::Instant,
) -> Result<()> {
    use rendernet::reference::{self, Image, Options, RayMarcher, View};
    let (inv, name) = colour_inverter(net)?;
    let (tex, tex_name) = s.load()?;
    let (view, light) = (scene.view(), scene.light());
    let rm = RayMarcher::new(gpu).with_options(Options { supersample: 2, ..Options::default() });
    let size = inv.size() as u32;
    let target = match image {
        Some(p) => Image::load_rgb(p)?,
        None => rm.render(gpu, grid, &view, &light, Shader::Phong, size)?,
    };
    let bar = ProgressBar::new_spinner();
    bar.set_message("searching the texture code");
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let t1 = std::time::Instant::now();
    let one = [rendernet::invert::ShapeView { image: &target, view, light }];
    let est = inv.recover_texture(gpu, &TexturePreset::small(), &tex, grid, &one, &s.options())?;
    bar.finish_and_clear();
    let secs = t1.elapsed().as_secs_f64();
    super::invert::write_voxels(&est.grid, out_voxels, super::invert::voxels_format(out_voxels, true)?)?;
    let turned = View { azimuth: (view.azimuth + 90.0) % 360.0, ..view };
    let seen = rm.render(gpu, &est.grid, &view, &light, Shader::Phong, size)?;
    let side = rm.render(gpu, &est.grid, &turned, &light, Shader::Phong, size)?;
    reference::write_png(&image::DynamicImage::ImageRgb8(Image::side_by_side(&[&target, &seen, &side])?), out)?;
    // Without --image the target is the reference renderer's: the re-render is scored.
    let psnr = image.is_none().then(|| rendernet::metrics::object_psnr(&seen, &target));
    let turned_psnr = match (image, grid.colour()) {
        (None, Some(_)) => Some(rendernet::metrics::object_psnr(&side, &rm.render(gpu, grid, &turned, &light, Shader::Phong, size)?)),
        _ => None,
    };
    if json {
        let j = serde_json::json!({
            "shape": what, "paint": describe(&est.paint), "code": est.code, "start_paint": describe(&est.start_paint),
            "loss_curve": est.curve, "object_psnr": psnr, "turned_object_psnr": turned_psnr, "seconds": secs,
            "out": out.display().to_string(), "out_voxels": out_voxels.display().to_string(),
        });
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    println!("recovered the paint of {what} ({name}, {tex_name}): {}", describe(&est.paint));
    println!("best start before descent: {}; image MSE {:.5} after {} steps", describe(&est.start_paint), est.curve.last().copied().unwrap_or(f64::NAN), est.curve.len().saturating_sub(1));
    if let Some(p) = psnr {
        println!("the recovered paint drawn by the reference renderer against the input: object PSNR {p:.2} dB");
    }
    if let Some(p) = turned_psnr {
        println!("the same from 90 degrees further round, against the true paint: object PSNR {p:.2} dB");
    }
    println!("wrote {} (input | recovered paint | turned 90 degrees) and {} in {:.1} s", out.display(), out_voxels.display(), t0.elapsed().as_secs_f64());
    Ok(())
}
