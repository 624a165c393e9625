//! Gradient descent on a decoder's code through a frozen RenderNet: what shape recovery (the
//! shape prior's code) and texture recovery (the texture decoder's code) share. A decoder
//! in front of the renderer turns codes into the grid it reads; starts are scored by image
//! loss in batches, the best few refined by Adam on the code, the lowest loss wins. Codes
//! stay inside the decoders' input range (0, 1).

use super::{Inverter, ShapeView, Window};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::{Executor, Op, Value};
use crate::nn::camera;
use crate::nn::prior::PriorPreset;
use crate::nn::rendernet::{Head, RenderNet, phong_of};
use crate::nn::texture::TexturePreset;
use crate::ops::loss::Loss;
use crate::reference::Light;

/// The decoder in front of the renderer.
pub(super) enum Front<'a> {
    /// The shape prior's decoder: its grid is RenderNet's input.
    Shape {
        /// Its sizes.
        preset: &'a PriorPreset,
        /// Its weights (`dec.*` are used).
        weights: &'a [u8],
    },
    /// The texture decoder: its RGB times a known occupancy, beside the occupancy.
    Texture {
        /// Its sizes.
        preset: &'a TexturePreset,
        /// Its weights (`tex.*` are used).
        weights: &'a [u8],
        /// The shape, as RenderNet's input values `[R, R, R]` of the decoder's side.
        occupancy: &'a [f32],
    },
}

impl Front<'_> {
    fn latent(&self) -> usize {
        match self {
            Front::Shape { preset, .. } => preset.latent,
            Front::Texture { .. } => crate::voxel::shapes::TEXTURE_CODE,
        }
    }

    /// The renderer with this decoder in front for `n` items: the network, the code input and
    /// (texture) the occupancy input.
    fn build(&self, inv: &Inverter, n: usize, cam_hw: [usize; 2]) -> Result<(RenderNet, Value, Option<Value>)> {
        let head = Head::Phong(phong_of(&inv.head_light));
        match self {
            Front::Shape { preset, .. } => {
                let (net, code) = crate::nn::prior::decoder_with_renderer(preset, &inv.preset, head, n, cam_hw)?;
                Ok((net, code, None))
            }
            Front::Texture { preset, occupancy, .. } => {
                if occupancy.len() != preset.res.pow(3) {
                    return Err(Error::Invalid(format!("the shape has {} voxels; the texture decoder paints {}^3", occupancy.len(), preset.res)));
                }
                let (net, code, occ) = crate::nn::texture::decoder_with_renderer(preset, &inv.preset, head, n, cam_hw)?;
                Ok((net, code, Some(occ)))
            }
        }
    }

    /// The decoder's weights, their label and the prefix of the parameters taken from them.
    fn params(&self) -> (&[u8], &'static str, &'static str) {
        match self {
            Front::Shape { weights, .. } => (weights, "prior", "dec."),
            Front::Texture { weights, .. } => (weights, "texture decoder", "tex."),
        }
    }
}

/// The decoder in front of a frozen RenderNet for `codes` codes at a time, each rendered at
/// every view (item `c * views + v`), with the image MSE against the views' images (plus,
/// with the silhouette term, the mask MSE against their foregrounds).
pub(super) struct CodeSearch {
    net: RenderNet,
    ex: Executor,
    code: Value,
    loss: Value,
    latent: usize,
    views: usize,
    codes: usize,
    /// Each view's cropped image.
    targets: Vec<Vec<f32>>,
    /// With the silhouette term: the mask value and each view's cropped foreground.
    masks: Option<(Value, Vec<Vec<f32>>)>,
}

