//! `rendernet dataset`: generate a sharded, deterministic training/test set.

use clap::Args;
use rendernet::data::{self, GenerateOptions, Shapes};
use rendernet::reference::Shader;
use rendernet::{Gpu, Result};
use std::path::PathBuf;

/// Flags of `rendernet dataset`.
#[derive(Args, Debug)]
pub struct DatasetArgs {
    /// Shape source: chairs (procedural), real (meshes under --real-dir), mixed (chair,
    /// table, sofa, primitive in turn) or varied (mixed's four and creature in turn).
    #[arg(long, default_value = "chairs", value_parser = parse_shapes)]
    shapes: Shapes,
    /// Target shader: phong (stores phong, normal, albedo, mask), albedo, normal, depth, mask,
    /// toon, contour or ao.
    #[arg(long, default_value = "phong", value_parser = super::truth::parse_shader)]
    shader: Shader,
    /// Number of shapes N (not samples: N * views samples are written).
    #[arg(long, default_value_t = 100)]
    count: usize,
    /// Random views per shape.
    #[arg(long, default_value_t = 10)]
    views: usize,
    /// Input grid side R.
    #[arg(long, default_value_t = 32)]
    res: usize,
    /// Side of the grid the targets are rendered from; default 2 * res.
    #[arg(long)]
    truth_res: Option<usize>,
    /// Image side in pixels.
    #[arg(long, default_value_t = 128)]
    image: usize,
    /// Sub-voxels per axis of the input grids: 1 gives binary occupancy (as binvox files);
    /// K > 1 averages K^3 samples per voxel, so surface voxels hold the fraction inside, as
    /// `render` voxelises a mesh. A network trained on such grids sees where a surface lies
    /// within a voxel; the targets are unchanged.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=8))]
    input_supersample: u64,
    /// Seed of shapes, views and lights; the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Fraction of shapes held out for test (the last ceil(F * N) shapes).
    #[arg(long, default_value_t = 0.1)]
    test_fraction: f64,
    /// Camera radius: `MIN,MAX` for a uniform range (the paper's 3,6.3), or one value for a
    /// fixed distance, e.g. 3.3 for evaluation at the closest framing.
    #[arg(long, default_value = "3,6.3", value_parser = parse_radius)]
    radius: (f64, f64),
    /// Sub-pixels per axis averaged into each target pixel (anti-aliasing).
    #[arg(long, default_value_t = 2)]
    supersample: u32,
    /// Ambient-occlusion rays per pixel of --shader ao targets: a perfect square (stratified
    /// directions). 16 renders about 4x faster than the default 64, with coarser shading.
    #[arg(long, default_value_t = 64)]
    ao_rays: u32,
    /// Paint the procedural shapes: each part a colour, plain, striped or checkered. The
    /// input grids then carry RGB (a `colours` tensor) and Phong datasets an RGB albedo map;
    /// a network trained on it takes coloured voxels (.vox palettes) and renders in colour.
    #[arg(long)]
    colour: bool,
    /// Meshes for --shapes real (see datasets/fetch_real.sh).
    #[arg(long, default_value = "datasets/real")]
    real_dir: PathBuf,
    /// Output directory (shards and manifest.json).
    #[arg(long)]
    out: PathBuf,
}

fn parse_radius(s: &str) -> std::result::Result<(f64, f64), String> {
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>().map_err(|_| format!("'{x}' is not a number"))).collect::<std::result::Result<_, _>>()?;
    match v[..] {
        [r] if r > 0.0 && r.is_finite() => Ok((r, r)),
        [lo, hi] if lo > 0.0 && lo <= hi && hi.is_finite() => Ok((lo, hi)),
        _ => Err(format!("'{s}': expected R or MIN,MAX with 0 < MIN <= MAX")),
    }
}

fn parse_shapes(s: &str) -> std::result::Result<Shapes, String> {
    Shapes::parse(s).ok_or_else(|| format!("unknown shapes '{s}'; expected chairs, real, mixed or varied"))
}

/// Generates the dataset and reports counts and timing.
pub fn run(a: DatasetArgs) -> Result<()> {
    let gpu = Gpu::new()?;
    let o = GenerateOptions {
        shapes: a.shapes,
        shader: a.shader,
        count: a.count,
        views: a.views,
        res: a.res,
        truth_res: a.truth_res.unwrap_or(2 * a.res),
        input_supersample: a.input_supersample as usize,
        image: a.image,
        seed: a.seed,
        test_fraction: a.test_fraction,
        radius: a.radius,
        supersample: a.supersample,
        ao_rays: a.ao_rays,
        real_dir: a.real_dir,
        colour: a.colour,
    };
    let bar = indicatif::ProgressBar::new((o.count * o.views) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{elapsed_precise} {wide_bar} {pos}/{len} samples {per_sec} eta {eta}")
            .expect("valid template"),
    );
    let s = data::generate(&gpu, &o, &a.out, |done, _| bar.set_position(done as u64))?;
    bar.finish();
    let n = s.manifest.train.count + s.manifest.test.count;
    println!(
        "wrote {} train + {} test samples ({} shapes x {} views) to {} in {:.1} s ({:.1} samples/s, on {})",
        s.manifest.train.count,
        s.manifest.test.count,
        a.count,
        a.views,
        a.out.display(),
        s.seconds,
        n as f64 / s.seconds,
        gpu.info.name
    );
    Ok(())
}
