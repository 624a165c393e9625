//! Texture recovery: gradient descent on the texture decoder's code (`nn::texture`) so that a
//! coloured RenderNet, rendering a known shape painted with the decoded texture at known
//! cameras and lights, reproduces one or more images of it (the paper's texture code
//! inversion). Multi-start: paints of the training distribution are scored by image loss in
//! batches, the best few refined by Adam. The code read back is a paint
//! ([`Paint::from_code`]): two colours, the pattern, its period and axis.

use super::code::{self, Descent, Front};
use super::{Inverter, ShapeView};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::nn::camera;
use crate::nn::texture::TexturePreset;
use crate::rng::SplitMix64;
use crate::voxel::VoxelGrid;
use crate::voxel::shapes::{Paint, TEXTURE_CODE};

/// Settings of the texture-code search.
#[derive(Clone, Debug)]
pub struct TextureOptions {
    /// Adam steps per refined start.
    pub steps: usize,
    /// Adam's step on the code (which lives in 0..1).
    pub lr: f64,
    /// Starting code; `None` scores [`texture_starts`] of `candidates` paints.
    pub start: Option<[f32; TEXTURE_CODE]>,
    /// Paints scored as starts.
    pub candidates: usize,
    /// Best-scoring starts refined by Adam; the lowest final loss wins.
    pub keep: usize,
}

impl Default for TextureOptions {
    fn default() -> Self {
        TextureOptions { steps: 40, lr: 0.02, start: None, candidates: 32, keep: 2 }
    }
}

/// What the texture search found.
#[derive(Clone, Debug)]
pub struct TextureEstimate {
    /// The best code.
    pub code: [f32; TEXTURE_CODE],
    /// The paint it describes.
    pub paint: Paint,
    /// The start that scored best before descent.
    pub start_paint: Paint,
    /// The shape painted with `paint` (the shape's own grid when it is a cube, else the
    /// decoder's side).
    pub grid: VoxelGrid,
    /// The winning start's image MSE after each step, best so far.
    pub curve: Vec<f64>,
}

/// Stream of the starting paints, apart from every dataset's and the decoder's training.
const STARTS: u64 = 0x57a7_7e5;

/// `n` starting paints: draws of the `dataset --colour` distribution from a fixed stream (half
/// plain, a quarter striped, a quarter checkered), the same on every call.
pub fn texture_starts(n: usize) -> Vec<Paint> {
    (0..n).map(|i| Paint::random(&mut SplitMix64::new(STARTS, i as u64))).collect()
}

fn to_code(z: &[f32]) -> [f32; TEXTURE_CODE] {
    let mut c = [0.0; TEXTURE_CODE];
    c.copy_from_slice(z);
    c
}

impl Inverter {
    /// Recovers the texture of `shape` seen in `views` (each image with its camera and
    /// light) as a code of the texture decoder `tp` with weights `tex_weights` (`tex.*`).
    /// The inverter must hold a coloured RenderNet ([`crate::nn::rendernet::Preset::with_colour`]);
    /// the shape is read at the decoder's side whatever the preset's input says.
    pub fn recover_texture(&self, gpu: &Gpu, tp: &TexturePreset, tex_weights: &[u8], shape: &VoxelGrid, views: &[ShapeView], o: &TextureOptions) -> Result<TextureEstimate> {
        if !self.preset.colour {
            return Err(Error::Invalid(format!("{}: texture recovery needs coloured RenderNet weights (a grey network renders no texture)", self.name)));
        }
        let inv = self.reading(tp.res);
        let cube = shape.resample_to(tp.res).map_err(|e| Error::Invalid(format!("shape: {e}")))?;
        let occupancy = camera::input_values(&cube);
        let starts: Vec<Vec<f32>> = match o.start {
            Some(z) => vec![z.to_vec()],
            None => texture_starts(o.candidates.max(1)).iter().map(|p| p.code().to_vec()).collect(),
        };
        let none = |z: &[f32]| (0.0, vec![0.0; z.len()]);
        let d = Descent { steps: o.steps, lr: o.lr, keep: o.keep, silhouette: false, penalty: &none };
        let f = code::search(&inv, gpu, &Front::Texture { preset: tp, weights: tex_weights, occupancy: &occupancy }, views, starts, &d)?;
        let code = to_code(&f.code);
        let paint = Paint::from_code(&code);
        let [a, b, c] = shape.dims();
        let base = if a == b && b == c { shape.clone() } else { cube };
        let side = base.dims()[0];
        let grid = base.with_colour(paint.field(side)).map_err(|e| Error::Invalid(e.to_string()))?;
        Ok(TextureEstimate { code, paint, start_paint: Paint::from_code(&to_code(&f.start)), grid, curve: f.curve })
    }
}

