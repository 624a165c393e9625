//! `rendernet stress`: sweeps of corrupted, coarse, crowded and extreme scenes through
//! RenderNet and the reference renderer, scored against the clean scene (library:
//! `rendernet::stress`).

use super::truth::{SceneArgs, load};
use super::weights::{Loaded, MANY_RENDERS};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rendernet::nn::render::Renderer;
use rendernet::chart::{self, Cap, Options};
use rendernet::metrics::PSNR_CAP;
use rendernet::reference::{self, Shader};
use rendernet::stress::{self, Row};
use rendernet::{Error, Gpu, Result, VoxelGrid};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Flags of `rendernet stress`.
#[derive(Args, Debug)]
pub struct StressArgs {
    /// The clean scene (default: the bunny at the default view and light).
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    net: super::weights::WeightsArgs,
    /// Seed of the random corruptions.
    #[arg(long, default_value_t = 0)]
    noise_seed: u64,
    /// Contact sheet: per sweep, a row of RenderNet images and a row of reference images of
    /// the corrupted grid, one column per level.
    #[arg(long, default_value = "stress.png")]
    out: PathBuf,
    /// Folder for one chart per sweep, `<out stem>-<sweep>.png`: object PSNR against the
    /// level, one line per method (default: the folder of `--out`).
    #[arg(long, value_name = "DIR")]
    charts: Option<PathBuf>,
    /// Print JSON rows (sweep, level, label, method, scores) instead of tables.
    #[arg(long)]
    json: bool,
    /// Add the sweep `unseen`: every grid or mesh file in DIR (e.g. `datasets/real` after
    /// `datasets/fetch_real.sh`; meshes voxelised at --resolution), clean, at the same view
    /// and light.
    #[arg(long, value_name = "DIR")]
    unseen: Option<PathBuf>,
}

/// The scene files of `dir` (extensions `voxel::load` reads), sorted, loaded.
fn unseen_shapes(dir: &Path, resolution: usize) -> Result<Vec<(String, VoxelGrid)>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::Invalid(format!("--unseen {}: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().and_then(|e| e.to_str()).is_some_and(|e| rendernet::voxel::EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(Error::Invalid(format!("--unseen {}: no .binvox, .safetensors, .vox, .obj, .off or .ply file", dir.display())));
    }
    files
        .iter()
        .map(|p| {
            let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or("shape").to_string();
            Ok((name, rendernet::voxel::load(p, resolution).map_err(|e| Error::Invalid(e.to_string()))?))
        })
        .collect()
}

/// Runs the sweeps, prints the tables or JSON, writes the contact sheet.
pub fn run(a: StressArgs) -> Result<()> {
    let t0 = Instant::now();
    super::output::check_png_out(&a.out)?;
    let charts = a.charts.clone().unwrap_or_else(|| a.out.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_path_buf());
    if !charts.is_dir() {
        return Err(Error::Invalid(format!("--charts {}: not a folder that exists", charts.display())));
    }
    let Loaded { preset, bytes, name } = a.net.resolve(Shader::Phong, false, MANY_RENDERS)?;
    let size = preset.image_for(preset.cam);
    a.scene.validate(size)?;
    let (grid, what) = load(&a.scene)?;
    let gpu = Gpu::new()?;
    let mut net = Renderer::new(&gpu, preset, &bytes, &name, size)?;
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} scenes [{elapsed_precise}]").expect("static template"));
    let unseen = match &a.unseen {
        Some(dir) => unseen_shapes(dir, a.scene.resolution)?,
        None => Vec::new(),
    };
    let rows = stress::run(&gpu, &mut net, &grid, &a.scene.view(), &a.scene.light(), a.noise_seed, &unseen, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    reference::write_png(&image::DynamicImage::ImageRgb8(contact_sheet(&rows, size)), &a.out)?;
    let stem = a.out.file_stem().and_then(|s| s.to_str()).unwrap_or("stress");
    let written = write_charts(&rows, &charts, stem)?;
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
    println!("charts: {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
    Ok(())
}

/// The sweeps in the order `stress::run` gives them.
fn sweeps(rows: &[Row]) -> Vec<&'static str> {
    let mut v: Vec<&'static str> = Vec::new();
    for r in rows {
        if !v.contains(&r.sweep) {
            v.push(r.sweep);
        }
    }
    v
}

