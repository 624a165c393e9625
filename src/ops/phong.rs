//! Phong shading of image-space maps (binds `shaders/phong.wgsl`): the paper's Section 3.3,
//! where the network predicts an albedo map and a normal map and the light is applied
//! explicitly, so gradients reach the maps and the light alike (inverse rendering of light).
//!
//! Per pixel, with the normal map stored as an image (`u = 2v - 1`, `n = u / max(|u|, 1e-6)`),
//! the light direction `l` (unit, towards the light, the normals' frame), its colour `col`,
//! the view vector `v = (0, 0, 1)` (the camera looks along -z) and `r = 2(n·l)n - l`:
//!
//! `I_c = mask * col_c * (A_c * (ambient + kd * max(0, n·l)) + ks * max(0, r·v)^shininess)`.
//!
//! The original TensorFlow code had only the Lambert and ambient terms (`ks = 0`, the
//! [`Default`]); the specular term is our addition. The light direction is used as given
//! (not renormalised), so its gradient is with respect to the raw components; a caller that
//! parameterises the light by angles gets unit vectors by construction.

use super::{expect_rank, expect_shape, reduce};
use crate::error::{Error, Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("phong");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n_pix: u32,
    hw: u32,
    c: u32,
    ambient: f32,
    kd: f32,
    ks: f32,
    shininess: f32,
    _pad: u32,
}

/// The shading model's scalar coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// Ambient term, added to the diffuse factor before the albedo multiplies it.
    pub ambient: f32,
    /// Diffuse (Lambert) weight.
    pub kd: f32,
    /// Specular weight; 0 disables the highlight (the original code's model).
    pub ks: f32,
    /// Specular exponent, finite and >= 0.
    pub shininess: f32,
}

impl Default for Phong {
    /// The original code's shading: ambient 0.1, Lambert 0.9, no specular (the exponent
    /// matters only once `ks > 0`).
    fn default() -> Self {
        Phong { ambient: 0.1, kd: 0.9, ks: 0.0, shininess: 10.0 }
    }
}

/// Phong's four inputs, or in [`Phong::backward`] their four gradients (same shapes).
#[derive(Clone, Copy, Debug)]
pub struct Inputs<'a> {
    /// Normal map `[N, 3, H, W]`, each component encoded in [0, 1] as images store them.
    pub normal: &'a Tensor,
    /// Albedo `[N, C, H, W]`, `C` = 1 (grey, broadcast over the colour) or 3.
    pub albedo: &'a Tensor,
    /// Soft object mask `[N, 1, H, W]` in [0, 1]; the background receives no light.
    pub mask: &'a Tensor,
    /// Light `[N, 6]`: unit direction towards the light (x, y, z), then colour (r, g, b).
    pub light: &'a Tensor,
}

impl Inputs<'_> {
    /// Checks the inputs against each other and returns `[N, C, H, W]`.
    fn dims(&self, op: &str) -> Result<[usize; 4]> {
        expect_rank(op, "normal", self.normal, 4)?;
        let &[n, three, h, w] = self.normal.shape() else { unreachable!() };
        if three != 3 {
            return Err(shape_err(op, format!("normal has shape {:?}, expected [N, 3, H, W]", self.normal.shape())));
        }
        expect_rank(op, "albedo", self.albedo, 4)?;
        let c = self.albedo.shape()[1];
        if c != 1 && c != 3 {
            return Err(shape_err(op, format!("albedo has shape {:?}, expected 1 or 3 channels", self.albedo.shape())));
        }
        expect_shape(op, "albedo", self.albedo, &[n, c, h, w])?;
        expect_shape(op, "mask", self.mask, &[n, 1, h, w])?;
        expect_shape(op, "light", self.light, &[n, 6])?;
        Ok([n, c, h, w])
    }

    /// Checks that `grads` has exactly these inputs' shapes.
    fn check_grads(&self, op: &str, grads: &Inputs) -> Result<()> {
        expect_shape(op, "normal gradient", grads.normal, self.normal.shape())?;
        expect_shape(op, "albedo gradient", grads.albedo, self.albedo.shape())?;
        expect_shape(op, "mask gradient", grads.mask, self.mask.shape())?;
        expect_shape(op, "light gradient", grads.light, self.light.shape())
    }
}

