//! The known grid drawn by the exact renderer (the reference ray marcher) instead of the
//! network: how well a camera explains the image ([`Inverter::exact_scores`], what
//! [`super::Pick::Exact`] ranks hypotheses by), the light the grid and the image alone
//! allow ([`Inverter::light_exact`], the light a [`super::Pick::Exact`] search reports), and
//! the exact polish of camera and light that refines its best hypotheses. The maps (normal, albedo, mask) are drawn at [`SUB`] x
//! [`SUB`] sub-pixels and each sub-pixel is shaded before the block is averaged, with the
//! highlight cut where the light is behind the surface: how the datasets' targets are drawn.
//! Averaging normals before shading (sessions 33-34) left the light 11.8 degrees off at the
//! true camera (median, 60 chair views); shading first, 6.7.

use super::light::Maps;
use super::starts::{POLISH_STEP_DEGREES, light_grid, light_starts};
use super::{Inverter, RADIUS, Window};
use crate::error::Result;
use crate::gpu::{Gpu, Tensor};
use crate::nn::camera;
use crate::nn::rendernet::phong_of;
use crate::reference::{GBUF_CHANNELS, GpuGrid, Image, Light, Options, Part, RayMarcher, View};
use crate::voxel::VoxelGrid;

/// Sub-pixels per image pixel along each axis of the exact maps: `dataset`'s targets average
/// 2 x 2 (its default `--supersample`).
const SUB: usize = 2;

/// Smoothings of the grid ([`VoxelGrid::smoothed`], applied 0..=this many times) the exact
/// scene chooses among. A binary grid of a curved mesh shades its stair steps as bands the
/// image does not have; on the 27 real meshes (binary 64^3 grids, targets from a smooth
/// 128^3 one) the light at the true camera went 20.7 -> 11.5 degrees median when the scene
/// chose among 0..=2 passes, while the chairs (boxes, which the binary grid draws exactly)
/// mostly keep 0.
const SMOOTHINGS: usize = 2;

/// Camera steps of the exact polish (degrees; the log-radius step is this / 100), coarse to
/// fine; each is taken while it improves the score, at most [`POLISH_ROUNDS`] times.
const POLISH_STEPS: [f64; 4] = [2.0, 1.0, 0.5, 0.25];
const POLISH_ROUNDS: usize = 6;

/// The known grid as the exact renderer draws it for one target: the grid and its smoothings
/// on the GPU (one chosen, [`Inverter::choose_smoothing`]), the window around the target's
/// foreground, its pixels, and the G-buffer the maps are read from ([`SUB`] times the window's larger side,
/// square). Only the window is marched, not the whole frame: a chair at radius 6 covers a
/// tenth of it, and a search scores ~500 cameras per image. The maps are the unshaded
/// G-buffer: on lavapipe (Mesa 22.3.6) every dispatch of the reference shading pass leaked
/// ~0.6 MB, which ran `eval-invert` out of memory.
pub(super) struct ExactScene {
    /// The grid and its [`SMOOTHINGS`], uploaded once.
    grids: Vec<GpuGrid>,
    /// Which of `grids` the maps are drawn from.
    pub(super) chosen: usize,
    win: Window,
    target: Vec<f32>,
    /// The target's foreground pixels inside the window.
    fg_pixels: usize,
    gbuf: Tensor,
}

impl ExactScene {
    /// How many grids (the grid and its smoothings) `chosen` picks among.
    pub(super) fn smoothings(&self) -> usize {
        self.grids.len()
    }
}

impl Inverter {
    /// The exact scene of `target`: `grid` and its [`SMOOTHINGS`] uploaded, the one that
    /// explains `target` best from `view` under its best light of the 20-degree grid chosen.
    pub(super) fn exact_scene(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, view: &View) -> Result<ExactScene> {
        let (win, t) = self.window(target)?;
        let fg_pixels = win.crop_mask(&self.foreground(target)?, self.size).iter().filter(|&&f| f).count();
        let [h, w] = win.pixel_dims();
        let side = SUB * h.max(w);
        let gbuf = Tensor::zeros(gpu, &[GBUF_CHANNELS, side, side])?;
        let mut grids = vec![GpuGrid::upload(gpu, grid)?];
        let mut g = grid.smoothed();
        for k in 0..SMOOTHINGS {
            grids.push(GpuGrid::upload(gpu, &g)?);
            if k + 1 < SMOOTHINGS {
                g = g.smoothed();
            }
        }
        let mut scene = ExactScene { grids, chosen: 0, win, target: t, fg_pixels, gbuf };
        self.choose_smoothing(gpu, &mut scene, view)?;
        Ok(scene)
    }

