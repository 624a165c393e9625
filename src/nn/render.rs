//! Rendering a voxel grid with trained RenderNet weights: the library call behind
//! `rendernet render` and `examples/render.rs`.

use super::camera;
use super::rendernet::{Head, Preset, RenderNet, phong_of};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::reference::{Image, Light, Shader, View};
use crate::voxel::VoxelGrid;

/// The shipped weights: the tiny preset trained for Phong on procedural chairs, tables, sofas
/// and primitives (weights/README.md: the commands that made them, their log and curve).
pub static TINY_PHONG_WEIGHTS: &[u8] = include_bytes!("../../weights/tiny-phong.safetensors");

/// The `nano` preset's Phong weights (the rung below tiny: faster, less accurate; same data
/// and recipe, shorter; weights/README.md).
pub static NANO_PHONG_WEIGHTS: &[u8] = include_bytes!("../../weights/nano-phong.safetensors");

/// The tiny preset trained for ambient occlusion (`--shader ao`) on the same shape families
/// (weights/README.md).
pub static TINY_AO_WEIGHTS: &[u8] = include_bytes!("../../weights/tiny-ao.safetensors");

/// The tiny preset trained for toon shading (`--shader toon`), started from the Phong
/// weights' trunk (weights/README.md). Soft: it draws the lit faces and the silhouette, not
/// yet the crisp bands and lines.
pub static TINY_TOON_WEIGHTS: &[u8] = include_bytes!("../../weights/tiny-toon.safetensors");

/// The tiny preset trained for line drawings (`--shader contour`: occluding, crease and
/// suggestive contours), started from the Phong weights' trunk and trained at 64^3
/// (weights/README.md). Soft grey strokes where the reference draws crisp black ones.
pub static TINY_CONTOUR_WEIGHTS: &[u8] = include_bytes!("../../weights/tiny-contour.safetensors");

/// Phong weights of the `base` preset (64^3 grids), trained on an NVIDIA H100 with this binary
/// (weights/README.md): the most accurate shipped model, `--quality best`.
pub static BASE_PHONG_WEIGHTS: &[u8] = include_bytes!("../../weights/base-phong.safetensors");

/// The tiny preset for coloured voxels (`.vox` palettes, mesh vertex colours, painted
/// procedural shapes): the Phong weights widened to RGB input and albedo and fine-tuned on
/// `dataset --colour` (weights/README.md). `render` picks it for a grid that has colour.
pub static TINY_PHONG_COLOUR_WEIGHTS: &[u8] = include_bytes!("../../weights/tiny-phong-colour.safetensors");

/// The `base` preset for coloured voxels: [`BASE_PHONG_WEIGHTS`] widened to RGB input and
/// albedo, its colour path taken from [`TINY_PHONG_COLOUR_WEIGHTS`], fine-tuned on `dataset
/// --colour` (weights/README.md). The most accurate colour model: `render`'s default for a
/// grid that has colour.
pub static BASE_PHONG_COLOUR_WEIGHTS: &[u8] = include_bytes!("../../weights/base-phong-colour.safetensors");

/// A shipped Phong model and its measured accuracy, for picking one by quality.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShippedModel {
    /// Preset name.
    pub preset: &'static str,
    /// Held-out object PSNR (dB) on 200 views of 20 mixed shapes no shipped model saw
    /// (`rendernet dataset --shapes mixed --count 20 --views 10 --res 64 --image 128 --seed 4242
    /// --test-fraction 1`, then `rendernet eval`; README "Speed against accuracy").
    pub object_psnr: f64,
}

/// The shipped Phong models, fastest first (each is slower and more accurate than the one
/// before it; `rendernet frontier` measures both).
pub const SHIPPED: &[ShippedModel] = &[
    ShippedModel { preset: "nano", object_psnr: 19.81 },
    ShippedModel { preset: "tiny", object_psnr: 22.06 },
    ShippedModel { preset: "base", object_psnr: 23.43 },
];

