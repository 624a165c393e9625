//! Inverse rendering through a frozen RenderNet: recover the camera pose (azimuth, elevation,
//! radius) and the light direction that make the network render a given image of a known
//! voxel grid (the paper's Section 5 with the shape given).
//!
//! Strategy (the paper's, plus radius): a coarse grid of azimuth x elevation starts is
//! scored by how well the network's predicted mask overlaps the image's foreground (light
//! does not change a silhouette, so this search ignores it); each start's radius is then set
//! from the ratio of silhouette areas (orthographic: area scales with `1 / radius^2`) and
//! every start is re-scored there. Every distinct view (with its opposite-side twin) is then
//! ranked by image MSE under its best light, and the grid is subdivided around the best
//! (the 8 views half a step away), as the paper does. The survivors are refined together,
//! one batch, by Adam on
//! `(azimuth, elevation, ln radius, light azimuth, light elevation)` with the image MSE as
//! loss; gradients reach the pose through the resampling op and the light through the Phong
//! op. The start with the lowest final MSE wins ([`Pick::Network`]), or, by default
//! ([`Pick::Exact`]) the exact render of the known grid arbitrates: the hypotheses, their
//! far-side twins and a coarse camera grid are scored on it, the best few refined on it, and
//! the light searched on it at the camera that wins (`pick.rs`, `exact.rs`).

mod code;
mod eval;
mod exact;
mod light;
mod pick;
mod window;
use window::Window;
mod shape;
mod texture;
mod starts;
pub use texture::{TextureError, TextureEstimate, TextureOptions, evaluate_textures, texture_starts};
pub use pick::Pick;
pub use eval::{InvertError, angle_between, evaluate, light_direction, view_direction};
use eval::phong_target;
pub use shape::{JointEstimate, PoseSource, ShapeError, ShapeEstimate, ShapeOptions, ShapeView, decode_codes, evaluate_shapes};

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::{Executor, Op, Value};
use crate::metrics::FOREGROUND;
use crate::nn::camera;
use crate::nn::rendernet::{Head, Preset, RenderNet, phong_of};
use crate::ops::loss::Loss;
use crate::reference::{Image, Light, View};
use crate::voxel::VoxelGrid;
use starts::{POLISH_STEP_DEGREES, POLISHED, best_of_neighbours, distinct_lights, light_grid, light_starts, neighbours, with_twins};

/// Search settings.
#[derive(Clone, Debug)]
pub struct InvertOptions {
    /// Azimuth starts, evenly spaced over 360 degrees.
    pub azimuths: usize,
    /// Elevation starts, evenly spaced inside (0, 180).
    pub elevations: usize,
    /// Starts kept for gradient refinement.
    pub keep: usize,
    /// Adam steps of the refinement.
    pub steps: usize,
    /// Initial step of Adam for the angles, degrees (the log-radius step is this / 100).
    pub lr_degrees: f64,
    /// What picks the camera among the refined hypotheses.
    pub pick: Pick,
}

impl Default for InvertOptions {
    fn default() -> Self {
        // 12 x 5 rather than 24 x 10: the finer grid put 90% of 30 unseen chairs within 10
        // degrees instead of 80%, but 59% of the 27 real meshes instead of 67%, for 1.35x
        // the time on lavapipe (README, "Inverse rendering"); `--azimuths 24 --elevations 10`.
        InvertOptions { azimuths: 12, elevations: 5, keep: 4, steps: 60, lr_degrees: 3.0, pick: Pick::Exact }
    }
}

/// What the inversion found.
#[derive(Clone, Debug)]
pub struct Estimate {
    /// Recovered camera.
    pub view: View,
    /// Recovered light (the network's material constants, white).
    pub light: Light,
    /// The search's light, before a light network picked `light`
    /// ([`Inverter::with_light_network`]; without one, `light`): the exact light at the polished camera with
    /// [`Pick::Exact`], the searching network's own with [`Pick::Network`].
    pub search_light: Light,
    /// The camera the network's own image MSE picked ([`Pick::Network`]); with
    /// [`Pick::Exact`] the exact maps may have picked another (`view`).
    pub network_view: View,
    /// Image MSE of the network's render at the estimate against the input (the light
    /// network's, when there is one: [`Inverter::with_light_network`]).
    pub mse: f64,
    /// Best MSE over the kept starts after each refinement step, then after each step of
    /// the light polish (`steps / 2` more; never above the refinement's last).
    pub curve: Vec<f64>,
    /// The network's render at the estimate (the light network's, when there is one).
    pub image: Image,
}