    /// Draws `scene`'s maps from whichever of its grids explains its target best from
    /// `view` under its best light of the 20-degree grid.
    fn choose_smoothing(&self, gpu: &Gpu, scene: &mut ExactScene, view: &View) -> Result<()> {
        let mut best = (f64::INFINITY, 0);
        for k in 0..scene.grids.len() {
            scene.chosen = k;
            let e = self.exact_fit(gpu, scene, view, &light_starts())?.0;
            if e < best.0 {
                best = (e, k);
            }
        }
        scene.chosen = best.1;
        Ok(())
    }

    /// The light, among every direction of the 5-degree grid and then half-degree steps
    /// around the best, under which the exact renderer's maps of `grid` (its exact scene at
    /// `view`) seen from `view` best match `target` over the search window: what the grid and
    /// the image alone say about the light, with no network in the way. Far from the true
    /// light, no network reading this grid could find it either: a light behind the object
    /// leaves the camera only ambient and rims.
    pub fn light_exact(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, view: &View) -> Result<Light> {
        self.light_search(gpu, &self.exact_scene(gpu, grid, target, view)?, view)
    }

    /// [`Inverter::light_exact`] in a scene already built for the same grid and target
    /// (its smoothing chosen again at `view`), so the grids are not uploaded again.
    pub(super) fn light_in(&self, gpu: &Gpu, scene: &mut ExactScene, view: &View) -> Result<Light> {
        self.choose_smoothing(gpu, scene, view)?;
        self.light_search(gpu, scene, view)
    }

    /// The light search of [`Inverter::light_exact`] in `scene` as it is.
    fn light_search(&self, gpu: &Gpu, scene: &ExactScene, view: &View) -> Result<Light> {
        let coarse = self.exact_fit(gpu, scene, view, &light_grid(POLISH_STEP_DEGREES))?.1;
        Ok(self.exact_fit(gpu, scene, view, &lights_around(&coarse, 0.5, 3.0))?.1)
    }

    /// How well the exact renderer's maps of `grid` explain `target` from each of `views`:
    /// the summed squared error over the window around `target`'s foreground under the best
    /// light of the 20-degree grid (162 directions relative to the camera, the network's
    /// material constants), lowest best; the grid smoothed as the image prefers from
    /// `views[0]` ([`SMOOTHINGS`]). What [`super::Pick::Exact`] ranks the search's
    /// hypotheses by.
    pub fn exact_scores(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, views: &[View]) -> Result<Vec<f64>> {
        let Some(first) = views.first() else { return Ok(Vec::new()) };
        self.scores_in(gpu, &self.exact_scene(gpu, grid, target, first)?, views)
    }

    /// [`Inverter::exact_scores`] in a scene already chosen, so that scores of several
    /// calls compare.
    pub(super) fn scores_in(&self, gpu: &Gpu, scene: &ExactScene, views: &[View]) -> Result<Vec<f64>> {
        let lights = light_starts();
        views.iter().map(|v| Ok(self.exact_fit(gpu, scene, v, &lights)?.0)).collect()
    }

    /// The exact polish: from `view`, the light of the 5-degree grid that fits best there,
    /// then a pattern search on azimuth, elevation and log radius ([`POLISH_STEPS`]), each
    /// camera scored under its best light near the current one, and last the light in
    /// half-degree steps. Returns the summed squared error, camera and light; the camera
    /// moves only when the score drops, so it never scores worse than `view`.
    pub(super) fn exact_polish(&self, gpu: &Gpu, scene: &ExactScene, view: &View) -> Result<(f64, View, Light)> {
        let (mut e, mut light) = self.exact_fit(gpu, scene, view, &light_grid(POLISH_STEP_DEGREES))?;
        let mut cam = *view;
        for step in POLISH_STEPS {
            for _ in 0..POLISH_ROUNDS {
                let mut moved = false;
                for c in nudges(&cam, step) {
                    let (ce, cl) = self.exact_fit(gpu, scene, &c, &lights_around(&light, step, 2.0 * step))?;
                    if ce < e {
                        (e, cam, light, moved) = (ce, c, cl, true);
                    }
                }
                if !moved {
                    break;
                }
            }
        }
        let (fe, fl) = self.exact_fit(gpu, scene, &cam, &lights_around(&light, 0.5, 2.0))?;
        Ok(if fe < e { (fe, cam, fl) } else { (e, cam, light) })
    }

