//! `rendernet invert`: recover camera pose and light from one image of a known voxel grid,
//! by gradient descent through the frozen network (library: `rendernet::invert`).

use super::truth::{SceneArgs, load};
use super::weights::{Loaded, MANY_RENDERS};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rendernet::bench::median;
use rendernet::data::Dataset;
use rendernet::invert::{self, InvertOptions, Inverter, Pick, angle_between, light_direction, view_direction};
use rendernet::nn::rendernet::Head;
use rendernet::train::head_for;
use rendernet::train::eval::Interval;
use rendernet::reference::{self, Image, Light, Options, Shader};
use rendernet::{Error, Gpu, Result};
use std::path::PathBuf;
use std::time::Instant;

/// What `--pick` takes ([`Pick`]).
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum PickArg {
    Exact,
    Network,
}

impl PickArg {
    fn pick(self) -> Pick {
        match self {
            PickArg::Exact => Pick::Exact,
            PickArg::Network => Pick::Network,
        }
    }
}

/// What `--light-network` takes: the shipped Phong presets, or none.
const LIGHT_NETWORKS: [&str; 4] = ["none", "nano", "tiny", "base"];

/// Flags of `rendernet invert`.
#[derive(Args, Debug)]
pub struct InvertArgs {
    /// The image to explain (square RGB, the network's image size: 128 px for tiny). Without
    /// it, the reference renderer draws the target from the scene flags (--azimuth, ...,
    /// --light-elevation), and the errors of the recovered pose and light are printed.
    #[arg(long)]
    image: Option<PathBuf>,
    /// The shape (--voxels or --shape; default the bunny) and, without --image, the true view
    /// and light.
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    net: super::weights::WeightsArgs,
    /// Azimuth starts of the coarse silhouette search (evenly spaced over 360 degrees).
    #[arg(long, default_value_t = InvertOptions::default().azimuths)]
    azimuths: usize,
    /// Elevation starts of the coarse search (evenly spaced inside 0..180).
    #[arg(long, default_value_t = InvertOptions::default().elevations)]
    elevations: usize,
    /// Starts refined by gradient descent: the coarse views (and their opposite-side twins),
    /// each with its best light of a 20-degree grid, ranked by image MSE; the best 2 x
    /// starts are subdivided (the 8 views half a grid step away) and the best `starts` of
    /// those refined.
    #[arg(long, default_value_t = InvertOptions::default().keep)]
    starts: usize,
    /// Gradient steps of the refinement (the light polish after it takes half as many).
    #[arg(long, default_value_t = InvertOptions::default().steps)]
    steps: usize,
    /// PNG with the input beside the network's render at the recovered pose and light (with
    /// --prior, also the recovered shape drawn by the reference renderer from 90 degrees
    /// further round).
    #[arg(long, default_value = "invert.png")]
    out: PathBuf,
    /// Recover the shape too, as the code of a shape prior, alternating with the camera and
    /// light search: `--prior` alone takes the shipped chair prior, `--prior FILE` weights
    /// from `rendernet train-prior`. --voxels/--shape then give only the true shape (to
    /// render the target without --image, and to score the recovered shape's IoU).
    #[arg(long, value_name = "FILE", num_args = 0..=1)]
    prior: Option<Option<PathBuf>>,
    /// With --prior: rounds of (camera and light search, shape search).
    #[arg(long, default_value_t = 2)]
    rounds: usize,
    /// With --prior: Adam steps on the shape code per refined start, each round.
    #[arg(long, default_value_t = rendernet::invert::ShapeOptions::default().steps)]
    shape_steps: usize,
    /// Where the recovered grid is written: with --prior .binvox (default invert.binvox) or
    /// .safetensors; with --texture .vox (default invert.vox) or .safetensors.
    #[arg(long)]
    out_voxels: Option<PathBuf>,
    /// Recover the texture instead of the camera and light: the paint (two colours; plain,
    /// stripes or a checkerboard) of the shape --voxels/--shape, as a code of the texture
    /// decoder rendered through the shipped colour network, at the camera and light the
    /// scene flags give (--azimuth ... --light-elevation: with --image, the image's own).
    /// Writes the painted grid to --out-voxels, and --out: input | the recovered paint drawn
    /// by the reference renderer at that view | the same from 90 degrees further round.
    #[arg(long, conflicts_with = "prior")]
    texture: bool,
    #[command(flatten)]
    texture_search: super::texture::TextureSearchArgs,
    /// Shipped Phong network that picks the final light at the recovered camera (its best
    /// light over a 5-degree grid of directions) and draws the estimate: base, whose lights
    /// measured closer to the truth on procedural chairs but not on real meshes (README), or
    /// none to keep the search's own light (the exact light's with --pick exact). Not with
    /// --prior or --texture.
    #[arg(long, value_name = "PRESET", default_value = "none", value_parser = LIGHT_NETWORKS, conflicts_with_all = ["prior", "texture"])]
    light_network: String,
    /// What picks the camera among the search's hypotheses: exact (default) draws the refined
    /// ones, the best unrefined views, the far-side twins of all and a 15-degree camera grid
    /// with the reference renderer from the known grid, refines camera and light of the 3
    /// distinct ones whose maps explain the image best on those maps, keeps the best, and
    /// searches the light over every direction there (the light reported); network keeps
    /// the network's own lowest image MSE (the paper's way). With --prior the network picks.
    #[arg(long, value_enum, default_value_t = PickArg::Exact)]
    pick: PickArg,
    /// Print JSON (pose, light, MSE, errors when known, loss curve, seconds) instead of text.
    #[arg(long)]
    json: bool,
}