/// One held-out painted shape's texture recovery, scored.
#[derive(Clone, Debug)]
pub struct TextureError {
    /// Procedural family and seed of the shape.
    pub shape: String,
    /// The paint it was painted with.
    pub paint: Paint,
    /// The paint recovered.
    pub recovered: Paint,
    /// Images the texture was recovered from.
    pub views: usize,
    /// Object PSNR (dB) of the reference renderer drawing the shape painted with the
    /// recovered paint, against it painted with the true one, from a view no input image had.
    pub novel_view_psnr: f64,
    /// The same with the best start before descent (picking among the starting paints).
    pub start_psnr: f64,
    /// The same with the shape left white (the floor: no texture recovered).
    pub white_psnr: f64,
    /// Mean absolute error of the colours, 0..1 (colour `a` for a plain paint, `a` and `b`
    /// otherwise).
    pub colour_error: f64,
    /// Whether the pattern (plain, stripes along the right axis, checkerboard) is right.
    pub pattern_right: bool,
    /// Wall time of the search.
    pub seconds: f64,
}

/// Whether two paints share their pattern kind (and the stripes' axis).
fn same_pattern(a: &Paint, b: &Paint) -> bool {
    use crate::voxel::shapes::Pattern::{Checker, Plain, Stripes};
    match (a.pattern, b.pattern) {
        (Plain, Plain) | (Checker { .. }, Checker { .. }) => true,
        (Stripes { axis: x, .. }, Stripes { axis: y, .. }) => x == y,
        _ => false,
    }
}

/// Recovers the paints of `samples` procedural shapes (the four of
/// [`crate::voxel::shapes::Family::ALL`] in turn, seeds no dataset draws) painted with the
/// texture decoder's held-out paints (never seen in its training), each from `views`
/// reference images at random cameras (radius 3.3-4.5) and lights, both known; scores each
/// recovered paint from one more random view. `progress(done, total)`.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_textures(
    gpu: &Gpu,
    inv: &Inverter,
    tp: &TexturePreset,
    tex_weights: &[u8],
    samples: usize,
    views: usize,
    o: &TextureOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<TextureError>> {
    use crate::reference::{Light, Options, RayMarcher, Shader, View};
    use crate::voxel::shapes::Family;
    if views == 0 {
        return Err(Error::Invalid("texture evaluation needs at least one view per shape".into()));
    }
    const RES: usize = 64;
    let rm = RayMarcher::new(gpu).with_options(Options { supersample: 2, ..Options::default() });
    let size = inv.size() as u32;
    let mut out = Vec::with_capacity(samples);
    for i in 0..samples {
        let family = Family::ALL[i % Family::ALL.len()];
        let seed = 0x7e47_0000 + i as u64;
        let shape = family.generate(seed).to_grid(RES).map_err(|e| Error::Invalid(e.to_string()))?;
        let paint = crate::train::texture::held_out_paint(i);
        let painted = |p: &Paint| shape.clone().with_colour(p.field(RES)).map_err(|e| Error::Invalid(e.to_string()));
        let truth = painted(&paint)?;
        let poses = crate::data::generate::sample_poses(seed, views + 1, (3.3, 4.5));
        let cam = |k: usize| {
            let ([az, el, r], [la, le, ..]) = poses[k];
            (View { azimuth: az as f64, elevation: el as f64, radius: r as f64 }, Light { azimuth: la as f64, elevation: le as f64, ..Light::default() })
        };
        let images: Vec<_> = (0..views).map(|k| rm.render(gpu, &truth, &cam(k).0, &cam(k).1, Shader::Phong, size)).collect::<Result<_>>()?;
        let sv: Vec<ShapeView> = images.iter().enumerate().map(|(k, image)| ShapeView { image, view: cam(k).0, light: cam(k).1 }).collect();
        let t = std::time::Instant::now();
        let est = inv.recover_texture(gpu, tp, tex_weights, &shape, &sv, o)?;
        let seconds = t.elapsed().as_secs_f64();
        let (nv, nl) = cam(views);
        let want = rm.render(gpu, &truth, &nv, &nl, Shader::Phong, size)?;
        let score = |g: &VoxelGrid| -> Result<f64> { Ok(crate::metrics::object_psnr(&rm.render(gpu, g, &nv, &nl, Shader::Phong, size)?, &want)) };
        let pattern_right = same_pattern(&est.paint, &paint);
        let err = |x: glam::Vec3, y: glam::Vec3| ((x - y).abs().element_sum() / 3.0) as f64;
        let plain = matches!(paint.pattern, crate::voxel::shapes::Pattern::Plain);
        let colour_error = if plain { err(est.paint.a, paint.a) } else { 0.5 * (err(est.paint.a, paint.a) + err(est.paint.b, paint.b)) };
        out.push(TextureError {
            shape: format!("{family:?} {seed}").to_lowercase(),
            paint,
            recovered: est.paint,
            views,
            novel_view_psnr: score(&painted(&est.paint)?)?,
            start_psnr: score(&painted(&est.start_paint)?)?,
            white_psnr: score(&shape)?,
            colour_error,
            pattern_right,
            seconds,
        });
        progress(i + 1, samples);
    }
    Ok(out)
}
