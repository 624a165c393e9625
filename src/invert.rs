//! Inverse rendering through a frozen RenderNet: recover the camera pose (azimuth, elevation,
//! radius) and the light direction that make the network render a given image of a known
//! voxel grid (the paper's Section 5 with the shape given).
//!
//! Strategy (the paper's, plus radius): a coarse grid of azimuth x elevation starts is
//! scored by how well the network's predicted mask overlaps the image's foreground (light
//! does not change a silhouette, so this search ignores it); each start's radius is then set
//! from the ratio of silhouette areas (orthographic: area scales with `1 / radius^2`) and the
//! best starts are re-scored. The survivors are refined together, one batch, by Adam on
//! `(azimuth, elevation, ln radius, light azimuth, light elevation)` with the image MSE as
//! loss; gradients reach the pose through the resampling op and the light through the Phong
//! op. The start with the lowest final MSE wins.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::{Executor, Op, Value};
use crate::metrics::FOREGROUND;
use crate::nn::camera;
use crate::nn::rendernet::{Head, Preset, RenderNet, phong_of};
use crate::ops::loss::Loss;
use crate::reference::{Image, Light, View};
use crate::voxel::VoxelGrid;

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
}

impl Default for InvertOptions {
    fn default() -> Self {
        InvertOptions { azimuths: 12, elevations: 5, keep: 4, steps: 60, lr_degrees: 3.0 }
    }
}

/// What the inversion found.
#[derive(Clone, Debug)]
pub struct Estimate {
    /// Recovered camera.
    pub view: View,
    /// Recovered light (the network's material constants, white).
    pub light: Light,
    /// Image MSE of the network's render at the estimate against the input.
    pub mse: f64,
    /// Best MSE over the kept starts after each refinement step.
    pub curve: Vec<f64>,
    /// The network's render at the estimate.
    pub image: Image,
}

/// Radii the search keeps to (the training set's range, with margin).
const RADIUS: (f64, f64) = (2.0, 9.0);
/// Coarse starts re-scored at their own radius (silhouette IoU at the mid radius already
/// ranks views well; this bounds the second pass's cost).
const RESCORED: usize = 16;
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
}

impl Inverter {
    /// `weights`: Phong RenderNet parameters of `preset` (safetensors bytes, `name` labels
    /// them in errors); `light` gives the material constants the network was trained with.
    pub fn new(preset: Preset, weights: &[u8], name: &str, light: Light) -> Inverter {
        let size = preset.image_for(preset.cam);
        Inverter { preset, head_light: light, weights: weights.to_vec(), name: name.to_string(), size }
    }

    /// Image side the network renders (the input image must have it).
    pub fn size(&self) -> usize {
        self.size
    }

    fn executor(&self, gpu: &Gpu, batch: usize, loss: bool) -> Result<(RenderNet, Executor, Option<(Value, Value)>)> {
        let p = &self.preset;
        let mut net = RenderNet::build(p, Head::Phong(phong_of(&self.head_light)), batch, [p.cam, p.cam], false)?;
        let mut extra = None;
        if loss {
            let target = net.graph.input("target.image", &[batch, 3, self.size, self.size])?;
            let l = net.graph.apply("loss.invert", Op::Loss(Loss::Mse), &[net.image, target])?;
            extra = Some((target, l));
        }
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        ex.load_params_bytes(gpu, &self.weights, &self.name)?;
        ex.training = false;
        ex.freeze_params();
        ex.keep(net.image);
        if let Some([_, _, mask]) = net.maps {
            ex.keep(mask);
        }
        if loss {
            ex.want_grad(net.pose);
            ex.want_grad(net.light.expect("Phong head"));
        }
        Ok((net, ex, extra))
    }

    /// Feeds `grid` once per batch entry, and each start's pose and light.
    fn feed(&self, gpu: &Gpu, net: &RenderNet, ex: &Executor, grid: &[f32], vars: &[Vars]) -> Result<()> {
        let p = &self.preset;
        let n = vars.len();
        ex.feed(gpu, net.grid, &grid.repeat(n))?;
        let pose: Vec<f32> = vars.iter().flat_map(|v| camera::pose_for_view(&v.view(), p.input, p.cam, None)).collect();
        ex.feed(gpu, net.pose, &pose)?;
        let light: Vec<f32> = vars.iter().flat_map(|v| camera::light_values(&v.light(&self.head_light))).collect();
        ex.feed(gpu, net.light.expect("Phong head"), &light)
    }