/// Radii the search keeps to (the training set's range, with margin).
const RADIUS: (f64, f64) = (2.0, 9.0);
/// Views of the search's ranking (before subdivision) that [`Pick::Exact`] scores beside the
/// refined hypotheses, with their twins: 24 found one more real mesh than the subdivided 8
/// alone; scoring all of them (about 40) gave the same cameras for more time (README, "The
/// exact renderer picks the camera").
const EXACT_UNREFINED: usize = 24;
/// Radius of the coarse silhouette pass, mid-range of the training views.
const COARSE_RADIUS: f64 = 4.65;

/// Unknowns of one start: camera azimuth, elevation (degrees), ln radius, light azimuth,
/// light elevation (degrees).
#[derive(Clone, Copy, Debug)]
struct Vars([f64; 5]);

impl Vars {
    fn view(&self) -> View {
        View { azimuth: self.0[0].rem_euclid(360.0), elevation: self.0[1], radius: self.0[2].exp() }
    }

    fn light(&self, base: &Light) -> Light {
        Light { azimuth: self.0[3], elevation: self.0[4], ..*base }
    }

    /// Keeps polar angles inside (0, 180) and the radius in range.
    fn clamp(&mut self) {
        self.0[1] = self.0[1].clamp(1.0, 179.0);
        self.0[2] = self.0[2].clamp(RADIUS.0.ln(), RADIUS.1.ln());
        self.0[4] = self.0[4].clamp(1.0, 179.0);
    }
}

/// A frozen RenderNet set up for inversion at one image size.
pub struct Inverter {
    preset: Preset,
    head_light: Light,
    weights: Vec<u8>,
    name: String,
    size: usize,
    /// A second network whose maps pick the final light at the recovered camera
    /// ([`Inverter::with_light_network`]).
    light_by: Option<Box<Inverter>>,
}

impl Inverter {
    /// `weights`: Phong RenderNet parameters of `preset` (safetensors bytes, `name` labels
    /// them in errors); `light` gives the material constants the network was trained with.
    /// Grids are read at the side the weights record ([`Preset::for_weights`]), as
    /// [`crate::nn::render::Renderer`] reads them; malformed bytes are an error.
    pub fn new(preset: Preset, weights: &[u8], name: &str, light: Light) -> Result<Inverter> {
        Ok(Inverter::exactly(preset.for_weights(weights, name)?, weights, name, light))
    }

    /// The inverter for `preset` as given (its input side kept).
    fn exactly(preset: Preset, weights: &[u8], name: &str, light: Light) -> Inverter {
        let size = preset.image_for(preset.cam);
        Inverter { preset, head_light: light, weights: weights.to_vec(), name: name.to_string(), size, light_by: None }
    }

    /// This inverter with `other` choosing the light: after the camera and light search
    /// through this network, the light becomes `other`'s best light at the recovered camera
    /// ([`Inverter::light_optimum`]), and `other` draws and scores the estimate. Base picking
    /// after tiny's search measured closer to the true light on procedural chairs, not on
    /// real meshes (README "Inverse rendering"). `other` must render images of this one's
    /// size; it shades with this one's material constants (the image's).
    pub fn with_light_network(mut self, mut other: Inverter) -> Result<Inverter> {
        if other.size != self.size {
            return Err(Error::Invalid(format!(
                "light network {}: renders {} px images, the inverter {} px ({})",
                other.name, other.size, self.size, self.name
            )));
        }
        other.head_light = self.head_light;
        self.light_by = Some(Box::new(other));
        Ok(self)
    }

    /// The network that picks the final light: the one of [`Inverter::with_light_network`],
    /// else this one.
    pub fn light_network(&self) -> &Inverter {
        self.light_by.as_deref().unwrap_or(self)
    }

    /// The same network reading grids at `res`^3: what a decoder in front of it produces.
    fn reading(&self, res: usize) -> Inverter {
        // No light network: the shape and texture searches that read through it pick no light.
        Inverter::exactly(Preset { input: res, ..self.preset.clone() }, &self.weights, &self.name, self.head_light)
    }

    /// Image side the network renders (the input image must have it).
    pub fn size(&self) -> usize {
        self.size
    }