/// How a sweep's level reads on a chart: the x axis label, and either a scale for a numeric
/// axis or `None` for a categorical one (the levels' labels in sweep order: a view index or
/// a gap with "one copy" at level 99 have no meaningful numeric distance).
fn sweep_axis(sweep: &str) -> (&'static str, &'static str, Option<f64>) {
    match sweep {
        "dropout" => ("Voxel dropout", "occupied voxels switched off (%)", Some(100.0)),
        "salt" => ("Salt noise", "empty voxels inside the object's bounding box switched on (%)", Some(100.0)),
        "value-noise" => ("Value noise", "amplitude a of uniform noise in [-a, a] added to every occupancy value", Some(1.0)),
        "downsample" => ("Downsampled grid", "grid resolution after downsampling (voxels)", None),
        "two-objects" => ("Two objects", "two copies at 3/8 size: gap between them in voxels (negative: overlapping)", None),
        "view" => ("Extreme view and light", "camera or light change from the default scene (clean grid)", None),
        "unseen" => ("Unseen shapes", "shape (clean grid, default view and light)", None),
        _ => ("Sweep", "level", Some(1.0)),
    }
}

/// One chart per sweep in `dir`, `<stem>-<sweep>.png`: object PSNR against the level, a
/// line per method, on one y scale for all sweeps; identical images (PSNR at the cap) sit in
/// a band on top. Returns the paths.
fn write_charts(rows: &[Row], dir: &Path, stem: &str) -> Result<Vec<PathBuf>> {
    let shown = rows.iter().map(|r| r.scores.object_psnr).filter(|v| v.is_finite() && *v < PSNR_CAP);
    let (lo, hi) = shown.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let y_range = (lo < hi).then(|| (lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)));
    let mut written = Vec::new();
    for sweep in sweeps(rows) {
        let (title, x_label, scale) = sweep_axis(sweep);
        let here: Vec<&Row> = rows.iter().filter(|r| r.sweep == sweep).collect();
        let mut categories: Vec<String> = Vec::new();
        for r in &here {
            if !categories.contains(&r.label) {
                categories.push(r.label.clone());
            }
        }
        let x = |r: &Row| match scale {
            Some(s) => r.level * s,
            None => categories.iter().position(|c| *c == r.label).unwrap_or(0) as f64,
        };
        let line = |method: &str| here.iter().filter(|r| r.method == method).map(|r| (x(r), r.scores.object_psnr)).collect::<Vec<_>>();
        // In these two sweeps the grid is not corrupted: the reference renderer draws the
        // truth itself.
        let reference = if matches!(sweep, "two-objects" | "view") { "reference renderer (draws the truth itself here)" } else { "reference renderer on the corrupted grid" };
        let series = [("RenderNet", line("rendernet")), (reference, line("reference"))];
        let options = Options {
            x_categories: if scale.is_none() { categories.iter().map(|c| c.replace("^3", "³")).collect() } else { Vec::new() },
            cap: Some(Cap { at: PSNR_CAP, note: format!("identical to the clean image (PSNR capped at {PSNR_CAP:.0} dB)") }),
            markers: true,
            y_range,
            ..Options::default()
        };
        let path = dir.join(format!("{stem}-{sweep}.png"));
        let full_title = format!("{title}: object PSNR against the clean scene's reference image");
        chart::line_chart(&path, &full_title, x_label, "object PSNR (dB)", &series, &options)?;
        written.push(path);
    }
    Ok(written)
}

/// Per sweep two rows (RenderNet, then the reference renderer on the same corrupted grid),
/// one column per level.
fn contact_sheet(rows: &[Row], size: usize) -> image::RgbImage {
    let sweeps = sweeps(rows);
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