/// Loads the shape and the image (or renders it), inverts, reports.
pub fn run(a: InvertArgs) -> Result<()> {
    let t0 = Instant::now();
    super::output::check_png_out(&a.out)?;
    if a.prior.is_some() {
        voxels_format(&a.out_voxels(), false)?;
    }
    if a.texture {
        voxels_format(&a.out_voxels(), true)?;
    }
    let Loaded { preset, bytes, name } = a.net.resolve(Shader::Phong, false, MANY_RENDERS)?;
    if a.image.is_none() {
        // The scene flags then describe the true view and light, rendered as the target.
        a.scene.validate(preset.image_for(preset.cam))?;
    }
    let (grid, what) = load(&a.scene)?;
    let gpu = Gpu::new()?;
    if a.texture {
        return super::texture::invert_texture(&a.texture_search, &a.net, &gpu, &grid, &what, a.image.as_deref(), &a.scene, &a.out, &a.out_voxels(), a.json, t0);
    }
    let inv = light_network(Inverter::new(preset, &bytes, &name, Light::default())?, &a.light_network)?;
    let (target, truth) = match &a.image {
        Some(p) => (Image::load_rgb(p)?, None),
        None => {
            let (view, light) = (a.scene.view(), a.scene.light());
            let opts = Options { supersample: 2, ..Options::default() };
            let img = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, inv.size() as u32)?;
            (img, Some((view, light)))
        }
    };
    let o = InvertOptions { azimuths: a.azimuths, elevations: a.elevations, keep: a.starts, steps: a.steps, pick: a.pick.pick(), ..Default::default() };
    if let Some(prior) = &a.prior {
        return with_prior(&a, &gpu, &inv, prior.as_deref(), &grid, &target, truth, &o, t0);
    }
    let bar = ProgressBar::new(o.steps as u64);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} refinement steps [{elapsed_precise}] {msg}").expect("static template"));
    let t1 = Instant::now();
    let est = inv.invert(&gpu, &grid, &target, &o, |step, mse| {
        bar.set_position(step as u64);
        bar.set_message(format!("best MSE {mse:.5}"));
    })?;
    bar.finish_and_clear();
    let secs = t1.elapsed().as_secs_f64();
    reference::write_png(&image::DynamicImage::ImageRgb8(Image::side_by_side(&[&target, &est.image])?), &a.out)?;
    let errors = truth.map(|(v, l)| {
        (angle_between(view_direction(&v), view_direction(&est.view)), angle_between(light_direction(&l), light_direction(&est.light)), est.view.radius / v.radius, angle_between(view_direction(&v), view_direction(&est.network_view)))
    });
    let psnr = -10.0 * est.mse.max(1e-10).log10();
    if a.json {
        let mut j = serde_json::json!({
            "shape": what,
            "azimuth": est.view.azimuth, "elevation": est.view.elevation, "radius": est.view.radius,
            "light_azimuth": est.light.azimuth, "light_elevation": est.light.elevation,
            "mse": est.mse, "psnr": psnr, "curve": est.curve, "seconds": secs, "out": a.out.display().to_string(),
            "light_network": a.light_network,
            "search_light_azimuth": est.search_light.azimuth, "search_light_elevation": est.search_light.elevation,
            "pick": format!("{:?}", a.pick).to_lowercase(),
            "network_azimuth": est.network_view.azimuth, "network_elevation": est.network_view.elevation, "network_radius": est.network_view.radius,
        });
        if let Some((pe, le, rr, ne)) = errors {
            j["network_pose_error_degrees"] = ne.into();
            j["pose_error_degrees"] = pe.into();
            j["light_error_degrees"] = le.into();
            j["radius_ratio"] = rr.into();
        }
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    println!("inverted {what}");
    println!(
        "recovered: azimuth {:.1} elevation {:.1} radius {:.2}, light azimuth {:.1} elevation {:.1}",
        est.view.azimuth, est.view.elevation, est.view.radius, est.light.azimuth, est.light.elevation
    );
    println!("re-render against the input: MSE {:.5} (PSNR {psnr:.2} dB)", est.mse);
    if let Some((pe, le, rr, ne)) = errors {
        println!("errors against the true scene: camera direction {pe:.1} deg (the network's own pick: {ne:.1}), light direction {le:.1} deg, radius x{rr:.3}");
    }
    println!("wrote {} (input | network at the recovered pose) in {:.1} s ({secs:.1} s inverting on {})", a.out.display(), t0.elapsed().as_secs_f64(), gpu.info.name);
    Ok(())
}

