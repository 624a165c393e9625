//! `rendernet truth`: one ground-truth image from the reference renderer.

use clap::Args;
use rendernet::reference::camera::{self, RADIUS_AT_SCALE_ONE};
use rendernet::reference::{Light, Options, RayMarcher, Shader, View};
use rendernet::voxel::{self, Family, VoxelGrid};
use rendernet::{Error, Gpu, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to render and from where: shared by `truth` and `render`, and validated by
/// [`SceneArgs::validate`] before either loads anything.
// Numeric flags take hyphen values so `--radius -1` and `--azimuth -inf` reach the range
// checks (clap would otherwise read them as unknown flags).
#[derive(Args, Debug)]
pub struct SceneArgs {
    /// Voxel grid (.binvox, .safetensors, MagicaVoxel .vox) or mesh (.obj, .off, .ply, voxelised at --resolution).
    #[arg(long, value_name = "PATH", conflicts_with = "shape")]
    voxels: Option<PathBuf>,
    /// Grid side used to voxelise a mesh or a procedural --shape.
    #[arg(long, default_value_t = 64, allow_negative_numbers = true)]
    pub resolution: usize,
    /// Procedural shape family instead of a file: chair, table, sofa, primitive or creature.
    #[arg(long, value_parser = parse_family)]
    shape: Option<Family>,
    /// Seed of the procedural shape.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    seed: u64,
    /// Paint the procedural --shape as `dataset --colour` does (a colour and pattern per part).
    #[arg(long, requires = "shape")]
    colour: bool,
    /// Camera azimuth in degrees about the up axis (0 looks at the object's front); any finite value.
    #[arg(long, default_value_t = View::default().azimuth, allow_hyphen_values = true)]
    azimuth: f64,
    /// Camera elevation: polar angle in degrees, 0..=180: 90 horizontal, smaller looks down
    /// (training used 10..170).
    #[arg(long, default_value_t = View::default().elevation, allow_hyphen_values = true)]
    elevation: f64,
    /// Camera radius; the image is 2 * radius / 3.3 object units wide (training used 3..6.3).
    /// Accepted: 0.05 up to 3.3 * size / 16, where the object still spans 8 pixels.
    #[arg(long, default_value_t = View::default().radius, allow_hyphen_values = true)]
    radius: f64,
    /// Light azimuth in degrees relative to the camera (positive = from the right); any finite value.
    #[arg(long, default_value_t = Light::default().azimuth, allow_hyphen_values = true)]
    light_azimuth: f64,
    /// Light elevation (polar) in degrees relative to the camera, 0..=180 (90 = level, smaller = above).
    #[arg(long, default_value_t = Light::default().elevation, allow_hyphen_values = true)]
    light_elevation: f64,
}

/// Closest camera the flags accept. The frame is then 2 * 0.05 / 3.3 = 0.03 object units
/// wide, two voxels of the default 64^3 grid: any closer only magnifies the inside of one
/// voxel into a flat field (and, far closer, the network's pose scale overflows f32).
pub const MIN_RADIUS: f64 = 0.05;

/// Fewest pixels the object's unit box must span. The box spans `size * 3.3 / (2 * radius)`
/// pixels; below 8 the reference image is an unrecognisable dot and RenderNet's a grey smudge
/// (at --size 128: radius 20 still shows the bunny at 10 px, radius 40 a 5 px blob).
const MIN_OBJECT_PX: f64 = 8.0;

/// Farthest camera the flags accept for `size`-pixel images (see [`MIN_OBJECT_PX`]).
pub fn max_radius(size: usize) -> f64 {
    RADIUS_AT_SCALE_ONE * size as f64 / (2.0 * MIN_OBJECT_PX)
}

impl SceneArgs {
    /// The camera the flags name.
    pub fn view(&self) -> View {
        View { azimuth: self.azimuth, elevation: self.elevation, radius: self.radius }
    }

    /// The light the flags name (material constants: the reference renderer's defaults).
    pub fn light(&self) -> Light {
        Light { azimuth: self.light_azimuth, elevation: self.light_elevation, ..Light::default() }
    }

    /// Checks the camera and light flags for `size`-pixel images, naming the flag and its
    /// range: the same checks as [`View::validate`], plus the radius bounds above.
    pub fn validate(&self, size: usize) -> Result<()> {
        let flag = |name: &str, v: f64, check: std::result::Result<(), String>| {
            check.map_err(|m| Error::Invalid(format!("--{name} {v}: {m}")))
        };
        flag("azimuth", self.azimuth, camera::check_angle(self.azimuth))?;
        flag("elevation", self.elevation, camera::check_polar(self.elevation))?;
        flag("light-azimuth", self.light_azimuth, camera::check_angle(self.light_azimuth))?;
        flag("light-elevation", self.light_elevation, camera::check_polar(self.light_elevation))?;
        let max = max_radius(size);
        let radius_ok = camera::check_radius(self.radius).is_ok() && (MIN_RADIUS..=max).contains(&self.radius);
        flag(
            "radius",
            self.radius,
            if radius_ok {
                Ok(())
            } else {
                Err(format!(
                    "must lie in {MIN_RADIUS}..={} for --size {size} (closer shows the inside of one voxel, farther leaves the object under {MIN_OBJECT_PX} pixels)",
                    short(max)
                ))
            },
        )
    }

    /// One line saying what the flags render.
    pub fn describe(&self, what: &str) -> String {
        format!(
            "{what}, azimuth {} elevation {} radius {}, light azimuth {} elevation {}",
            self.azimuth, self.elevation, self.radius, self.light_azimuth, self.light_elevation
        )
    }
}

/// Flags of `rendernet truth`.
#[derive(Args, Debug)]
pub struct TruthArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output: phong, albedo, normal, depth, mask, toon, contour or ao.
    #[arg(long, default_value = "phong", value_parser = parse_shader)]
    shader: Shader,
    /// Image side in pixels.
    #[arg(long, default_value_t = 128, allow_negative_numbers = true)]
    size: u32,
    /// Sub-pixels per axis averaged into each pixel (anti-aliasing); 1 = none.
    #[arg(long, default_value_t = 2, allow_negative_numbers = true)]
    supersample: u32,
    /// Where to write the PNG (a .png name; written atomically).
    #[arg(long, default_value = "truth.png")]
    out: PathBuf,
    /// Also write the scene's voxel grid: .vox (keeps colour), .binvox (grey only) or
    /// .safetensors, e.g. a painted `--shape` as a MagicaVoxel file for `render --voxels`.
    #[arg(long, value_name = "PATH")]
    out_voxels: Option<PathBuf>,
}

