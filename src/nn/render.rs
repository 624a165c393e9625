//! Rendering a voxel grid with trained RenderNet weights: the library call behind
//! `rendernet render` and `examples/render.rs`.

use super::camera;
use super::rendernet::{Head, Preset, RenderNet, phong_of};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::reference::{Image, Light, View};
use crate::voxel::VoxelGrid;

/// The shipped weights: the tiny preset trained for Phong on procedural chairs (see
/// weights/README.md for the command that reproduced them and their training curve).
pub const TINY_PHONG_WEIGHTS: &[u8] = include_bytes!("../../weights/tiny-phong.safetensors");

/// A RenderNet ready to render, for one image size.
pub struct Renderer {
    preset: Preset,
    net: RenderNet,
    ex: Executor,
    size: usize,
}

impl Renderer {
    /// Builds the Phong network of `preset` for `size`-pixel images (a multiple of
    /// `2^(up stages + 2)`; the network is fully convolutional, so any such size works) and
    /// loads `weights` (safetensors bytes; `name` labels them in errors).
    pub fn new(gpu: &Gpu, preset: Preset, weights: &[u8], name: &str, size: usize) -> Result<Renderer> {
        let f = preset.image_for(preset.cam) / preset.cam;
        if size == 0 || size % (4 * f) != 0 {
            return Err(Error::Invalid(format!("image size {size} must be a positive multiple of {}", 4 * f)));
        }
        let cam_hw = size / f;
        let net = RenderNet::build(&preset, Head::Phong(phong_of(&Light::default())), 1, [cam_hw, cam_hw], false)?;
        let mut ex = Executor::new(gpu, net.graph.clone(), 0)?;
        ex.load_params_bytes(gpu, weights, name)?;
        ex.training = false;
        ex.keep(net.image);
        Ok(Renderer { preset, net, ex, size })
    }

    /// Image side in pixels.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Renders `grid` (any size: resampled to the preset's input) from `view` under `light`.
    /// Returns the RGB image `[3, size, size]`, clamped to [0, 1]; errors on a view or light
    /// that [`View::validate`] or [`Light::validate`] rejects.
    pub fn render(&mut self, gpu: &Gpu, grid: &VoxelGrid, view: &View, light: &Light) -> Result<Image> {
        // Checked here, not left to the pose tensor's NaN guard, which can only name 'pose'.
        view.validate().map_err(|m| Error::Invalid(format!("render: view: {m}")))?;
        light.validate().map_err(|m| Error::Invalid(format!("render: light: {m}")))?;
        let p = &self.preset;
        let g = if grid.dims() == [p.input; 3] {
            grid.clone()
        } else {
            grid.resample_to(p.input).map_err(|e| Error::Invalid(e.to_string()))?
        };
        let cam_hw = self.size / (p.image_for(p.cam) / p.cam);
        self.ex.feed(gpu, self.net.grid, &camera::input_values(&g))?;
        self.ex.feed(gpu, self.net.pose, &camera::pose_for_view(view, p.input, cam_hw, None))?;
        let l = self.net.light.expect("the Phong head has a light input");
        self.ex.feed(gpu, l, &camera::light_values(light))?;
        self.ex.forward(gpu)?;
        let data = self.ex.read(gpu, self.net.image)?.into_iter().map(|v| v.clamp(0.0, 1.0)).collect();
        Ok(Image { channels: 3, size: self.size, data })
    }
}
