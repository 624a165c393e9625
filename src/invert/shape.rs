//! Shape recovery through the shape prior: gradient descent on the prior's latent code so
//! that RenderNet, rendering the decoded grid at a known pose and light, reproduces the image
//! (the paper's Section 5 with the decoder as the prior: the shape stays one the decoder can
//! make). The code stays inside the decoder's range (0, 1), the sigmoid's.

use super::{Inverter, Window};
use crate::error::Result;
use crate::gpu::Gpu;
use crate::graph::{Executor, Op};
use crate::nn::camera;
use crate::nn::prior::{PriorPreset, decoder_with_renderer};
use crate::nn::rendernet::{Head, phong_of};
use crate::ops::loss::Loss;
use crate::reference::{Image, Light, View};
use crate::voxel::VoxelGrid;

/// Settings of the code search.
#[derive(Clone, Debug)]
pub struct ShapeOptions {
    /// Adam steps.
    pub steps: usize,
    /// Adam's step on the code (which lives in 0..1).
    pub lr: f64,
    /// Starting code; `None` starts every entry at 0.5.
    pub start: Option<Vec<f32>>,
}

impl Default for ShapeOptions {
    fn default() -> Self {
        ShapeOptions { steps: 100, lr: 0.02, start: None }
    }
}

/// What the code search found.
#[derive(Clone, Debug)]
pub struct ShapeEstimate {
    /// The decoded grid of the best code (occupancy probabilities).
    pub grid: VoxelGrid,
    /// The best code.
    pub code: Vec<f32>,
    /// The image MSE after each step (over the window around the image's foreground).
    pub curve: Vec<f64>,
}

impl Inverter {
    /// Recovers a shape for `target` seen from `view` under `light` (direction; the
    /// material is the network's) by Adam on the latent code of the prior `prior`, whose
    /// weights (`dec.*` are used) are `prior_weights`.
    pub fn recover_shape(&self, gpu: &Gpu, prior: &PriorPreset, prior_weights: &[u8], target: &Image, view: &View, light: &Light, o: &ShapeOptions) -> Result<ShapeEstimate> {
        let p = &self.preset;
        let win = Window::around(p, &self.foreground(target)?, self.size);
        let (mut net, code) = decoder_with_renderer(prior, p, Head::Phong(phong_of(&self.head_light)), 1, [win.cam[2], win.cam[3]])?;
        let [h, w] = win.pixel_dims();
        let tv = net.graph.input("target.image", &[1, 3, h, w])?;
        let loss = net.graph.apply("loss.shape", Op::Loss(Loss::Mse), &[net.image, tv])?;
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        ex.load_params_parts(gpu, &[(&self.weights, &self.name, ""), (prior_weights, "prior", "dec.")])?;
        ex.training = false;
        ex.freeze_params();
        ex.want_grad(code);
        ex.keep(net.grid);
        ex.feed(gpu, net.pose, &camera::pose_for_view(view, p.input, p.cam, Some(win.cam)))?;
        ex.feed(gpu, net.light.expect("Phong head"), &camera::light_values(&Light { azimuth: light.azimuth, elevation: light.elevation, ..self.head_light }))?;
        ex.feed(gpu, tv, &win.crop_rgb(target))?;
        let mut z = o.start.clone().unwrap_or_else(|| vec![0.5; prior.latent]);
        if z.len() != prior.latent {
            return Err(crate::Error::Invalid(format!("starting code has {} entries; the prior's has {}", z.len(), prior.latent)));
        }
        let (mut m, mut v) = (vec![0.0f64; z.len()], vec![0.0f64; z.len()]);
        let (b1, b2) = (0.9f64, 0.999f64);
        let mut curve = Vec::with_capacity(o.steps);
        let mut best = (f64::INFINITY, z.clone());
        for step in 0..=o.steps {
            ex.feed(gpu, code, &z)?;
            ex.backward(gpu, loss)?;
            let l = ex.read(gpu, loss)?[0] as f64;
            if l < best.0 {
                best = (l, z.clone());
            }
            curve.push(best.0);
            if step == o.steps {
                break;
            }
            let g = ex.grad(gpu, code)?;
            let t = (step + 1) as i32;
            for j in 0..z.len() {
                let gj = g[j] as f64;
                m[j] = b1 * m[j] + (1.0 - b1) * gj;
                v[j] = b2 * v[j] + (1.0 - b2) * gj * gj;
                let step = o.lr * (m[j] / (1.0 - b1.powi(t))) / ((v[j] / (1.0 - b2.powi(t))).sqrt() + 1e-12);
                z[j] = (z[j] as f64 - step).clamp(1e-3, 1.0 - 1e-3) as f32;
            }
        }
        ex.feed(gpu, code, &best.1)?;
        ex.forward(gpu)?;
        let grid = camera::grid_from_input_values(&ex.read(gpu, net.grid)?, prior.res)?;
        Ok(ShapeEstimate { grid, code: best.1, curve })
    }
}

/// One held-out sample's shape recovery, scored.
#[derive(Clone, Debug)]
pub struct ShapeError {
    /// Shape the sample shows.
    pub shape_id: u32,
    /// Voxel IoU (threshold 0.5) of the recovered grid against the true one.
    pub iou: f64,
    /// The same for the starting code's grid: what the prior gives without the image.
    pub iou_start: f64,
    /// Final image MSE over the search window.
    pub mse: f64,
    /// Wall time of the search.
    pub seconds: f64,
}

/// Recovers the shapes of `samples` held-out samples of `ds` (spread over the split; 0 =
/// all) from their images at their true pose and light, and scores them by voxel IoU.
/// The dataset's grids must have the prior's side. `progress(done, total)`.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_shapes(
    gpu: &Gpu,
    inv: &Inverter,
    prior: &PriorPreset,
    prior_weights: &[u8],
    ds: &crate::data::Dataset,
    samples: usize,
    o: &ShapeOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<ShapeError>> {
    let test = ds.split(crate::data::Split::Test);
    let n = test.spread(samples).count();
    let mut out = Vec::with_capacity(n);
    for (k, i) in test.spread(samples).enumerate() {
        let s = test.get(i)?;
        if s.grid.dims() != [prior.res; 3] {
            return Err(crate::Error::Invalid(format!("{}: grids are {:?}; the prior's are {}^3", ds.dir().display(), s.grid.dims(), prior.res)));
        }
        let target = super::phong_target(ds, &s)?;
        let t = std::time::Instant::now();
        let est = inv.recover_shape(gpu, prior, prior_weights, target, &s.view, &s.light, o)?;
        let seconds = t.elapsed().as_secs_f64();
        let start = inv.recover_shape(gpu, prior, prior_weights, target, &s.view, &s.light, &ShapeOptions { steps: 0, ..o.clone() })?;
        let iou = |g: &VoxelGrid| crate::nn::prior::iou(g.occupancy(), s.grid.occupancy());
        out.push(ShapeError { shape_id: s.shape_id, iou: iou(&est.grid), iou_start: iou(&start.grid), mse: *est.curve.last().unwrap_or(&f64::NAN), seconds });
        progress(k + 1, n);
    }
    Ok(out)
}