pub(crate) fn parse_shader(s: &str) -> std::result::Result<Shader, String> {
    Shader::parse(s).ok_or_else(|| {
        let names: Vec<_> = Shader::ALL.iter().map(|s| s.name()).collect();
        format!("unknown shader '{s}'; expected one of {}", names.join(", "))
    })
}

fn parse_family(s: &str) -> std::result::Result<Family, String> {
    match s.to_ascii_lowercase().as_str() {
        "chair" => Ok(Family::Chair),
        "table" => Ok(Family::Table),
        "sofa" => Ok(Family::Sofa),
        "primitive" => Ok(Family::Primitive),
        "creature" => Ok(Family::Creature),
        _ => Err(format!("unknown shape '{s}'; expected chair, table, sofa, primitive or creature")),
    }
}

fn voxel_err(e: voxel::VoxelError) -> Error {
    Error::Invalid(e.to_string())
}

/// Loads the grid the flags name, and says what it is.
pub fn load(a: &SceneArgs) -> Result<(VoxelGrid, String)> {
    let Some(path) = &a.voxels else {
        if let Some(family) = a.shape {
            let shape = family.generate(a.seed);
            let grid = if a.colour { shape.to_coloured_grid(a.resolution, a.seed) } else { shape.to_grid(a.resolution) }.map_err(voxel_err)?;
            let paint = if a.colour { "painted " } else { "" };
            let what = format!("{paint}procedural {family:?} seed {} at {}^3", a.seed, a.resolution).to_lowercase();
            return Ok((grid, what));
        }
        return Ok((voxel::bunny(), "the embedded Stanford bunny at 64^3".into()));
    };
    let grid = voxel::load(path, a.resolution).map_err(voxel_err)?;
    let d = grid.dims();
    Ok((grid, format!("{} ({}x{}x{})", display(path), d[0], d[1], d[2])))
}

fn display(p: &Path) -> String {
    p.display().to_string()
}

/// `x` with at most two decimals and no trailing zeros (26.4, not 26.400000000000002).
fn short(x: f64) -> String {
    let s = format!("{x:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Loads, renders, writes the PNG, and reports what was rendered and how long it took.
pub fn run(a: TruthArgs) -> Result<()> {
    let t0 = Instant::now();
    a.scene.validate(a.size as usize)?;
    super::output::check_png_out(&a.out)?;
    let (grid, what) = load(&a.scene)?;
    if let Some(path) = &a.out_voxels {
        // A grey grid may go to .vox too (MagicaVoxel's own file), not only to what `invert`
        // writes grey grids as; a coloured one never to .binvox.
        let vox = path.extension().is_some_and(|e| e == "vox");
        super::invert::write_voxels(&grid, path, super::invert::voxels_format(path, grid.colour().is_some() || vox)?)?;
        println!("wrote {}", path.display());
    }
    let gpu = Gpu::new()?;
    let (view, light) = (a.scene.view(), a.scene.light());
    let renderer = RayMarcher::new(&gpu).with_options(Options { supersample: a.supersample, ..Options::default() });
    let t1 = Instant::now();
    let img = renderer.render(&gpu, &grid, &view, &light, a.shader, a.size)?;
    let render_s = t1.elapsed().as_secs_f64();
    img.save_png(&a.out)?;
    let what = format!("{what}: shader {}, {}x{} px (supersample {})", a.shader.name(), a.size, a.size, a.supersample);
    println!("rendered {}", a.scene.describe(&what));
    println!("wrote {} in {:.2} s (render {:.2} s, on {})", a.out.display(), t0.elapsed().as_secs_f64(), render_s, gpu.info.name);
    Ok(())
}