/// The fastest shipped model whose held-out object PSNR is at least `db`; an error naming
/// the best there is when none reaches it.
pub fn shipped_for_psnr(db: f64) -> Result<ShippedModel> {
    if !db.is_finite() {
        return Err(Error::Invalid(format!("--target-psnr {db}: expected a number of dB")));
    }
    SHIPPED.iter().find(|m| m.object_psnr >= db).copied().ok_or_else(|| {
        let best = SHIPPED.last().expect("at least one shipped model");
        Error::Invalid(format!(
            "--target-psnr {db}: no shipped model reaches it; the most accurate, '{}', scores {:.2} dB held-out object PSNR (train a larger preset and pass --weights)",
            best.preset, best.object_psnr
        ))
    })
}

/// The shipped Phong weights of `preset`, if any.
pub fn shipped_phong_weights(preset: &Preset) -> Option<&'static [u8]> {
    shipped_weights(preset, Shader::Phong)
}

/// The shipped weights of `preset` trained for `shader`, if any (for a colour preset, only
/// tiny's Phong weights).
pub fn shipped_weights(preset: &Preset, shader: Shader) -> Option<&'static [u8]> {
    if preset.colour {
        return match (preset.name, shader) {
            ("tiny", Shader::Phong) => Some(TINY_PHONG_COLOUR_WEIGHTS),
            ("base", Shader::Phong) => Some(BASE_PHONG_COLOUR_WEIGHTS),
            _ => None,
        };
    }
    match (preset.name, shader) {
        ("tiny", Shader::Phong) => Some(TINY_PHONG_WEIGHTS),
        ("nano", Shader::Phong) => Some(NANO_PHONG_WEIGHTS),
        ("base", Shader::Phong) => Some(BASE_PHONG_WEIGHTS),
        ("tiny", Shader::AmbientOcclusion) => Some(TINY_AO_WEIGHTS),
        ("tiny", Shader::Toon) => Some(TINY_TOON_WEIGHTS),
        ("tiny", Shader::Contour) => Some(TINY_CONTOUR_WEIGHTS),
        _ => None,
    }
}

/// The most accurate shipped model with weights for `shader` (colour weights for a coloured
/// grid), by the order of [`SHIPPED`]: what `render` uses when no preset is named.
pub fn most_accurate_shipped(shader: Shader, coloured: bool) -> Option<&'static str> {
    let has = |n: &str| Preset::by_name(n).is_ok_and(|p| shipped_weights(&if coloured { p.with_colour() } else { p }, shader).is_some());
    SHIPPED.iter().rev().map(|m| m.preset).find(|&n| has(n))
}

/// The shaders some preset has shipped weights for, with those presets' names (the presets of
/// [`SHIPPED`], the only ones with weights in the binary).
pub fn shipped_shaders() -> Vec<(Shader, Vec<&'static str>)> {
    Shader::ALL
        .into_iter()
        .map(|s| (s, SHIPPED.iter().map(|m| m.preset).filter(|&n| Preset::by_name(n).is_ok_and(|p| shipped_weights(&p, s).is_some())).collect::<Vec<_>>()))
        .filter(|(_, names)| !names.is_empty())
        .collect()
}

/// Whether RenderNet weights were trained on coloured voxels: their first 3D conv
/// (`enc3d.conv1.weight`, OIDHW) takes 4 input channels. False for weights without it (the
/// EC baselines); malformed bytes are an error naming `name`.
pub fn weights_take_colour(weights: &[u8], name: &str) -> Result<bool> {
    let st = safetensors::SafeTensors::deserialize(weights).map_err(|e| Error::Invalid(format!("{name}: not a safetensors file: {e}")))?;
    Ok(st.tensor("enc3d.conv1.weight").is_ok_and(|t| t.shape().get(1) == Some(&4)))
}

/// A RenderNet ready to render, for one image size.
pub struct Renderer {
    preset: Preset,
    shader: Shader,
    weights: Vec<u8>,
    name: String,
    /// Networks built so far, by camera window `[h, w]` (one per window size).
    nets: Vec<([usize; 2], RenderNet, Executor)>,
    /// The image side asked for.
    size: usize,
    /// The side the network draws: `size`, or the preset's trained side when `size` is larger
    /// (the network then draws at the camera-grid density it learned and the image is
    /// upscaled; drawn directly at 4x the density, the default bunny fell from 22.85 to 11.51
    /// dB object PSNR).
    drawn: usize,
    margin: Option<usize>,
}