impl InvertArgs {
    /// `--out-voxels`, or its default for the mode.
    fn out_voxels(&self) -> PathBuf {
        self.out_voxels.clone().unwrap_or_else(|| PathBuf::from(if self.texture { "invert.vox" } else { "invert.binvox" }))
    }
}

/// The format `--out-voxels` names: `binvox` (`vox` for a coloured grid) or `safetensors`,
/// else an error.
pub(super) fn voxels_format(path: &std::path::Path, colour: bool) -> Result<&str> {
    match (path.extension().and_then(|e| e.to_str()), colour) {
        (Some(e @ "safetensors"), _) | (Some(e @ "binvox"), false) | (Some(e @ "vox"), true) => Ok(e),
        (_, false) => Err(Error::Invalid(format!("--out-voxels {}: write .binvox or .safetensors", path.display()))),
        (_, true) => Err(Error::Invalid(format!("--out-voxels {}: write .vox or .safetensors (a binvox file has no colour)", path.display()))),
    }
}

/// Writes `grid` to `path` in `format` (one [`voxels_format`] returned).
pub(super) fn write_voxels(grid: &rendernet::voxel::VoxelGrid, path: &std::path::Path, format: &str) -> Result<()> {
    match format {
        "vox" => rendernet::voxel::vox::write(grid, path)?,
        "binvox" => rendernet::voxel::binvox::Binvox::from_grid(grid.clone()).write(path)?,
        _ => rendernet::voxel::safetensors_io::write(grid, path)?,
    }
    Ok(())
}