    /// Scores starts by silhouette: the predicted mask's area and IoU with `fg`.
    fn silhouettes(&self, gpu: &Gpu, grid: &[f32], fg: &[bool], starts: &[Vars]) -> Result<Vec<(f64, f64)>> {
        let (net, mut ex, _) = self.executor(gpu, starts.len(), false)?;
        self.feed(gpu, &net, &ex, grid, starts)?;
        ex.forward(gpu)?;
        let mask = ex.read(gpu, net.maps.expect("Phong head")[2])?;
        let hw = self.size * self.size;
        Ok(mask
            .chunks(hw)
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

    /// Recovers pose and light for `target` (RGB, the network's image size) of `grid`.
    pub fn invert(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, o: &InvertOptions, mut progress: impl FnMut(usize, f64)) -> Result<Estimate> {
        if target.channels != 3 || target.size != self.size {
            return Err(Error::Invalid(format!(
                "the image is {}x{} with {} channels; preset '{}' inverts {s}x{s} RGB images",
                target.size, target.size, target.channels, self.preset.name, s = self.size
            )));
        }
        if o.azimuths == 0 || o.elevations == 0 || o.keep == 0 {
            return Err(Error::Invalid("azimuth and elevation starts and kept starts must be at least 1".into()));
        }
        let gv = self.grid_values(grid)?;
        let hw = self.size * self.size;
        let fg: Vec<bool> = (0..hw).map(|i| (0..3).any(|c| target.data[c * hw + i] > FOREGROUND)).collect();
        let target_area = fg.iter().filter(|&&f| f).count() as f64;
        if target_area == 0.0 {
            return Err(Error::Invalid("the image has no foreground (every pixel is black): nothing to invert".into()));
        }
        let base = Light::default();
        // Coarse pass: silhouettes at the mid radius, one elevation row per batch.
        let mut scored: Vec<(f64, Vars)> = Vec::new();
        for e in 0..o.elevations {
            let el = 180.0 * (e as f64 + 0.5) / o.elevations as f64;
            let row: Vec<Vars> = (0..o.azimuths)
                .map(|a| Vars([360.0 * a as f64 / o.azimuths as f64, el, COARSE_RADIUS.ln(), base.azimuth, base.elevation]))
                .collect();
            for ((area, iou), mut v) in self.silhouettes(gpu, &gv, &fg, &row)?.into_iter().zip(row) {
                // Area scales with 1 / radius^2: the radius that matches the image's area.
                v.0[2] = (COARSE_RADIUS * (area.max(1.0) / target_area).sqrt()).ln();
                v.clamp();
                scored.push((iou, v));
            }
        }
        // Re-score the best coarse starts at their own radii; keep the best of those.
        scored.sort_by(|a, b| b.0.total_cmp(&a.0));
        let starts: Vec<Vars> = scored.iter().take(RESCORED.max(o.keep)).map(|s| s.1).collect();
        let mut rescored = Vec::new();
        for chunk in starts.chunks(o.azimuths) {
            for ((_, iou), v) in self.silhouettes(gpu, &gv, &fg, chunk)?.into_iter().zip(chunk) {
                rescored.push((iou, *v));
            }
        }
        rescored.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut vars: Vec<Vars> = rescored.iter().take(o.keep).map(|s| s.1).collect();
        self.refine(gpu, &gv, target, &mut vars, o, &mut progress)
    }

    /// The image MSE (unclamped, as the loss op computes it) of each start in `unknowns` —
    /// `[azimuth, elevation, ln radius, light azimuth, light elevation]`, degrees — against
    /// `target`, with its gradient with respect to those five numbers: what the refinement
    /// descends, exposed for callers with their own optimiser (and for testing against
    /// finite differences).
    pub fn gradient(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, unknowns: &[[f64; 5]]) -> Result<Vec<(f64, [f64; 5])>> {
        let gv = self.grid_values(grid)?;
        let vars: Vec<Vars> = unknowns.iter().map(|&u| Vars(u)).collect();
        let mut d = Descent::new(self, gpu, target, vars.len())?;
        let (img, grads) = d.step(self, gpu, &gv, &vars)?;
        let per = 3 * self.size * self.size;
        Ok(img
            .chunks(per)
            .zip(grads)
            .map(|(y, g)| (y.iter().zip(&target.data).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>() / per as f64, g))
            .collect())
    }

    fn grid_values(&self, grid: &VoxelGrid) -> Result<Vec<f32>> {
        let p = &self.preset;
        let g = if grid.dims() == [p.input; 3] { grid.clone() } else { grid.resample_to(p.input).map_err(|e| Error::Invalid(e.to_string()))? };
        Ok(camera::input_values(&g))
    }

    /// Adam on every kept start at once; returns the best.
    fn refine(&self, gpu: &Gpu, gv: &[f32], target: &Image, vars: &mut [Vars], o: &InvertOptions, progress: &mut impl FnMut(usize, f64)) -> Result<Estimate> {
        let n = vars.len();
        let mut d = Descent::new(self, gpu, target, n)?;
        let (mut m, mut v) = (vec![[0.0f64; 5]; n], vec![[0.0f64; 5]; n]);
        let (b1, b2) = (0.9f64, 0.999f64);
        let mut curve = Vec::with_capacity(o.steps);
        let mut best: Option<(f64, Vars, Vec<f32>)> = None;
        let per = 3 * self.size * self.size;
        for step in 0..=o.steps {
            let (img, grads) = d.step(self, gpu, gv, vars)?;
            for (k, y) in img.chunks(per).enumerate() {
                // Scored as the user sees it: clamped to [0, 1].
                let mse = y.iter().zip(&target.data).map(|(a, b)| ((a.clamp(0.0, 1.0) - b) as f64).powi(2)).sum::<f64>() / per as f64;
                if best.as_ref().is_none_or(|b| mse < b.0) {
                    best = Some((mse, vars[k], y.to_vec()));
                }
            }
            let b = best.as_ref().expect("at least one start").0;
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
        let (mse, best, img) = best.expect("at least one start");
        Ok(Estimate {
            view: best.view(),
            light: best.light(&self.head_light),
            mse,
            curve,
            image: Image { channels: 3, size: self.size, data: img.into_iter().map(|x| x.clamp(0.0, 1.0)).collect() },
        })
    }
}

/// A frozen network with an MSE loss against one target, for a batch of starts.
struct Descent {
    net: RenderNet,
    ex: Executor,
    loss: Value,
}

impl Descent {
    fn new(inv: &Inverter, gpu: &Gpu, target: &Image, n: usize) -> Result<Descent> {
        let (net, ex, extra) = inv.executor(gpu, n, true)?;
        let (tv, loss) = extra.expect("built with a loss");
        ex.feed(gpu, tv, &target.data.repeat(n))?;
        Ok(Descent { net, ex, loss })
    }

    /// Renders every start and returns the images (unclamped, batch-major) and each start's
    /// gradient of its own MSE with respect to its unknowns.
    fn step(&mut self, inv: &Inverter, gpu: &Gpu, gv: &[f32], vars: &[Vars]) -> Result<(Vec<f32>, Vec<[f64; 5]>)> {
        inv.feed(gpu, &self.net, &self.ex, gv, vars)?;
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

/// Unit vector from the object towards the camera for `view`'s azimuth and elevation (polar
/// angle from the up axis), for measuring pose errors as angles.
pub fn view_direction(view: &View) -> [f64; 3] {
    let (az, el) = (view.azimuth.to_radians(), view.elevation.to_radians());
    [az.sin() * el.sin(), el.cos(), az.cos() * el.sin()]
}

/// Unit vector towards the light in the camera frame ([`Light::direction`] in f64).
pub fn light_direction(light: &Light) -> [f64; 3] {
    let (az, el) = (light.azimuth.to_radians(), light.elevation.to_radians());
    [az.sin() * el.sin(), el.cos(), az.cos() * el.sin()]
}

/// Angle in degrees between two unit vectors.
pub fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d: f64 = (0..3).map(|i| a[i] * b[i]).sum();
    d.clamp(-1.0, 1.0).acos().to_degrees()
}

/// How far one inversion landed from the known scene.
#[derive(Clone, Copy, Debug)]
pub struct InvertError {
    /// Shape the sample shows.
    pub shape_id: u32,
    /// Angle between the true and recovered camera directions, degrees.
    pub pose_degrees: f64,
    /// Angle between the true and recovered light directions, degrees.
    pub light_degrees: f64,
    /// Recovered radius over the true one.
    pub radius_ratio: f64,
    /// Image MSE of the re-render against the input.
    pub mse: f64,
    /// Wall time of the inversion.
    pub seconds: f64,
}

/// Inverts `samples` held-out samples of `ds` (spread over the split; 0 = all) from their
/// target images, with the grid known, and measures the errors. `progress(done, total)`.
pub fn evaluate(
    gpu: &Gpu,
    inv: &Inverter,
    ds: &crate::data::Dataset,
    samples: usize,
    o: &InvertOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<InvertError>> {
    let test = ds.split(crate::data::Split::Test);
    let n = if samples == 0 { test.len() } else { samples.min(test.len()) };
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let s = test.get(k * test.len() / n)?;
        let target = s.images.get("phong").ok_or_else(|| Error::Invalid(format!("{}: not a Phong dataset (no 'phong' images)", ds.dir().display())))?;
        let t = std::time::Instant::now();
        let est = inv.invert(gpu, &s.grid, target, o, |_, _| {})?;
        out.push(InvertError {
            shape_id: s.shape_id,
            pose_degrees: angle_between(view_direction(&s.view), view_direction(&est.view)),
            light_degrees: angle_between(light_direction(&s.light), light_direction(&est.light)),
            radius_ratio: est.view.radius / s.view.radius,
            mse: est.mse,
            seconds: t.elapsed().as_secs_f64(),
        });
        progress(k + 1, n);
    }
    Ok(out)
}