impl CodeSearch {
    pub(super) fn new(inv: &Inverter, gpu: &Gpu, front: &Front, views: &[ShapeView], codes: usize, silhouette: bool) -> Result<CodeSearch> {
        let p = &inv.preset;
        let fgs: Vec<Vec<bool>> = views.iter().map(|v| inv.foreground(v.image)).collect::<Result<_>>()?;
        let wins: Vec<Window> = fgs.iter().map(|fg| Window::around(p, fg, inv.size)).collect();
        let len = [0, 1].map(|a| wins.iter().map(|w| w.cam[2 + a]).max().unwrap_or(p.cam));
        let wins: Vec<Window> = wins.iter().map(|w| w.resized(p, len)).collect();
        let n = codes * views.len();
        let (mut net, code, occupancy) = front.build(inv, n, [len[0], len[1]])?;
        let [h, w] = wins[0].pixel_dims();
        let tv = net.graph.input("target.image", &[n, 3, h, w])?;
        let mut loss = net.graph.apply("loss.shape", Op::Loss(Loss::Mse), &[net.image, tv])?;
        let mask_target = if silhouette {
            let tm = net.graph.input("target.mask", &[n, 1, h, w])?;
            let lm = net.graph.apply("loss.silhouette", Op::Loss(Loss::Mse), &[net.maps.expect("Phong head")[2], tm])?;
            loss = net.graph.apply("loss.total", Op::Add, &[loss, lm])?;
            Some(tm)
        } else {
            None
        };
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        ex.load_params_parts(gpu, &[(&inv.weights, &inv.name, ""), front.params()])?;
        ex.training = false;
        ex.freeze_params();
        ex.want_grad(code);
        ex.keep(net.image);
        let targets: Vec<Vec<f32>> = views.iter().zip(&wins).map(|(v, w)| w.crop_rgb(v.image)).collect();
        let each = |f: &dyn Fn(usize) -> Vec<f32>| -> Vec<f32> { (0..n).flat_map(|k| f(k % views.len())).collect() };
        ex.feed(gpu, net.pose, &each(&|v| camera::pose_for_view(&views[v].view, p.input, p.cam, Some(wins[v].cam)).to_vec()))?;
        let light = |v: usize| camera::light_values(&Light { azimuth: views[v].light.azimuth, elevation: views[v].light.elevation, ..inv.head_light }).to_vec();
        ex.feed(gpu, net.light.expect("Phong head"), &each(&light))?;
        ex.feed(gpu, tv, &each(&|v| targets[v].clone()))?;
        if let (Some(value), Front::Texture { occupancy: occ, .. }) = (occupancy, front) {
            ex.feed(gpu, value, &occ.repeat(n))?;
        }
        let masks = match mask_target {
            Some(tm) => {
                let m: Vec<Vec<f32>> = fgs.iter().zip(&wins).map(|(fg, w)| w.crop_mask(fg, inv.size).into_iter().map(|b| b as u8 as f32).collect()).collect();
                ex.feed(gpu, tm, &each(&|v| m[v].clone()))?;
                let mv = net.maps.expect("Phong head")[2];
                ex.keep(mv);
                Some((mv, m))
            }
            None => None,
        };
        Ok(CodeSearch { net, ex, code, loss, latent: front.latent(), views: views.len(), codes, targets, masks })
    }

    /// Renders up to `self.codes` codes at every view: each code's image MSE (mean over the
    /// views) and, with `grad`, its gradient.
    pub(super) fn run(&mut self, gpu: &Gpu, codes: &[&[f32]], grad: bool) -> Result<Vec<(f64, Vec<f64>)>> {
        let mut z = Vec::with_capacity(self.codes * self.views * self.latent);
        for c in 0..self.codes {
            // A short list is padded with its last code (those results are dropped).
            let code = codes[c.min(codes.len() - 1)];
            for _ in 0..self.views {
                z.extend_from_slice(code);
            }
        }
        self.ex.feed(gpu, self.code, &z)?;
        if grad {
            self.ex.backward(gpu, self.loss)?;
        } else {
            self.ex.forward(gpu)?;
        }
        let img = self.ex.read(gpu, self.net.image)?;
        let g = if grad { self.ex.grad(gpu, self.code)? } else { Vec::new() };
        let mask = match &self.masks {
            Some((mv, m)) => Some((self.ex.read(gpu, *mv)?, m)),
            None => None,
        };
        let per = self.targets[0].len();
        // Item k's loss: its image MSE, plus its silhouette MSE with the term.
        let item = |k: usize| {
            let v = k % self.views;
            let sil = mask.as_ref().map_or(0.0, |(mk, m)| mse(&mk[k * m[v].len()..(k + 1) * m[v].len()], &m[v]));
            mse(&img[k * per..(k + 1) * per], &self.targets[v]) + sil
        };
        let n = (self.codes * self.views) as f64;
        Ok((0..codes.len())
            .map(|c| {
                let items = c * self.views..(c + 1) * self.views;
                let mse = items.clone().map(item).sum::<f64>() / self.views as f64;
                // The loss is the batch mean: a code's own mean over its views has n / views
                // times the gradient its rows receive.
                let gz = if grad {
                    (0..self.latent).map(|j| items.clone().map(|k| g[k * self.latent + j] as f64).sum::<f64>() * n / self.views as f64).collect()
                } else {
                    Vec::new()
                };
                (mse, gz)
            })
            .collect())
    }
}