    /// The G-buffer of `scene`'s window seen from `view` (`[GBUF_CHANNELS, side, side]`, the
    /// window's [`SUB`]-times finer pixels in its top-left corner), read back.
    fn march(&self, gpu: &Gpu, scene: &ExactScene, view: &View) -> Result<Vec<f32>> {
        let rm = RayMarcher::new(gpu).with_options(Options { supersample: 1, ..Options::default() });
        let fine = Window { f: SUB * scene.win.f, ..scene.win };
        let part = Part { frame: (SUB * self.size) as u32, x0: (fine.cam[1] * fine.f) as u32, y0: (fine.cam[0] * fine.f) as u32 };
        gpu.run(|pass| rm.record_gbuffer(gpu, pass, &scene.grids[scene.chosen], view, Some(part), false, &scene.gbuf))?;
        scene.gbuf.to_vec(gpu)
    }

    /// `view` moved along its line of sight until the grid's silhouette covers as many
    /// window pixels (any of its sub-pixels hit) as the target's foreground (area goes as
    /// 1 / radius^2; two steps, inside the search's radius range). A camera grid at the network's radius ranks badly where
    /// that radius is off: on one real mesh (silla2) the network's best was 11% too far, and
    /// at its radius the grid cells within 5 degrees of the truth scored below cells 20
    /// degrees off; at the true radius they scored best.
    pub(super) fn sized(&self, gpu: &Gpu, scene: &ExactScene, view: &View) -> Result<View> {
        let [h, w] = scene.win.pixel_dims();
        let side = scene.gbuf.shape()[1];
        let mut v = *view;
        for _ in 0..2 {
            let g = self.march(gpu, scene, &v)?;
            let hit = |y: usize, x: usize| (0..SUB * SUB).any(|k| g[(SUB * y + k / SUB) * side + SUB * x + k % SUB] != 0.0);
            let covered = (0..h * w).filter(|&i| hit(i / w, i % w)).count();
            if covered == 0 {
                break;
            }
            v.radius = (v.radius * (covered as f64 / scene.fg_pixels as f64).sqrt()).clamp(RADIUS.0, RADIUS.1);
        }
        Ok(v)
    }