/// `invert --prior`: shape, camera and light recovered together; writes the grid and the
/// picture, and reports the errors when the truth is known.
#[allow(clippy::too_many_arguments)]
fn with_prior(a: &InvertArgs, gpu: &Gpu, inv: &Inverter, prior: Option<&std::path::Path>, truth_grid: &rendernet::voxel::VoxelGrid, target: &Image, truth: Option<(rendernet::reference::View, Light)>, o: &InvertOptions, t0: Instant) -> Result<()> {
    let out_voxels = a.out_voxels();
    let ext = voxels_format(&out_voxels, false)?;
    let (pw, prior_name) = super::prior::load_prior(prior)?;
    let pp = rendernet::nn::prior::PriorPreset::small();
    let bar = ProgressBar::new(a.rounds.max(1) as u64);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} rounds (camera and light, then shape) [{elapsed_precise}]").expect("static template"));
    let t1 = Instant::now();
    let so = rendernet::invert::ShapeOptions { steps: a.shape_steps, ..Default::default() };
    let est = inv.invert_unknown_shape(gpu, &pp, &pw, target, o, &so, a.rounds, |r, _| bar.set_position(r as u64))?;
    bar.finish_and_clear();
    let secs = t1.elapsed().as_secs_f64();
    let grid = &est.shape.grid;
    write_voxels(grid, &out_voxels, ext)?;
    let (view, light) = (est.pose.view, est.pose.light);
    let turned = rendernet::reference::View { azimuth: (view.azimuth + 90.0) % 360.0, ..view };
    let side = reference::RayMarcher::new(gpu).render(gpu, grid, &turned, &light, Shader::Phong, inv.size() as u32)?;
    reference::write_png(&image::DynamicImage::ImageRgb8(Image::side_by_side(&[target, &est.pose.image, &side])?), &a.out)?;
    let iou = truth.is_some().then(|| grid.resample_to(32).ok().and_then(|g| truth_grid.resample_to(32).ok().and_then(|t| g.iou(&t)))).flatten();
    let errors = truth.map(|(v, l)| (angle_between(view_direction(&v), view_direction(&view)), angle_between(light_direction(&l), light_direction(&light))));
    if a.json {
        let mut j = serde_json::json!({
            "azimuth": view.azimuth, "elevation": view.elevation, "radius": view.radius,
            "light_azimuth": light.azimuth, "light_elevation": light.elevation, "mse": est.pose.mse,
            "shape_loss_curve": est.shape.curve, "code": est.shape.code, "seconds": secs,
            "out": a.out.display().to_string(), "out_voxels": out_voxels.display().to_string(),
        });
        if let Some((pe, le)) = errors {
            j["pose_error_degrees"] = pe.into();
            j["light_error_degrees"] = le.into();
        }
        if let Some(iou) = iou {
            j["voxel_iou"] = iou.into();
        }
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    println!("recovered shape, camera and light ({} rounds, prior {})", a.rounds.max(1), prior_name);
    println!(
        "camera: azimuth {:.1} elevation {:.1} radius {:.2}; light azimuth {:.1} elevation {:.1}; re-render MSE {:.5}",
        view.azimuth, view.elevation, view.radius, light.azimuth, light.elevation, est.pose.mse
    );
    if let Some((pe, le)) = errors {
        println!("errors against the true scene: camera direction {pe:.1} deg, light direction {le:.1} deg");
    }
    if let Some(iou) = iou {
        println!("voxel IoU of the recovered shape against the true one (32^3): {iou:.3}");
    }
    println!(
        "wrote {} (input | network at the estimate | recovered shape turned 90 degrees) and {} in {:.1} s",
        a.out.display(),
        out_voxels.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Flags of `rendernet eval-invert`.
#[derive(Args, Debug)]
pub struct EvalInvertArgs {
    /// Phong dataset whose held-out samples (grid, true view and light, reference image) are
    /// inverted; its shapes should be unseen by the weights.
    #[arg(long)]
    data: PathBuf,
    /// Held-out samples to invert, spread over the split (0 = all).
    #[arg(long, default_value_t = 10)]
    samples: usize,
    #[command(flatten)]
    net: super::weights::WeightsArgs,
    /// Refinement steps per sample.
    #[arg(long, default_value_t = InvertOptions::default().steps)]
    steps: usize,
    /// Starts refined per sample (as `invert --starts`: the best views by image MSE after the
    /// coarse grid's subdivision).
    #[arg(long, default_value_t = InvertOptions::default().keep)]
    starts: usize,
    /// Azimuth starts of the coarse search (as `invert --azimuths`).
    #[arg(long, default_value_t = InvertOptions::default().azimuths)]
    azimuths: usize,
    /// Elevation starts of the coarse search (as `invert --elevations`).
    #[arg(long, default_value_t = InvertOptions::default().elevations)]
    elevations: usize,
    /// Shipped Phong network that picks the final light at the recovered camera (its best
    /// light over a 5-degree grid of directions) and draws the estimate: base, whose lights
    /// measured closer to the truth on procedural chairs but not on real meshes (README), or
    /// none to keep the search's own light (the exact light's with --pick exact).
    #[arg(long, value_name = "PRESET", default_value = "none", value_parser = LIGHT_NETWORKS)]
    light_network: String,
    /// What picks the camera among the search's hypotheses: exact (default) draws the refined
    /// ones, the best unrefined views, the far-side twins of all and a 15-degree camera grid
    /// with the reference renderer from the known grid, refines camera and light of the 3
    /// distinct ones whose maps explain the image best on those maps, keeps the best, and
    /// searches the light over every direction there (the light reported); network keeps
    /// the network's own lowest image MSE (the paper's way).
    #[arg(long, value_enum, default_value_t = PickArg::Exact)]
    pick: PickArg,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// `inv` with the shipped Phong network `preset` picking its final light (`none`: `inv` as
/// it is), loaded as `--preset` loads embedded weights.
fn light_network(inv: Inverter, preset: &str) -> Result<Inverter> {
    if preset == "none" {
        return Ok(inv);
    }
    let shipped = super::weights::WeightsArgs { weights: None, preset: Some(preset.to_string()), quality: None, target_psnr: None };
    let Loaded { preset, bytes, name } = shipped.resolve(Shader::Phong, false, MANY_RENDERS)?;
    inv.with_light_network(Inverter::new(preset, &bytes, &name, Light::default())?)
}

/// The network of `net` set up to invert images of the Phong dataset `ds` (its material
/// constants), and the weights' name.
pub(crate) fn dataset_inverter(net: &super::weights::WeightsArgs, ds: &Dataset) -> Result<(Inverter, String)> {
    let Head::Phong(ph) = head_for(ds)? else {
        return Err(Error::Invalid(format!("{}: inversion needs a Phong dataset", ds.dir().display())));
    };
    let light = Light { ambient: ph.ambient, kd: ph.kd, ks: ph.ks, shininess: ph.shininess, ..Light::default() };
    let Loaded { preset, bytes, name } = net.resolve(Shader::Phong, false, MANY_RENDERS)?;
    Ok((Inverter::new(preset, &bytes, &name, light)?, name))
}

/// Inverts held-out samples and summarises the errors.
pub fn run_eval(a: EvalInvertArgs) -> Result<()> {
    let gpu = Gpu::new()?;
    let ds = Dataset::open(&a.data)?;
    let (inv, name) = dataset_inverter(&a.net, &ds)?;
    let inv = light_network(inv, &a.light_network)?;
    let o = InvertOptions { azimuths: a.azimuths, elevations: a.elevations, keep: a.starts, steps: a.steps, pick: a.pick.pick(), ..Default::default() };
    let bar = ProgressBar::new(a.samples as u64);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} images [{elapsed_precise}<{eta_precise}]").expect("static template"));
    let errs = invert::evaluate(&gpu, &inv, &ds, a.samples, &o, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let pose: Vec<f64> = errs.iter().map(|e| e.pose_degrees).collect();
    let network: Vec<f64> = errs.iter().map(|e| e.network_pose_degrees).collect();
    let light: Vec<f64> = errs.iter().map(|e| e.light_degrees).collect();
    let optimum: Vec<f64> = errs.iter().map(|e| e.light_optimum_degrees).collect();
    let exact: Vec<f64> = errs.iter().map(|e| e.light_exact_degrees).collect();
    let exact_truth: Vec<f64> = errs.iter().map(|e| e.light_exact_truth_degrees).collect();
    // Light errors split by where the true light is: in front of the object or behind it.
    let side = |front: bool, f: fn(&invert::InvertError) -> f64| errs.iter().filter(|e| e.light_in_front == front).map(f).collect::<Vec<f64>>();
    let (front, behind) = (side(true, |e| e.light_degrees), side(false, |e| e.light_degrees));
    let (exact_front, exact_behind) = (side(true, |e| e.light_exact_truth_degrees), side(false, |e| e.light_exact_truth_degrees));
    let radius: Vec<f64> = errs.iter().map(|e| (e.radius_ratio - 1.0).abs()).collect();
    let within = |xs: &[f64], t: f64| xs.iter().filter(|&&x| x <= t).count() as f64 / xs.len().max(1) as f64;
    let secs = Interval::of(&errs.iter().map(|e| e.seconds).collect::<Vec<_>>());
    // Cameras more than 10 degrees off, split by who failed: the search (the true camera
    // scores better than what it found) or the network (the wrong view scores better).
    let off: Vec<&invert::InvertError> = errs.iter().filter(|e| e.pose_degrees > 10.0).collect();
    let search_failures = off.iter().filter(|e| e.truth_mse < e.search_mse).count();
    if a.json {
        let mut j = serde_json::json!({
            "samples": errs.len(),
            "light_network": a.light_network,
            "pose_error_median_degrees": median(&pose),
            "pose_error_mean_degrees": Interval::of(&pose).mean, "pose_error_ci95_degrees": Interval::of(&pose).ci95,
            "pose_within_5_degrees": within(&pose, 5.0), "pose_within_10_degrees": within(&pose, 10.0),
            "light_error_median_degrees": median(&light), "light_within_10_degrees": within(&light, 10.0),
            "search_light_error_median_degrees": median(&errs.iter().map(|e| e.search_light_degrees).collect::<Vec<_>>()),
            "light_optimum_error_median_degrees": median(&optimum), "light_optimum_within_10_degrees": within(&optimum, 10.0),
            "light_exact_error_median_degrees": median(&exact), "light_exact_within_10_degrees": within(&exact, 10.0),
            "light_exact_truth_error_median_degrees": median(&exact_truth), "light_exact_truth_within_10_degrees": within(&exact_truth, 10.0),
            "lights_in_front": front.len(),
            "light_error_median_in_front_degrees": median(&front), "light_error_median_behind_degrees": median(&behind),
            "light_exact_truth_error_median_in_front_degrees": median(&exact_front), "light_exact_truth_error_median_behind_degrees": median(&exact_behind),
            "radius_relative_error_median": median(&radius),
            "pose_off_by_10_degrees": off.len(), "pose_off_search_failures": search_failures,
            "seconds_per_image": secs.mean,
            "per_sample": errs.iter().map(|e| serde_json::json!({
                "shape": e.shape_id, "pose_degrees": e.pose_degrees, "network_pose_degrees": e.network_pose_degrees, "light_degrees": e.light_degrees, "search_light_degrees": e.search_light_degrees,
                "light_optimum_degrees": e.light_optimum_degrees, "light_exact_degrees": e.light_exact_degrees, "light_exact_truth_degrees": e.light_exact_truth_degrees, "light_in_front": e.light_in_front, "radius_ratio": e.radius_ratio, "mse": e.mse,
                "truth_mse": e.truth_mse, "search_mse": e.search_mse, "seconds": e.seconds})).collect::<Vec<_>>(),
        });
        j["pick"] = format!("{:?}", a.pick).to_lowercase().into();
        j["network_pose_error_median_degrees"] = median(&network).into();
        j["network_pose_within_5_degrees"] = within(&network, 5.0).into();
        j["network_pose_within_10_degrees"] = within(&network, 10.0).into();
        println!("{}", serde_json::to_string_pretty(&j).map_err(|e| Error::Invalid(e.to_string()))?);
        return Ok(());
    }
    let iv = Interval::of(&pose);
    println!("{} held-out images of {}, shape known, {} on {} (light picked by: {})", errs.len(), a.data.display(), name, gpu.info.name, a.light_network);
    println!(
        "camera direction error: median {:.1} deg, mean {:.1} ± {:.1} (95%), within 5 deg {:.0}%, within 10 deg {:.0}%",
        median(&pose), iv.mean, iv.ci95, 100.0 * within(&pose, 5.0), 100.0 * within(&pose, 10.0)
    );
    println!(
        "  the network's own pick (--pick network): median {:.1} deg, within 5 deg {:.0}%, within 10 deg {:.0}%",
        median(&network),
        100.0 * within(&network, 5.0),
        100.0 * within(&network, 10.0)
    );
    println!("light direction error: median {:.1} deg, within 10 deg {:.0}%", median(&light), 100.0 * within(&light, 10.0));
    if a.light_network != "none" {
        let own: Vec<f64> = errs.iter().map(|e| e.search_light_degrees).collect();
        println!("  the search's own light: median {:.1} deg, within 10 deg {:.0}%", median(&own), 100.0 * within(&own, 10.0));
    }
    println!(
        "the light-picking network's own best light at the true camera (5-degree grid): median {:.1} deg from the truth, within 10 deg {:.0}%",
        median(&optimum),
        100.0 * within(&optimum, 10.0)
    );
    println!(
        "light fitted to the exact renderer's maps of the grid at the recovered camera: median {:.1} deg, within 10 deg {:.0}%",
        median(&exact),
        100.0 * within(&exact, 10.0)
    );
    println!(
        "the same at the true camera (what the image and grid allow): median {:.1} deg, within 10 deg {:.0}%",
        median(&exact_truth),
        100.0 * within(&exact_truth, 10.0)
    );
    println!(
        "lights on the camera's side: {} of {}; light error median {:.1} deg there, {:.1} behind the object (exact maps at the true camera: {:.1} and {:.1})",
        front.len(),
        errs.len(),
        median(&front),
        median(&behind),
        median(&exact_front),
        median(&exact_behind)
    );
    println!(
        "cameras more than 10 deg off: {} of {}; {} of them the search's (the true camera scores a lower image MSE), {} the network's (the wrong view scores lower)",
        off.len(),
        errs.len(),
        search_failures,
        off.len() - search_failures
    );
    println!("radius relative error: median {:.3}", median(&radius));
    println!("{:.1} s per image (mean)", secs.mean);
    Ok(())
}