/// Camera voxels of context [`Renderer`] keeps around the object's projected bounding box.
/// The network's receptive field reaches ~18 camera voxels in the image plane, but its
/// response to empty space fades within a few: with 2 the default scene's object PSNR is
/// within 0.2 dB of the whole frame's (the shipped weights: 22.37 cropped, 22.22 whole;
/// margins 2 to 12 agree within 0.05 dB; tests/model.rs measures it).
pub const CROP_MARGIN: usize = 2;

/// Networks (one per window size) a [`Renderer`] keeps built.
const MAX_WINDOWS: usize = 6;

impl Renderer {
    /// Builds the Phong network of `preset` for `size`-pixel images (a multiple of
    /// `2^(up stages + 2)`; the network is fully convolutional, so any such size works; sizes
    /// above the preset's trained image side are drawn at that side and upscaled) and loads
    /// `weights` (safetensors bytes; `name` labels them in errors).
    pub fn new(gpu: &Gpu, preset: Preset, weights: &[u8], name: &str, size: usize) -> Result<Renderer> {
        Renderer::for_shader(gpu, preset, Shader::Phong, weights, name, size)
    }

    /// [`Renderer::new`] for weights trained on another shader's images (a dataset made with
    /// `--shader`): Phong has the normal/albedo/mask heads and takes the light; every other
    /// shader is one image head of [`Shader::channels`] channels that ignores the light.
    /// Weights trained on coloured voxels (4 input channels, see [`weights_take_colour`])
    /// switch the preset to [`Preset::with_colour`], and weights trained at another input
    /// side read grids at that side ([`Preset::for_weights`]).
    pub fn for_shader(gpu: &Gpu, preset: Preset, shader: Shader, weights: &[u8], name: &str, size: usize) -> Result<Renderer> {
        let preset = preset.for_weights(weights, name)?;
        let f = preset.image_for(preset.cam) / preset.cam;
        if size == 0 || size % (4 * f) != 0 {
            return Err(Error::Invalid(format!("image size {size} must be a positive multiple of {}", 4 * f)));
        }
        let drawn = if preset.fully_convolutional() { size.min(preset.image_for(preset.cam)) } else { size };
        let mut r = Renderer { preset, shader, weights: weights.to_vec(), name: name.to_string(), nets: Vec::new(), size, drawn, margin: Some(CROP_MARGIN) };
        // Built now so bad weights fail here, not at the first render.
        let full = drawn / f;
        r.net_for(gpu, [full, full])?;
        Ok(r)
    }

    /// Crops the camera grid to the object's projected box grown by `margin` camera voxels
    /// (`Some`, default [`CROP_MARGIN`]: empty space costs nothing), or renders the whole
    /// frame (`None`).
    pub fn with_crop_margin(mut self, margin: Option<usize>) -> Renderer {
        self.margin = margin;
        self
    }

    fn net_for(&mut self, gpu: &Gpu, hw: [usize; 2]) -> Result<usize> {
        if let Some(i) = self.nets.iter().position(|n| n.0 == hw) {
            return Ok(i);
        }
        // A few windows are kept (a turntable revisits them); more would only hold GPU memory.
        if self.nets.len() == MAX_WINDOWS {
            self.nets.remove(1); // index 0 is the whole frame, built first
        }
        let head = match self.shader {
            Shader::Phong => Head::Phong(phong_of(&Light::default())),
            s => Head::Image(s.channels()),
        };
        let net = RenderNet::build(&self.preset, head, 1, hw, false)?;
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        ex.load_params_bytes(gpu, &self.weights, &self.name)?;
        ex.training = false;
        ex.keep(net.image);
        self.nets.push((hw, net, ex));
        Ok(self.nets.len() - 1)
    }

    /// Image side in pixels.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The side the network draws before any upscaling to [`Renderer::size`].
    pub fn drawn_size(&self) -> usize {
        self.drawn
    }

    /// The shader the weights were trained for.
    pub fn shader(&self) -> Shader {
        self.shader
    }

