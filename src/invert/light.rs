//! Many lights scored from one forward pass. The Phong head's light enters only the analytic
//! shading of the network's normal, albedo and mask maps (`ops::phong`), so once a start's
//! maps are read back, every light direction costs a few flops per pixel on the CPU instead
//! of a network forward: the light searches rank thousands of directions for the price of
//! one render per view. Here too: the light search itself (`Inverter::ranked_lights`,
//! `Inverter::light_optimum`).

use super::starts::{POLISH_STEP_DEGREES, light_grid};
use super::{Inverter, Vars, Window};
use crate::error::Result;
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::nn::camera;
use crate::nn::rendernet::{RenderNet, phong_of};
use crate::ops::phong::Phong;
use crate::reference::{Image, Light, View};
use crate::voxel::VoxelGrid;

/// One start's light-independent maps over the search window.
pub(super) struct Maps {
    /// Unit normals (decoded from the map's [0, 1] encoding as the shader decodes them).
    normal: Vec<[f32; 3]>,
    /// Albedo, grey broadcast to three channels.
    albedo: Vec<[f32; 3]>,
    mask: Vec<f32>,
    /// Map pixels per image pixel along each axis: each is shaded, then the `sub x sub`
    /// block averaged, as a supersampled reference image is drawn.
    sub: usize,
    /// Image pixels per row (with `sub > 1`).
    width: usize,
    /// Cut the highlight where the light is behind the surface (`n.l <= 0`), as the
    /// reference renderer does. The Phong op (so the network's image) keeps it there: the
    /// networks were trained with that op.
    cut: bool,
}

impl Maps {
    /// Batch entry `b` of maps read back from the network: `normal [N, 3, H, W]`, `albedo [N,
    /// C, H, W]` (C 1 or 3), `mask [N, 1, H, W]`, `hw = H * W`.
    pub(super) fn of(normal: &[f32], albedo: &[f32], mask: &[f32], hw: usize, b: usize) -> Maps {
        let c = albedo.len() / (mask.len() / hw) / hw;
        let (nb, ab) = (&normal[b * 3 * hw..(b + 1) * 3 * hw], &albedo[b * c * hw..(b + 1) * c * hw]);
        let normal = (0..hw)
            .map(|px| {
                let u = [2.0 * nb[px] - 1.0, 2.0 * nb[hw + px] - 1.0, 2.0 * nb[2 * hw + px] - 1.0];
                let len = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt().max(1e-6);
                u.map(|x| x / len)
            })
            .collect();
        let albedo = (0..hw).map(|px| if c == 3 { [ab[px], ab[hw + px], ab[2 * hw + px]] } else { [ab[px]; 3] }).collect();
        Maps { normal, albedo, mask: mask[b * hw..(b + 1) * hw].to_vec(), sub: 1, width: 0, cut: false }
    }

    /// The exact renderer's maps (normal `[3, H, W]`, albedo `[C, H, W]`, mask `[H, W]`,
    /// `sub` times the target's `width` across), shaded as the reference renderer shades.
    pub(super) fn exact(normal: &[f32], albedo: &[f32], mask: &[f32], sub: usize, width: usize) -> Maps {
        Maps { sub, width, cut: true, ..Maps::of(normal, albedo, mask, mask.len(), 0) }
    }

    /// The image `[3, H, W]` these maps give under `light` (`nn::camera::light_values`:
    /// direction then colour), as the Phong op draws it (view along +z).
    #[cfg(test)]
    pub(super) fn shade(&self, ph: &Phong, light: &[f32; 6]) -> Vec<f32> {
        let hw = self.mask.len();
        let mut out = vec![0.0; 3 * hw];
        for px in 0..hw {
            let v = self.pixel(ph, light, px);
            for c in 0..3 {
                out[c * hw + px] = v[c];
            }
        }
        out
    }