impl Phong {
    fn params(&self, op: &str, [n, c, h, w]: [usize; 4]) -> Result<Params> {
        if !(self.shininess.is_finite() && self.shininess >= 0.0) {
            return Err(Error::Invalid(format!("{op}: shininess {} must be finite and >= 0", self.shininess)));
        }
        let n_pix = n as u64 * (h * w) as u64;
        if n_pix * 6 > u32::MAX as u64 {
            return Err(shape_err(op, format!("{n_pix} pixels overflow 32-bit indexing")));
        }
        Ok(Params {
            n_pix: n_pix as u32,
            hw: (h * w) as u32,
            c: c as u32,
            ambient: self.ambient,
            kd: self.kd,
            ks: self.ks,
            shininess: self.shininess,
            _pad: 0,
        })
    }

    /// Shades `x` into `image` `[N, 3, H, W]`.
    pub fn forward(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Inputs, image: &Tensor) -> Result<()> {
        let op = "phong_forward";
        let dims = x.dims(op)?;
        expect_shape(op, "image", image, &[dims[0], 3, dims[2], dims[3]])?;
        let p = self.params(op, dims)?;
        let args = [Arg::R(x.normal), Arg::R(x.albedo), Arg::R(x.mask), Arg::R(x.light), Arg::W(image)];
        gpu.dispatch(pass, SHADER, op, &p, &args, grid_1d(p.n_pix as u64, 64)?)
    }

    /// Writes the gradients of all four inputs into `grads` from the upstream gradient
    /// `dimage` `[N, 3, H, W]`: [`Phong::backward_maps`] then [`Phong::backward_light`].
    pub fn backward(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Inputs,
        dimage: &Tensor,
        grads: &Inputs,
    ) -> Result<()> {
        x.check_grads("phong_backward", grads)?;
        self.backward_maps(gpu, pass, x, dimage, [grads.normal, grads.albedo, grads.mask])?;
        self.backward_light(gpu, pass, x, dimage, grads.light)
    }

    /// Writes the gradients of the normal, albedo and mask maps (in that order) from
    /// `dimage`. A grey albedo's gradient sums the three colour channels.
    pub fn backward_maps(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Inputs,
        dimage: &Tensor,
        [normal, albedo, mask]: [&Tensor; 3],
    ) -> Result<()> {
        let op = "phong_backward";
        let dims @ [n, _, h, w] = x.dims(op)?;
        expect_shape(op, "image gradient", dimage, &[n, 3, h, w])?;
        expect_shape(op, "normal gradient", normal, x.normal.shape())?;
        expect_shape(op, "albedo gradient", albedo, x.albedo.shape())?;
        expect_shape(op, "mask gradient", mask, x.mask.shape())?;
        let p = self.params(op, dims)?;
        let maps = backward_args(x, dimage, [Arg::W(normal), Arg::W(albedo), Arg::W(mask)]);
        gpu.dispatch(pass, SHADER, "phong_backward_maps", &p, &maps, grid_1d(p.n_pix as u64, 64)?)
    }

    /// Writes the light's gradient `[N, 6]` from `dimage`: per-pixel partials in an internal
    /// `[N * 6, H * W]` scratch, summed by the deterministic reduction. Callers that do not
    /// want the light's gradient (training) skip it.
    pub fn backward_light(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Inputs, dimage: &Tensor, light: &Tensor) -> Result<()> {
        let op = "phong_backward";
        let dims @ [n, _, h, w] = x.dims(op)?;
        expect_shape(op, "image gradient", dimage, &[n, 3, h, w])?;
        expect_shape(op, "light gradient", light, x.light.shape())?;
        let p = self.params(op, dims)?;
        let parts = gpu.scratch(&[n * 6, h * w])?;
        gpu.dispatch(pass, SHADER, "phong_backward_light", &p, &backward_args(x, dimage, [Arg::W(&parts)]), grid_1d(p.n_pix as u64, 64)?)?;
        reduce::sum_outer_inner(gpu, pass, &parts, [1, n * 6, h * w], 1.0, light)
    }
}

/// The backward entry points' bindings: the four inputs and the upstream gradient, then
/// the entry point's outputs.
fn backward_args<'a, const K: usize>(x: &Inputs<'a>, dimage: &'a Tensor, outs: [Arg<'a>; K]) -> Vec<Arg<'a>> {
    let mut args = vec![Arg::R(x.normal), Arg::R(x.albedo), Arg::R(x.mask), Arg::R(x.light), Arg::R(dimage)];
    args.extend(outs);
    args
}