    fn executor(&self, gpu: &Gpu, batch: usize, loss: bool, win: &Window) -> Result<(RenderNet, Executor, Option<(Value, Value)>)> {
        let p = &self.preset;
        if !p.fully_convolutional() {
            return Err(Error::Invalid(format!("inverse rendering needs RenderNet weights; preset '{}' is a baseline without normal maps", p.name)));
        }
        let mut net = RenderNet::build(p, Head::Phong(phong_of(&self.head_light)), batch, [win.cam[2], win.cam[3]], false)?;
        let mut extra = None;
        if loss {
            let [h, w] = win.pixel_dims();
            let target = net.graph.input("target.image", &[batch, 3, h, w])?;
            let l = net.graph.apply("loss.invert", Op::Loss(Loss::Mse), &[net.image, target])?;
            extra = Some((target, l));
        }
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        ex.load_params_bytes(gpu, &self.weights, &self.name)?;
        ex.training = false;
        ex.freeze_params();
        ex.keep(net.image);
        // The maps: the silhouette scores read the mask, the light ranking all three.
        for m in net.maps.into_iter().flatten() {
            ex.keep(m);
        }
        if loss {
            ex.want_grad(net.pose);
            ex.want_grad(net.light.expect("Phong head"));
        }
        Ok((net, ex, extra))
    }

    /// Feeds `grid` once per batch entry, and each start's pose (seen through `win`) and light.
    fn feed(&self, gpu: &Gpu, net: &RenderNet, ex: &Executor, grid: &[f32], vars: &[Vars], win: &Window) -> Result<()> {
        let p = &self.preset;
        let n = vars.len();
        ex.feed(gpu, net.grid, &grid.repeat(n))?;
        let pose: Vec<f32> = vars.iter().flat_map(|v| camera::pose_for_view(&v.view(), p.input, p.cam, Some(win.cam))).collect();
        ex.feed(gpu, net.pose, &pose)?;
        let light: Vec<f32> = vars.iter().flat_map(|v| camera::light_values(&v.light(&self.head_light))).collect();
        ex.feed(gpu, net.light.expect("Phong head"), &light)
    }

    /// Scores starts by silhouette inside `win`: the predicted mask's area and IoU with `fg`
    /// (the window's pixels). `sil` is a forward-only network built once per inversion for
    /// `batch` starts; a shorter list is padded with its last start.
    fn silhouettes(&self, gpu: &Gpu, sil: &mut (RenderNet, Executor), grid: &[f32], fg: &[bool], starts: &[Vars], win: &Window) -> Result<Vec<(f64, f64)>> {
        let (net, ex) = sil;
        let batch = net.graph.info(net.pose).shape[0];
        let mut padded = starts.to_vec();
        padded.resize(batch, *starts.last().expect("at least one start"));
        self.feed(gpu, net, ex, grid, &padded, win)?;
        ex.forward(gpu)?;
        let mask = ex.read(gpu, net.maps.expect("Phong head")[2])?;
        Ok(mask
            .chunks(fg.len())
            .take(starts.len())
            .map(|m| {
                let (mut inter, mut uni, mut area) = (0usize, 0usize, 0usize);
                for (&v, &t) in m.iter().zip(fg) {
                    let p = v > 0.5;
                    area += p as usize;
                    inter += (p && t) as usize;
                    uni += (p || t) as usize;
                }
                (area as f64, if uni == 0 { 1.0 } else { inter as f64 / uni as f64 })
            })
            .collect())
    }

    /// Checks `target`'s size and returns its foreground mask (full image).
    fn foreground(&self, target: &Image) -> Result<Vec<bool>> {
        if target.channels != 3 || target.size != self.size {
            return Err(Error::Invalid(format!(
                "the image is {}x{} with {} channels; preset '{}' inverts {s}x{s} RGB images",
                target.size, target.size, target.channels, self.preset.name, s = self.size
            )));
        }
        let hw = self.size * self.size;
        let fg: Vec<bool> = (0..hw).map(|i| (0..3).any(|c| target.data[c * hw + i] > FOREGROUND)).collect();
        if !fg.contains(&true) {
            return Err(Error::Invalid("the image has no foreground (every pixel is black): nothing to invert".into()));
        }
        Ok(fg)
    }