fn mse(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(&x, &y)| (x as f64 - y as f64).powi(2)).sum::<f64>() / a.len().max(1) as f64
}

/// A code's penalty term and its gradient (the shape prior's Gaussian; none for textures).
pub(super) type Penalty<'a> = dyn Fn(&[f32]) -> (f64, Vec<f64>) + 'a;

/// How a code search runs.
pub(super) struct Descent<'a> {
    /// Adam steps per refined start.
    pub steps: usize,
    /// Adam's step on the code.
    pub lr: f64,
    /// Best-scoring starts refined.
    pub keep: usize,
    /// Add the silhouette term to the image loss.
    pub silhouette: bool,
    /// Added to each code's loss.
    pub penalty: &'a Penalty<'a>,
}

/// What a code search found.
pub(super) struct Found {
    /// The best code after descent.
    pub code: Vec<f32>,
    /// The start that scored best before descent.
    pub start: Vec<f32>,
    /// The winning start's loss after each step, best so far.
    pub curve: Vec<f64>,
}

/// Scores `starts` (at least one) by loss in batches of about 8 renders, refines the best
/// `d.keep` by Adam, and returns the lowest loss met.
pub(super) fn search(inv: &Inverter, gpu: &Gpu, front: &Front, views: &[ShapeView], starts: Vec<Vec<f32>>, d: &Descent) -> Result<Found> {
    if views.is_empty() {
        return Err(Error::Invalid("a code search needs at least one image".into()));
    }
    if starts.is_empty() {
        return Err(Error::Invalid("a code search needs at least one starting code".into()));
    }
    let per_batch = (8 / views.len()).clamp(1, starts.len());
    let mut scorer = CodeSearch::new(inv, gpu, front, views, per_batch, d.silhouette)?;
    let mut scored = Vec::with_capacity(starts.len());
    for chunk in starts.chunks(per_batch) {
        let refs: Vec<&[f32]> = chunk.iter().map(Vec::as_slice).collect();
        for (z, (m, _)) in chunk.iter().zip(scorer.run(gpu, &refs, false)?) {
            scored.push((m + (d.penalty)(z).0, z.clone()));
        }
    }
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let start = scored[0].1.clone();
    drop(scorer);
    let mut one = CodeSearch::new(inv, gpu, front, views, 1, d.silhouette)?;
    let mut best: Option<(f64, Vec<f32>, Vec<f64>)> = None;
    for (_, z0) in scored.into_iter().take(d.keep.max(1)) {
        let (loss, z, curve) = descend(gpu, &mut one, z0, d)?;
        if best.as_ref().is_none_or(|b| loss < b.0) {
            best = Some((loss, z, curve));
        }
    }
    let (_, code, curve) = best.expect("at least one start");
    Ok(Found { code, start, curve })
}

/// Adam on the code from `z`: the best (loss, code) met and the best-so-far curve.
fn descend(gpu: &Gpu, search: &mut CodeSearch, mut z: Vec<f32>, d: &Descent) -> Result<(f64, Vec<f32>, Vec<f64>)> {
    let (mut m, mut v) = (vec![0.0f64; z.len()], vec![0.0f64; z.len()]);
    let (b1, b2) = (0.9f64, 0.999f64);
    let mut curve = Vec::with_capacity(d.steps + 1);
    let mut best = (f64::INFINITY, z.clone());
    for step in 0..=d.steps {
        let (mse, g) = search.run(gpu, &[&z], true)?.swap_remove(0);
        let (pv, pg) = (d.penalty)(&z);
        if mse + pv < best.0 {
            best = (mse + pv, z.clone());
        }
        curve.push(best.0);
        if step == d.steps {
            break;
        }
        let t = (step + 1) as i32;
        for j in 0..z.len() {
            let gj = g[j] + pg[j];
            m[j] = b1 * m[j] + (1.0 - b1) * gj;
            v[j] = b2 * v[j] + (1.0 - b2) * gj * gj;
            let step = d.lr * (m[j] / (1.0 - b1.powi(t))) / ((v[j] / (1.0 - b2.powi(t))).sqrt() + 1e-12);
            z[j] = (z[j] as f64 - step).clamp(1e-3, 1.0 - 1e-3) as f32;
        }
    }
    Ok((best.0, best.1, curve))
}