    /// Summed squared error against `target` (`[3, H, W]`) of the image under `light`,
    /// clamped to [0, 1] as a user sees it.
    pub(super) fn sse(&self, ph: &Phong, light: &[f32; 6], target: &[f32]) -> f64 {
        let hw = target.len() / 3;
        let (k, w) = (self.sub, self.width.max(1));
        let mut sum = 0.0;
        for px in 0..hw {
            let (y, x) = (px / w, px % w);
            let mut v = [0.0f32; 3];
            for dy in 0..k {
                for dx in 0..k {
                    let s = self.pixel(ph, light, (y * k + dy) * w * k + x * k + dx);
                    for c in 0..3 {
                        v[c] += s[c].clamp(0.0, 1.0);
                    }
                }
            }
            for c in 0..3 {
                sum += ((v[c] / (k * k) as f32 - target[c * hw + px]) as f64).powi(2);
            }
        }
        sum
    }

    fn pixel(&self, ph: &Phong, light: &[f32; 6], px: usize) -> [f32; 3] {
        let (n, a, m) = (self.normal[px], self.albedo[px], self.mask[px]);
        if m == 0.0 {
            // Background: most of a window, and `powf` is the costly part of a light's score.
            return [0.0; 3];
        }
        let d = n[0] * light[0] + n[1] * light[1] + n[2] * light[2];
        let s = 2.0 * d * n[2] - light[2];
        let spec = if s > 0.0 && (d > 0.0 || !self.cut) { s.powf(ph.shininess) } else { 0.0 };
        let diffuse = ph.ambient + ph.kd * d.max(0.0);
        [0, 1, 2].map(|c| m * light[3 + c] * (a[c] * diffuse + ph.ks * spec))
    }
}

impl Inverter {
    /// The light, among every direction of a 5-degree grid, under which the network's render
    /// of `grid` seen from `view` best matches `target` (image MSE over the window around its
    /// foreground): the best any light search through this network can do at that camera.
    /// At the true camera, its distance from the true light is the network's share of a light
    /// error; the rest is the search's. Also returns that render's image MSE over the window
    /// (clamped, as the search scores its estimate), before any refinement; at the true
    /// camera, [`Inverter::refined_mse`] refines from this light.
    pub fn light_optimum(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, view: &View) -> Result<(Light, f64)> {
        let (win, gv, t) = self.windowed(grid, target)?;
        let (net, ex, _) = self.executor(gpu, 1, false, &win)?;
        let d = Light::default();
        let start = Vars([view.azimuth, view.elevation, view.radius.ln(), d.azimuth, d.elevation]);
        let ranked = self.ranked_lights(gpu, &mut (net, ex), &gv, &t, &[start], &win, &light_grid(POLISH_STEP_DEGREES))?;
        let (sse, best) = ranked[0][0];
        Ok((best.light(&self.head_light), sse / t.len() as f64))
    }