    /// Recovers pose and light for `target` (RGB, the network's image size) of `grid`.
    pub fn invert(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, o: &InvertOptions, mut progress: impl FnMut(usize, f64)) -> Result<Estimate> {
        if o.azimuths == 0 || o.elevations == 0 || o.keep == 0 {
            return Err(Error::Invalid("azimuth and elevation starts and kept starts must be at least 1".into()));
        }
        let fg_full = self.foreground(target)?;
        let win = Window::around(&self.preset, &fg_full, self.size);
        let fg = win.crop_mask(&fg_full, self.size);
        let target_area = fg.iter().filter(|&&f| f).count() as f64;
        let gv = self.grid_values(grid)?;
        let base = Light::default();
        let (net, ex, _) = self.executor(gpu, o.azimuths, false, &win)?;
        let mut sil = (net, ex);
        // Coarse pass: silhouettes at the mid radius, one elevation row per batch, for each
        // view's radius (its overlap is scored again at that radius below).
        let mut starts: Vec<Vars> = Vec::new();
        for e in 0..o.elevations {
            let el = 180.0 * (e as f64 + 0.5) / o.elevations as f64;
            let row: Vec<Vars> = (0..o.azimuths)
                .map(|a| Vars([360.0 * a as f64 / o.azimuths as f64, el, COARSE_RADIUS.ln(), base.azimuth, base.elevation]))
                .collect();
            for ((area, _), mut v) in self.silhouettes(gpu, &mut sil, &gv, &fg, &row, &win)?.into_iter().zip(row) {
                // Area scales with 1 / radius^2: the radius that matches the image's area.
                v.0[2] = (COARSE_RADIUS * (area.max(1.0) / target_area).sqrt()).ln();
                v.clamp();
                starts.push(v);
            }
        }
        // Re-score every coarse start at its own radius: the silhouette order decides which
        // of two near-duplicate views (within 30 degrees) the pool keeps.
        let mut rescored = Vec::new();
        for chunk in starts.chunks(o.azimuths) {
            for ((_, iou), v) in self.silhouettes(gpu, &mut sil, &gv, &fg, chunk, &win)?.into_iter().zip(chunk) {
                rescored.push((iou, *v));
            }
        }
        rescored.sort_by(|a, b| b.0.total_cmp(&a.0));
        // Every distinct view (twins included), each with its best light start, ranked by
        // image MSE: the shading tells front from back where the silhouette cannot, and a
        // silhouette cut to the best 16 or 12 views lost the true side of 1 of 8 held-out
        // chairs; the refinement starts from the views the image itself favours.
        let target_crop = win.crop_rgb(target);
        let views = with_twins(rescored.iter().map(|s| s.1), usize::MAX);
        let mut pool: Vec<(f64, Vars)> = self.ranked_lights(gpu, &mut sil, &gv, &target_crop, &views, &win, &light_starts())?.into_iter().map(|r| r[0]).collect();
        pool.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Subdivision (the paper's): the coarse grid can leave the true camera 20 degrees
        // from its nearest start, far enough for a wrong view to score better. Around each of
        // the best 2 * keep views, the 8 views half a step away are ranked the same way and
        // the best of the 9 stands for it.
        // The best views before subdivision are hypotheses for the exact pick too: on the real
        // meshes they found a camera the refined starts had missed (README "The exact
        // renderer picks the camera").
        let coarse: Vec<Vars> = pool.iter().take(EXACT_UNREFINED).map(|p| p.1).collect();
        pool.truncate(2 * o.keep);
        let (daz, del) = (180.0 / o.azimuths as f64, 90.0 / o.elevations as f64);
        let around: Vec<Vars> = pool.iter().flat_map(|p| neighbours(p.1, daz, del)).collect();
        let ranked = self.ranked_lights(gpu, &mut sil, &gv, &target_crop, &around, &win, &light_starts())?;
        best_of_neighbours(&mut pool, &ranked);
        let pool_views: Vec<Vars> = pool.iter().map(|p| p.1).chain(coarse).collect();
        let mut vars: Vec<Vars> = pool.into_iter().take(o.keep).map(|p| p.1).collect();
        let (mut best, mut curve, mut candidates) = self.refine_each(gpu, &gv, &target_crop, &mut vars, o, &mut progress, &win)?;
        // Light polish: Adam from the 12 light starts can settle in a local minimum tens of
        // degrees from the network's own optimum (measured: 51.6 degrees off on a chair
        // whose optimum at the true camera is 1.9 degrees off). So the light is searched
        // again over a 5-degree grid of all directions at the estimated camera, and
        // camera and light refined once more from the best POLISHED lights of that grid at
        // least 30 degrees apart (the network's light optimum is shallow: several far-apart
        // lights score alike); the lower MSE wins.
        let (again, tail, polished) = self.polish(gpu, &mut sil, &gv, &target_crop, best, o, &win)?;
        let last = *curve.last().expect("at least one step");
        if tail.last().is_some_and(|&m| m < last) {
            best = again;
        }
        curve.extend(tail.into_iter().map(|m| m.min(last)));
        candidates.extend(polished);
        let network_view = best.view();
        if o.pick == Pick::Exact {
            let refined: Vec<Vars> = std::iter::once(best).chain(candidates.iter().map(|c| c.1)).collect();
            // The pick's camera comes out of the exact polish (README "The exact polish and
            // the exact light"), which carries its light locally from the 5-degree grid's
            // best at its start; a fresh search of every direction at the polished camera, in
            // the scene chosen there, lands nearer the truth (real meshes: 11.3 -> 9.5
            // degrees median).
            let (v, mut scene) = self.exact_pick(gpu, grid, target, &refined, &pool_views)?;
            best = Vars([v.azimuth, v.elevation, v.radius.ln(), best.0[3], best.0[4]]);
            // At the estimate's own view (its radius through ln and exp), so that
            // `light_exact(estimate.view)` gives this light back.
            let l = self.light_in(gpu, &mut scene, &best.view())?;
            (best.0[3], best.0[4]) = (l.azimuth, l.elevation);
        }
        // A light network then picks the light at that camera, its best of the polish grid
        // (README "Inverse rendering": with tiny searching and base picking, closer to the
        // truth on 11 of 16 unseen chairs, on 4 of 12 real meshes).
        let search_light = best.light(&self.head_light);
        if let Some(by) = &self.light_by {
            let (l, _) = by.light_optimum(gpu, grid, target, &best.view())?;
            (best.0[3], best.0[4]) = (l.azimuth, l.elevation);
        }
        // The estimate's picture and score: the whole frame, once, by the network that
        // chose the light.
        let by = self.light_network();
        let gv = if self.light_by.is_some() { by.grid_values(grid)? } else { gv };
        let full = Window::full(&by.preset, by.size);
        let (net, mut ex, _) = by.executor(gpu, 1, false, &full)?;
        by.feed(gpu, &net, &ex, &gv, &[best], &full)?;
        ex.forward(gpu)?;
        let img: Vec<f32> = ex.read(gpu, net.image)?.into_iter().map(|x| x.clamp(0.0, 1.0)).collect();
        let mse = img.iter().zip(&target.data).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>() / img.len() as f64;
        Ok(Estimate { view: best.view(), light: best.light(&by.head_light), search_light, network_view, mse, curve, image: Image { channels: 3, size: by.size, data: img } })
    }

    /// The light polish from camera and light `best`: every light of the polish grid scored
    /// at that camera, then camera and light refined from the best [`POLISHED`] of them at
    /// least 30 degrees apart (`o.steps / 2` steps); the refinement's best and its curve.
    #[allow(clippy::too_many_arguments)]
    fn polish(&self, gpu: &Gpu, sil: &mut (RenderNet, Executor), gv: &[f32], target: &[f32], best: Vars, o: &InvertOptions, win: &Window) -> Result<(Vars, Vec<f64>, Vec<(f64, Vars)>)> {
        let grid_lights = self.ranked_lights(gpu, sil, gv, target, &[best], win, &light_grid(POLISH_STEP_DEGREES))?.remove(0);
        let mut relit = distinct_lights(grid_lights.into_iter().map(|r| r.1), POLISHED);
        let polish = InvertOptions { steps: o.steps / 2, ..o.clone() };
        self.refine_each(gpu, gv, target, &mut relit, &polish, &mut |_, _| {}, win)
    }

    /// The image MSE over the window around `target`'s foreground (clamped, as
    /// [`Estimate::curve`] scores) after the search's refinement (`o.steps` Adam steps on
    /// camera and light) started at `view` and `light`: started at the true camera and the
    /// network's best light there ([`Inverter::light_optimum`]), the lowest score the search
    /// could reach near the truth, which tells a search's failure from the network's.
    pub fn refined_mse(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, view: &View, light: &Light, o: &InvertOptions) -> Result<f64> {
        let (win, gv, t) = self.windowed(grid, target)?;
        let mut vars = [Vars([view.azimuth, view.elevation, view.radius.ln(), light.azimuth, light.elevation])];
        let (_, curve) = self.refine(gpu, &gv, &t, &mut vars, o, &mut |_, _| {}, &win)?;
        Ok(*curve.last().expect("at least one step"))
    }

    /// The image MSE (unclamped, as the loss op computes it, over the window around the
    /// target's foreground that the search renders) of each start in `unknowns` —
    /// `[azimuth, elevation, ln radius, light azimuth, light elevation]`, degrees — against
    /// `target`, with its gradient with respect to those five numbers: what the refinement
    /// descends, exposed for callers with their own optimiser (and for testing against
    /// finite differences).
    pub fn gradient(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, unknowns: &[[f64; 5]]) -> Result<Vec<(f64, [f64; 5])>> {
        let (win, gv, t) = self.windowed(grid, target)?;
        let vars: Vec<Vars> = unknowns.iter().map(|&u| Vars(u)).collect();
        let mut d = Descent::new(self, gpu, &t, vars.len(), &win)?;
        let (img, grads) = d.step(self, gpu, &gv, &vars, &win)?;
        Ok(img
            .chunks(t.len())
            .zip(grads)
            .map(|(y, g)| (y.iter().zip(&t).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>() / t.len() as f64, g))
            .collect())
    }

    /// What a search of one image renders: the window around `target`'s foreground, the
    /// network's input values of `grid` and the target's pixels inside the window.
    fn windowed(&self, grid: &VoxelGrid, target: &Image) -> Result<(Window, Vec<f32>, Vec<f32>)> {
        let (win, t) = self.window(target)?;
        Ok((win, self.grid_values(grid)?, t))
    }

    /// The window around `target`'s foreground and the target's pixels inside it.
    fn window(&self, target: &Image) -> Result<(Window, Vec<f32>)> {
        let win = Window::around(&self.preset, &self.foreground(target)?, self.size);
        let t = win.crop_rgb(target);
        Ok((win, t))
    }

    fn grid_values(&self, grid: &VoxelGrid) -> Result<Vec<f32>> {
        let p = &self.preset;
        let g = if grid.dims() == [p.input; 3] { grid.clone() } else { grid.resample_to(p.input)? };
        Ok(camera::input_values_with(&g, p.in_channels()))
    }

    /// Adam on every kept start at once (rendering `win` only, against the target's pixels
    /// there, `target`); returns the best start and the best MSE after each step.
    #[allow(clippy::too_many_arguments)]
    fn refine(&self, gpu: &Gpu, gv: &[f32], target: &[f32], vars: &mut [Vars], o: &InvertOptions, progress: &mut impl FnMut(usize, f64), win: &Window) -> Result<(Vars, Vec<f64>)> {
        let (best, curve, _) = self.refine_each(gpu, gv, target, vars, o, progress, win)?;
        Ok((best, curve))
    }

    /// [`Inverter::refine`], also returning each start's best (MSE, unknowns) over its steps.
    #[allow(clippy::too_many_arguments)]
    fn refine_each(&self, gpu: &Gpu, gv: &[f32], target: &[f32], vars: &mut [Vars], o: &InvertOptions, progress: &mut impl FnMut(usize, f64), win: &Window) -> Result<(Vars, Vec<f64>, Vec<(f64, Vars)>)> {
        let n = vars.len();
        let mut each: Vec<(f64, Vars)> = vars.iter().map(|v| (f64::INFINITY, *v)).collect();
        let mut d = Descent::new(self, gpu, target, n, win)?;
        let (mut m, mut v) = (vec![[0.0f64; 5]; n], vec![[0.0f64; 5]; n]);
        let (b1, b2) = (0.9f64, 0.999f64);
        let mut curve = Vec::with_capacity(o.steps);
        let mut best: Option<(f64, Vars)> = None;
        for step in 0..=o.steps {
            let (img, grads) = d.step(self, gpu, gv, vars, win)?;
            for (k, y) in img.chunks(target.len()).enumerate() {
                // Scored as the user sees it: clamped to [0, 1].
                let mse = y.iter().zip(target).map(|(a, b)| ((a.clamp(0.0, 1.0) - b) as f64).powi(2)).sum::<f64>() / target.len() as f64;
                if best.is_none_or(|b| mse < b.0) {
                    best = Some((mse, vars[k]));
                }
                if mse < each[k].0 {
                    each[k] = (mse, vars[k]);
                }
            }
            let b = best.expect("at least one start").0;
            curve.push(b);
            progress(step, b);
            if step == o.steps {
                break;
            }
            // Step size decays linearly to a tenth: large moves first, then settling.
            let lr = o.lr_degrees * (1.0 - 0.9 * step as f64 / o.steps.max(1) as f64);
            let t = (step + 1) as i32;
            for (k, g) in grads.iter().enumerate() {
                for j in 0..5 {
                    m[k][j] = b1 * m[k][j] + (1.0 - b1) * g[j];
                    v[k][j] = b2 * v[k][j] + (1.0 - b2) * g[j] * g[j];
                    let mh = m[k][j] / (1.0 - b1.powi(t));
                    let vh = v[k][j] / (1.0 - b2.powi(t));
                    let scale = if j == 2 { lr / 100.0 } else { lr };
                    vars[k].0[j] -= scale * mh / (vh.sqrt() + 1e-12);
                }
                vars[k].clamp();
            }
        }
        Ok((best.expect("at least one start").1, curve, each))
    }
}

/// A frozen network with an MSE loss against one target (a window's pixels), for a batch
/// of starts.
struct Descent {
    net: RenderNet,
    ex: Executor,
    loss: Value,
}

impl Descent {
    fn new(inv: &Inverter, gpu: &Gpu, target: &[f32], n: usize, win: &Window) -> Result<Descent> {
        let (net, ex, extra) = inv.executor(gpu, n, true, win)?;
        let (tv, loss) = extra.expect("built with a loss");
        ex.feed(gpu, tv, &target.repeat(n))?;
        Ok(Descent { net, ex, loss })
    }