    /// The best of `lights` (azimuth, elevation) for the exact maps of `scene` seen from
    /// `view`, with its summed squared error against the scene's target.
    fn exact_fit(&self, gpu: &Gpu, scene: &ExactScene, view: &View, lights: &[(f64, f64)]) -> Result<(f64, Light)> {
        let g = self.march(gpu, scene, view)?;
        let fine = Window { f: SUB * scene.win.f, ..scene.win };
        let [h, w] = fine.pixel_dims();
        let side = scene.gbuf.shape()[1];
        // Channel `c` of the window's pixels, where the ray hit (0 elsewhere, as the shading
        // pass draws the background), through `f`.
        let at = |c: usize, f: fn(f32) -> f32| -> Vec<f32> {
            (0..h * w).map(|i| (i / w) * side + i % w).map(|k| if g[k] != 0.0 { f(g[c * side * side + k]) } else { 0.0 }).collect()
        };
        let encode = |n: f32| (n + 1.0) * 0.5; // as the Normal image encodes a normal
        let normal: Vec<f32> = [2, 3, 4].iter().flat_map(|&c| at(c, encode)).collect();
        let albedo: Vec<f32> = [5, 6, 7].iter().flat_map(|&c| at(c, |a| a)).collect();
        let mask = at(0, |_| 1.0);
        let maps = Maps::exact(&normal, &albedo, &mask, SUB, scene.win.pixel_dims()[1]);
        let ph = phong_of(&self.head_light);
        let best = lights
            .iter()
            .map(|&(azimuth, elevation)| {
                let l = Light { azimuth, elevation, ..self.head_light };
                (maps.sse(&ph, &camera::light_values(&l), &scene.target), l)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("the light list is not empty");
        Ok(best)
    }
}

/// The six cameras one `step` (degrees; log radius `step / 100`) from `v` along azimuth,
/// elevation and radius, kept inside the search's ranges.
fn nudges(v: &View, step: f64) -> Vec<View> {
    let r = |k: f64| (v.radius.ln() + k * step / 100.0).exp().clamp(RADIUS.0, RADIUS.1);
    vec![
        View { azimuth: (v.azimuth + step).rem_euclid(360.0), ..*v },
        View { azimuth: (v.azimuth - step).rem_euclid(360.0), ..*v },
        View { elevation: (v.elevation + step).min(179.0), ..*v },
        View { elevation: (v.elevation - step).max(1.0), ..*v },
        View { radius: r(1.0), ..*v },
        View { radius: r(-1.0), ..*v },
    ]
}

/// Light directions `(azimuth, elevation)` every `step` degrees within `span` of `l`'s,
/// `l`'s own included, elevations kept inside (0, 180).
fn lights_around(l: &Light, step: f64, span: f64) -> Vec<(f64, f64)> {
    let n = (span / step).round() as i64;
    (-n..=n)
        .flat_map(|i| (-n..=n).map(move |j| ((l.azimuth + i as f64 * step).rem_euclid(360.0), (l.elevation + j as f64 * step).clamp(0.5, 179.5))))
        .collect()
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::{angle_between, light_direction, view_direction};
    use super::*;
    use crate::nn::rendernet::Preset;
    use crate::reference::Shader;

    /// The bunny's camera in these tests.
    pub(in crate::invert) const VIEW: View = View { azimuth: 75.0, elevation: 60.0, radius: 3.5 };

    /// The nano inverter and the bunny, with an exact Phong image of it from [`VIEW`] under
    /// `light` (2 x 2 sub-pixels, as `dataset` draws its targets).
    pub(in crate::invert) fn bunny_under(gpu: &Gpu, light: &Light) -> (Inverter, VoxelGrid, Image) {
        let inv = Inverter::new(Preset::nano(), crate::nn::render::NANO_PHONG_WEIGHTS, "nano", Light::default()).unwrap();
        let grid = crate::voxel::bunny();
        let rm = RayMarcher::new(gpu).with_options(Options { supersample: 2, ..Options::default() });
        let target = rm.render(gpu, &grid, &VIEW, light, Shader::Phong, inv.size as u32).unwrap();
        (inv, grid, target)
    }

    /// Fitted to the exact renderer's own maps, the light that drew an exact Phong image of
    /// the bunny (5-degree grid lights: from the front left, and from behind and below) comes
    /// back exactly: the maps are drawn and shaded as the image was (2 x 2 sub-pixels
    /// shaded, then averaged), so the only difference is f32 rounding, far below the nearest
    /// other light's error.
    #[test]
    fn exact_light_of_an_exact_image_is_the_light_that_drew_it() {
        let gpu = Gpu::new().unwrap();
        for truth in [Light { azimuth: 325.0, elevation: 72.5, ..Light::default() }, Light { azimuth: 150.0, elevation: 117.5, ..Light::default() }] {
            let (inv, grid, target) = bunny_under(&gpu, &truth);
            let l = inv.light_exact(&gpu, &grid, &target, &VIEW).unwrap();
            let off = angle_between(light_direction(&truth), light_direction(&l));
            assert!(off < 0.01, "exact light ({}, {}) is {off:.2} degrees from the truth ({}, {})", l.azimuth, l.elevation, truth.azimuth, truth.elevation);
        }
    }

    /// The exact polish walks back to the camera and light that drew an exact image from a
    /// start 3 degrees round, 2 degrees up and 4% farther, and never scores above its start.
    #[test]
    fn exact_polish_returns_to_the_camera_that_drew_the_image() {
        let gpu = Gpu::new().unwrap();
        let truth = Light { azimuth: 325.0, elevation: 72.5, ..Light::default() };
        let (inv, grid, target) = bunny_under(&gpu, &truth);
        let start = View { azimuth: 78.0, elevation: 62.0, radius: 3.5 * 1.04 };
        let scene = inv.exact_scene(&gpu, &grid, &target, &start).unwrap();
        let (e, v, l) = inv.exact_polish(&gpu, &scene, &start).unwrap();
        let start_score = inv.exact_fit(&gpu, &scene, &start, &light_grid(POLISH_STEP_DEGREES)).unwrap().0;
        assert!(e <= start_score, "polished {e} above the start's {start_score}");
        let cam_off = angle_between(view_direction(&VIEW), view_direction(&v));
        let light_off = angle_between(light_direction(&truth), light_direction(&l));
        assert!(cam_off < 0.5 && light_off < 1.0 && (v.radius / VIEW.radius - 1.0).abs() < 0.01, "camera {v:?} ({cam_off:.2} deg off), light {light_off:.2} deg off, score {e}");
    }

    /// From 15% too near and 15% too far, sizing brings the camera back within 3% of the
    /// radius that drew an exact image: its silhouette's area goes as 1 / radius^2.
    #[test]
    fn sizing_finds_the_radius_that_drew_the_image() {
        let gpu = Gpu::new().unwrap();
        let (inv, grid, target) = bunny_under(&gpu, &Light::default());
        let scene = inv.exact_scene(&gpu, &grid, &target, &VIEW).unwrap();
        for k in [0.85, 1.15] {
            let v = inv.sized(&gpu, &scene, &View { radius: VIEW.radius * k, ..VIEW }).unwrap();
            assert!((v.radius / VIEW.radius - 1.0).abs() < 0.03, "from {k} x the radius, sized to {} (truth {})", v.radius, VIEW.radius);
        }
    }
}