    /// Each of `starts` with each light of `lights` (azimuth, elevation), ranked by how well
    /// its render matches `target` (the window's pixels): summed squared error, lowest first,
    /// one list per start. The starts' maps come from one forward pass per `sil` batch; the
    /// lights are scored on the CPU ([`light::Maps`]). The refinement follows the image
    /// gradient, which from a light on the wrong side can pull the pose astray before the
    /// light gets there.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn ranked_lights(&self, gpu: &Gpu, sil: &mut (RenderNet, Executor), grid: &[f32], target: &[f32], starts: &[Vars], win: &Window, lights: &[(f64, f64)]) -> Result<Vec<Vec<(f64, Vars)>>> {
        let (net, ex) = sil;
        let batch = net.graph.info(net.pose).shape[0];
        let [nm, am, mm] = net.maps.expect("Phong head");
        let ph = phong_of(&self.head_light);
        let values: Vec<[f32; 6]> = lights.iter().map(|&(az, el)| camera::light_values(&Light { azimuth: az, elevation: el, ..self.head_light })).collect();
        let mut out = Vec::with_capacity(starts.len());
        for chunk in starts.chunks(batch) {
            let mut padded = chunk.to_vec();
            padded.resize(batch, *chunk.last().expect("chunks are not empty"));
            self.feed(gpu, net, ex, grid, &padded, win)?;
            ex.forward(gpu)?;
            let (normal, albedo, mask) = (ex.read(gpu, nm)?, ex.read(gpu, am)?, ex.read(gpu, mm)?);
            let hw = target.len() / 3;
            for (b, start) in chunk.iter().enumerate() {
                let maps = Maps::of(&normal, &albedo, &mask, hw, b);
                let mut ranked: Vec<(f64, Vars)> = lights
                    .iter()
                    .zip(&values)
                    .map(|(&(az, el), l)| (maps.sse(&ph, l, target), Vars([start.0[0], start.0[1], start.0[2], az, el])))
                    .collect();
                ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
                out.push(ranked);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nn::rendernet::Preset;

    /// The CPU shading the light searches rank lights with draws what the network's Phong op
    /// draws from the same maps (two starts of one batch, specular on, one light from
    /// behind), and its squared error is the one the image itself gives; f32 on both sides,
    /// so 1e-4 of a grey level's 1/255 scale leaves room for rounding only.
    #[test]
    fn lights_scored_on_the_cpu_match_the_network_image() {
        let gpu = Gpu::new().unwrap();
        let head = Light { ks: 0.4, shininess: 12.0, ..Light::default() };
        let inv = Inverter::new(Preset::nano(), crate::nn::render::NANO_PHONG_WEIGHTS, "nano", head).unwrap();
        let gv = inv.grid_values(&crate::voxel::bunny()).unwrap();
        let win = Window::full(&inv.preset, inv.size);
        let (net, mut ex, _) = inv.executor(&gpu, 2, false, &win).unwrap();
        let vars = [Vars([30.0, 70.0, 3.3f64.ln(), 30.0, 60.0]), Vars([200.0, 100.0, 4.0f64.ln(), 160.0, 120.0])];
        inv.feed(&gpu, &net, &ex, &gv, &vars, &win).unwrap();
        ex.forward(&gpu).unwrap();
        let [nm, am, mm] = net.maps.unwrap();
        let (img, normal, albedo, mask) = (ex.read(&gpu, net.image).unwrap(), ex.read(&gpu, nm).unwrap(), ex.read(&gpu, am).unwrap(), ex.read(&gpu, mm).unwrap());
        let hw = mask.len() / 2;
        let ph = phong_of(&head);
        let target: Vec<f32> = img[..3 * hw].iter().map(|v| v.clamp(0.0, 1.0) * 0.9).collect();
        for (b, v) in vars.iter().enumerate() {
            let maps = Maps::of(&normal, &albedo, &mask, hw, b);
            let l = camera::light_values(&v.light(&head));
            let drawn = &img[b * 3 * hw..(b + 1) * 3 * hw];
            let worst = maps.shade(&ph, &l).iter().zip(drawn).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
            assert!(worst < 1e-4, "start {b}: CPU shading differs from the network image by {worst}");
            assert!(drawn.iter().any(|&x| x > 0.3), "start {b}: nothing lit to compare");
            let sse: f64 = drawn.iter().zip(&target).map(|(a, t)| ((a.clamp(0.0, 1.0) - t) as f64).powi(2)).sum();
            assert!((maps.sse(&ph, &l, &target) - sse).abs() < 1e-3 * sse.max(1e-3), "start {b}: squared error {} against {sse}", maps.sse(&ph, &l, &target));
        }
    }

    /// The exact maps shade as the reference renderer: a normal 80 degrees from the camera
    /// under a light straight behind the object faces away from it (n.l < 0) though its
    /// mirror direction points at the camera (r.v > 0), so the reference draws ambient only
    /// there, while the network's maps (the Phong op) keep the highlight (`0.3 * 0.94^20`).
    #[test]
    fn exact_maps_cut_the_highlight_where_the_light_is_behind_the_surface() {
        let a = 80f32.to_radians();
        let normal = [0.5 * (a.sin() + 1.0), 0.5, 0.5 * (a.cos() + 1.0)];
        let ph = phong_of(&Light::default());
        let behind = [0.0, 0.0, -1.0, 1.0, 1.0, 1.0];
        let exact = Maps::exact(&normal, &[0.8], &[1.0], 1, 1).shade(&ph, &behind);
        for c in exact {
            assert!((c - 0.8 * ph.ambient).abs() < 1e-6, "exact maps draw {c}, not the ambient term alone");
        }
        let network = Maps::of(&normal, &[0.8], &[1.0], 1, 0).shade(&ph, &behind);
        assert!(network[0] > 0.8 * ph.ambient + 0.05, "the network's maps lost the Phong op's highlight: {}", network[0]);
    }

    /// Ranking the 20-degree grid's lights at the camera that drew the target puts the grid
    /// light that drew it first (error ~0, the network's own image), every list best first.
    #[test]
    fn light_ranking_puts_the_light_that_drew_the_image_first() {
        let gpu = Gpu::new().unwrap();
        let inv = Inverter::new(Preset::nano(), crate::nn::render::NANO_PHONG_WEIGHTS, "nano", Light::default()).unwrap();
        let gv = inv.grid_values(&crate::voxel::bunny()).unwrap();
        let win = Window::full(&inv.preset, inv.size);
        let (net, ex, _) = inv.executor(&gpu, 3, false, &win).unwrap();
        let mut sil = (net, ex);
        let truth = Vars([30.0, 70.0, 3.3f64.ln(), 140.0, 70.0]);
        inv.feed(&gpu, &sil.0, &sil.1, &gv, &[truth; 3], &win).unwrap();
        sil.1.forward(&gpu).unwrap();
        let img = sil.1.read(&gpu, sil.0.image).unwrap();
        let target: Vec<f32> = img[..img.len() / 3].iter().map(|v| v.clamp(0.0, 1.0)).collect();
        let other = Vars([210.0, 110.0, 5.0f64.ln(), 0.0, 90.0]);
        let ranked = inv.ranked_lights(&gpu, &mut sil, &gv, &target, &[other, truth], &win, &light_grid(20.0)).unwrap();
        assert_eq!(ranked.len(), 2);
        for r in &ranked {
            assert_eq!(r.len(), 162);
            assert!(r.windows(2).all(|w| w[0].0 <= w[1].0), "not best first");
        }
        let best = ranked[1][0];
        assert!(best.0 < 1e-6 && (best.1.0[3], best.1.0[4]) == (140.0, 70.0), "best light {:?} with error {}", best.1, best.0);
        assert!(ranked[0][0].0 > 1.0, "another camera explains the image as well: {}", ranked[0][0].0);
    }

    /// The network's own best light at the camera that drew its own image is the light that
    /// drew it, when that light lies on the 5-degree grid.
    #[test]
    fn light_optimum_of_the_network_image_is_the_light_that_drew_it() {
        let gpu = Gpu::new().unwrap();
        let inv = Inverter::new(Preset::nano(), crate::nn::render::NANO_PHONG_WEIGHTS, "nano", Light::default()).unwrap();
        let grid = crate::voxel::bunny();
        let full = Window::full(&inv.preset, inv.size);
        let (net, mut ex, _) = inv.executor(&gpu, 1, false, &full).unwrap();
        let truth = Vars([75.0, 60.0, 3.5f64.ln(), 215.0, 122.5]);
        inv.feed(&gpu, &net, &ex, &inv.grid_values(&grid).unwrap(), &[truth], &full).unwrap();
        ex.forward(&gpu).unwrap();
        let data = ex.read(&gpu, net.image).unwrap().into_iter().map(|v| v.clamp(0.0, 1.0)).collect();
        let target = Image { channels: 3, size: inv.size, data };
        let (l, mse) = inv.light_optimum(&gpu, &grid, &target, &truth.view()).unwrap();
        assert_eq!((l.azimuth, l.elevation), (215.0, 122.5));
        // Its own image at its own light, scored per value: what is left is the network
        // rendering the window around the bunny rather than the whole frame (border effects
        // of its convs; measured 5.1e-4); a summed rather than per-value error would be
        // thousands of times larger.
        assert!(mse < 1.5e-3, "the network's own image scores {mse} at its own camera and light");
    }
}