    /// Renders every start and returns the images (unclamped, batch-major) and each start's
    /// gradient of its own MSE with respect to its unknowns.
    fn step(&mut self, inv: &Inverter, gpu: &Gpu, gv: &[f32], vars: &[Vars], win: &Window) -> Result<(Vec<f32>, Vec<[f64; 5]>)> {
        inv.feed(gpu, &self.net, &self.ex, gv, vars, win)?;
        self.ex.backward(gpu, self.loss)?;
        let img = self.ex.read(gpu, self.net.image)?;
        let gp = self.ex.grad(gpu, self.net.pose)?;
        let gl = self.ex.grad(gpu, self.net.light.expect("Phong head"))?;
        // The loss is the batch mean: each start's own MSE has n times its gradient.
        let n = vars.len() as f64;
        let grads = (0..vars.len())
            .map(|k| chain(&vars[k], &gp[k * 6..k * 6 + 6], &gl[k * 6..k * 6 + 6], &inv.preset).map(|g| g * n))
            .collect();
        Ok((img, grads))
    }
}

/// Gradient of the loss with respect to one start's unknowns, from the gradients with
/// respect to the pose `(scale, -azimuth, -(90 - elevation), t...)` (radians) and the light
/// `(direction, colour)` (see `nn::camera`).
fn chain(v: &Vars, gp: &[f32], gl: &[f32], p: &Preset) -> [f64; 5] {
    let d = std::f64::consts::PI / 180.0;
    let pose = camera::pose_for_view(&v.view(), p.input, p.cam, None);
    let (az, el) = (v.0[3] * d, v.0[4] * d);
    // direction = (sin az sin el, cos el, cos az sin el)
    let dir_daz = [az.cos() * el.sin(), 0.0, -az.sin() * el.sin()];
    let dir_del = [az.sin() * el.cos(), -el.sin(), az.cos() * el.cos()];
    let dot = |a: [f64; 3]| (0..3).map(|i| a[i] * gl[i] as f64).sum::<f64>();
    [
        -(gp[1] as f64) * d,
        (gp[2] as f64) * d,
        // scale = k / radius: d scale / d ln radius = -scale.
        -(gp[0] as f64) * pose[0] as f64,
        dot(dir_daz) * d,
        dot(dir_del) * d,
    ]
}

/// Unit vector of azimuth `az` and polar angle `el` (degrees) about the up axis:
/// `(sin az · sin el, cos el, cos az · sin el)`.
fn polar_unit(az: f64, el: f64) -> [f64; 3] {
    let (az, el) = (az.to_radians(), el.to_radians());
    [az.sin() * el.sin(), el.cos(), az.cos() * el.sin()]
}