    /// Renders `grid` (any size: resampled to the preset's input) from `view` under `light`
    /// (ignored by shaders other than Phong). Returns the image `[C, size, size]` (C: the
    /// shader's [`Shader::channels`]), clamped to [0, 1]; errors on a view or light that
    /// [`View::validate`] or [`Light::validate`] rejects.
    pub fn render(&mut self, gpu: &Gpu, grid: &VoxelGrid, view: &View, light: &Light) -> Result<Image> {
        // Checked here, not left to the pose tensor's NaN guard, which can only name 'pose'.
        view.validate().map_err(|m| Error::Invalid(format!("render: view: {m}")))?;
        light.validate().map_err(|m| Error::Invalid(format!("render: light: {m}")))?;
        let p = self.preset.clone();
        let g = if grid.dims() == [p.input; 3] { grid.clone() } else { grid.resample_to(p.input)? };
        let f = p.image_for(p.cam) / p.cam;
        let (size, cam_hw) = (self.drawn, self.drawn / f);
        let win = match self.margin {
            Some(m) if p.fully_convolutional() => object_window(&g, view, cam_hw, m),
            _ => [0, 0, cam_hw, cam_hw],
        };
        let i = self.net_for(gpu, [win[2], win[3]])?;
        let (_, net, ex) = &mut self.nets[i];
        ex.feed(gpu, net.grid, &camera::input_values_with(&g, self.preset.in_channels()))?;
        ex.feed(gpu, net.pose, &p.pose_values(view, cam_hw, Some(win)))?;
        if let Some(l) = net.light {
            ex.feed(gpu, l, &camera::light_values(light))?;
        }
        ex.forward(gpu)?;
        let part = ex.read(gpu, net.image)?;
        // Pasted into a frame of the shader's background: outside the window is empty space.
        let (h, w, ch) = (win[2] * f, win[3] * f, self.shader.channels());
        let mut data = vec![self.shader.background(); ch * size * size];
        for c in 0..ch {
            for y in 0..h {
                let dst = (c * size + win[0] * f + y) * size + win[1] * f;
                let src = (c * h + y) * w;
                for (d, s) in data[dst..dst + w].iter_mut().zip(&part[src..src + w]) {
                    *d = s.clamp(0.0, 1.0);
                }
            }
        }
        let img = Image { channels: ch, size, data };
        Ok(if size == self.size { img } else { img.resized(self.size) })
    }
}

/// The camera-grid window `[h0, w0, h, w]` (sides multiples of 4, inside the `cam_hw` grid)
/// covering every voxel of `grid` above zero as `view` projects it, grown by `margin`.
/// The whole frame when the grid is empty.
pub fn object_window(grid: &VoxelGrid, view: &View, cam_hw: usize, margin: usize) -> [usize; 4] {
    let dims = grid.dims();
    // Object frame (reference::camera): voxel centre i along axis a sits at (i + 0.5 - n_a/2) / L.
    let l = *dims.iter().max().expect("three axes") as f64;
    let r = view.rotation().as_dmat3();
    let k = cam_hw as f64 * view.scale() / 2.0; // camera voxels per object unit
    let centre = (cam_hw as f64 - 1.0) / 2.0;
    let reach = 3f64.sqrt() / 2.0 / l * k; // a voxel's half diagonal, projected
    let (mut rows, mut cols) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
    for d in 0..dims[0] {
        for h in 0..dims[1] {
            for w in 0..dims[2] {
                if grid.get(d, h, w) <= 0.0 {
                    continue;
                }
                let at = |i: usize, a: usize| (i as f64 + 0.5 - dims[a] as f64 / 2.0) / l;
                let c = r * glam::DVec3::new(at(d, 0), at(h, 1), at(w, 2));
                // Camera grid: rows down the image (-y), columns right (+x), voxel centres at integers.
                let (row, col) = (centre - c.y * k, centre + c.x * k);
                rows = (rows.0.min(row - reach), rows.1.max(row + reach));
                cols = (cols.0.min(col - reach), cols.1.max(col + reach));
            }
        }
    }
    if rows.0 == f64::MAX {
        return [0, 0, cam_hw, cam_hw];
    }
    let span = |(a, b): (f64, f64)| -> (usize, usize) {
        let first = (a.floor() - margin as f64).max(0.0) as usize;
        let last = ((b.ceil() + margin as f64).max(0.0) as usize).min(cam_hw - 1);
        let len = (last.saturating_sub(first) + 1).next_multiple_of(4).min(cam_hw);
        (first.min(cam_hw - len), len)
    };
    let ((h0, h), (w0, w)) = (span(rows), span(cols));
    [h0, w0, h, w]
}
