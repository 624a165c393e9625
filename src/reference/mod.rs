//! The conventional renderer RenderNet learns to imitate: ground-truth images of a voxel
//! grid's smooth surface, on the GPU.
//!
//! The surface is the 0.5 iso-surface of the trilinearly interpolated occupancy (voxel
//! centres at integer grid coordinates, 0 outside the grid), found per pixel by an
//! orthographic ray march (fixed step, then bisection at the first crossing); normals come
//! from the central-difference gradient of the same field. For smoother ground truth pass a
//! finer grid than the network sees (e.g. 4x, from [`crate::voxel::Shape::to_grid`] or the
//! voxeliser): the object frame is resolution-independent, so the image does not change size.
//!
//! Two compute passes in one submit: `shaders/reference_march.wgsl` writes a G-buffer
//! (mask, depth, normal, albedo, ambient occlusion) at `size * supersample` pixels, and
//! `shaders/reference_shade.wgsl` shades it per [`Shader`] and averages the sub-pixels.
//! The camera and light conventions are in [`camera`]. The background is 0 (black) in every
//! output except [`Shader::Contour`], which draws black lines on white.

pub mod camera;
mod image;

pub use camera::{Light, View};
pub use image::{Image, png_path_problem, write_png};

use crate::error::{Error, Result};
use crate::gpu::{self, Arg, Gpu, Tensor};
use crate::voxel::VoxelGrid;

const MARCH: gpu::Shader =
    gpu::wgsl!("reference_march");
const SHADE: gpu::Shader =
    gpu::wgsl!("reference_shade");

/// Largest whole image a [`Part`] may belong to, pixels per side.
pub const MAX_FRAME: u32 = 16384;

/// G-buffer channels written by the march pass ([`RayMarcher::record_gbuffer`]).
pub const GBUF_CHANNELS: usize = 9;

/// What the reference renderer outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shader {
    /// Phong shading with a specular term, RGB (see [`Light`]).
    Phong,
    /// Surface colour: 1 (white) or the grid's interpolated colour, RGB.
    Albedo,
    /// Camera-frame unit normal encoded `(n + 1) / 2` (x right, y up, z towards the camera), RGB.
    Normal,
    /// `(1 + z) / 2` of the hit's camera-frame `z` (object units, towards the camera): nearer
    /// is brighter, the object's range is within `(0.07, 0.93)`, background 0. Grey.
    Depth,
    /// Coverage: 1 where the ray hits (fractional at edges when supersampled). Grey.
    Mask,
    /// Four-band diffuse (0, 1/3, 2/3, 1 of the diffuse term) plus the [`Shader::Contour`]
    /// lines in black, RGB.
    Toon,
    /// Black lines on white: occluding contours (silhouette and depth jumps), creases, and
    /// suggestive contours (DeCarlo et al. 2003: minima of `n.v` along the view direction
    /// projected on the surface, see [`Options::suggestive_bend`]). Grey.
    Contour,
    /// Ambient occlusion, 1 = unoccluded: 64 stratified cosine-weighted directions, each
    /// marched a short way (deterministic, noise-free). Grey.
    AmbientOcclusion,
}

impl Shader {
    /// Every shader, in a fixed order.
    pub const ALL: [Shader; 8] = [
        Shader::Phong,
        Shader::Albedo,
        Shader::Normal,
        Shader::Depth,
        Shader::Mask,
        Shader::Toon,
        Shader::Contour,
        Shader::AmbientOcclusion,
    ];

    /// Output channels: 3 (RGB) or 1 (grey).
    pub fn channels(self) -> usize {
        match self {
            Shader::Phong | Shader::Albedo | Shader::Normal | Shader::Toon => 3,
            _ => 1,
        }
    }

    /// The value of a background pixel (no surface hit): contours are drawn black on white
    /// (reference_shade.wgsl), every other shader on black.
    pub fn background(self) -> f32 {
        if self == Shader::Contour { 1.0 } else { 0.0 }
    }

    /// Short lowercase name, as the CLI spells it.
    pub fn name(self) -> &'static str {
        match self {
            Shader::Phong => "phong",
            Shader::Albedo => "albedo",
            Shader::Normal => "normal",
            Shader::Depth => "depth",
            Shader::Mask => "mask",
            Shader::Toon => "toon",
            Shader::Contour => "contour",
            Shader::AmbientOcclusion => "ao",
        }
    }

    /// Parses a [`Shader::name`] (also accepts `ambient-occlusion`).
    pub fn parse(s: &str) -> Option<Shader> {
        let s = s.to_ascii_lowercase();
        Shader::ALL.into_iter().find(|sh| sh.name() == s).or((s == "ambient-occlusion").then_some(Shader::AmbientOcclusion))
    }

    fn mode(self) -> u32 {
        Shader::ALL.iter().position(|&s| s == self).unwrap() as u32
    }
}

/// Quality settings; the defaults suit ground truth at the paper's resolutions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Sub-pixels per axis averaged into each pixel (1 = one ray through the pixel centre).
    pub supersample: u32,
    /// March step in voxels (the bisection then refines the crossing to ~1/1000 of a step).
    pub step: f32,
    /// Ambient-occlusion rays: `ao_dirs_sqrt^2` stratified directions.
    pub ao_dirs_sqrt: u32,
    /// Ambient-occlusion ray length in object units (the unit cube is the grid).
    pub ao_radius: f32,
    /// Normals half a voxel (at least one pixel) apart that differ by more than this many
    /// degrees mark a crease line.
    pub crease_degrees: f32,
    /// A neighbour farther by more than this many pixel widths marks an occluding contour.
    pub depth_jump_pixels: f32,
    /// Suggestive contours: how much `n.v` must rise on both sides of a minimum
    /// ([`Options::suggestive_step_voxels`] away) for it to be drawn. Lower draws fainter bends
    /// and, below ~0.05, the voxel grid's ripples as specks; `f32::INFINITY` turns suggestive
    /// contours off.
    pub suggestive_bend: f32,
    /// Suggestive contours: the distance in voxels over which the slope of `n.v` is measured.
    /// Two voxels average out the ripples a voxel grid's normals keep at one voxel's period.
    pub suggestive_step_voxels: f32,
    /// Suggestive contours are drawn only where `n.v` is below this (surfaces turning away
    /// from the camera), as DeCarlo et al. fade them out where the surface faces the viewer.
    pub suggestive_max_cos: f32,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            supersample: 1,
            step: 0.5,
            ao_dirs_sqrt: 8,
            ao_radius: 0.2,
            crease_degrees: 30.0,
            depth_jump_pixels: 4.0,
            suggestive_bend: 0.1,
            suggestive_step_voxels: 2.0,
            suggestive_max_cos: 0.8,
        }
    }
}

/// A grid uploaded to the GPU, reusable across many views.
pub struct GpuGrid {
    dims: [usize; 3],
    occupancy: Tensor,
    colour: Option<Tensor>,
}

impl GpuGrid {
    /// Uploads occupancy `[D, H, W]` and, when present, colour `[3, D, H, W]`.
    pub fn upload(gpu: &Gpu, grid: &VoxelGrid) -> Result<GpuGrid> {
        let dims = grid.dims();
        let occupancy = Tensor::from_slice(gpu, &dims, grid.occupancy())?;
        let colour = match grid.colour() {
            Some(c) => Some(Tensor::from_slice(gpu, &[3, dims[0], dims[1], dims[2]], c)?),
            None => None,
        };
        Ok(GpuGrid { dims, occupancy, colour })
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MarchParams {
    dims: [u32; 3],
    size: u32,
    has_colour: u32,
    want_ao: u32,
    ao_dirs_sqrt: u32,
    ao_steps: u32,
    r: [f32; 9],
    fov: f32,
    unit: f32,
    step: f32,
    ao_radius: f32,
    cu0: f32,
    cv0: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadeParams {
    size: u32,
    ss: u32,
    mode: u32,
    channels: u32,
    light: [f32; 3],
    ambient: f32,
    colour: [f32; 3],
    kd: f32,
    ks: f32,
    shininess: f32,
    depth_jump: f32,
    crease_cos: f32,
    crease_step: i32,
    sc_step: f32,
    sc_half: f32,
    sc_min_bend: f32,
    sc_max_cos: f32,
}

/// A square part of a larger image of the same view: outputs of side `S` hold the pixels
/// `[y0, y0 + S) x [x0, x0 + S)` of the `frame x frame` image ([`RayMarcher::record_part`]).
/// The part may run past the frame's edge; rays there are marched like any other. What a
/// caller that reads only a window of the image draws instead of the whole frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    /// Side of the whole image, pixels.
    pub frame: u32,
    /// Column of the part's first pixel in the whole image.
    pub x0: u32,
    /// Row of the part's first pixel in the whole image.
    pub y0: u32,
}

/// The reference (conventional, not learned) renderer: marches rays through the grid's
/// 0.5 iso-surface and shades the hits. Holds only settings; pipelines live in the
/// [`Gpu`]'s cache. The learned renderer is [`crate::nn::render::Renderer`].
#[derive(Clone, Debug, Default)]
pub struct RayMarcher {
    /// Quality settings used by every render.
    pub options: Options,
}

impl RayMarcher {
    /// A renderer with default [`Options`] (one ray per pixel).
    pub fn new(_gpu: &Gpu) -> RayMarcher {
        RayMarcher { options: Options::default() }
    }

    /// The same renderer with other options.
    pub fn with_options(mut self, options: Options) -> RayMarcher {
        self.options = options;
        self
    }

    /// Renders `grid` as `size x size` pixels: uploads it, records both passes into one
    /// submit and reads the image back.
    pub fn render(&self, gpu: &Gpu, grid: &VoxelGrid, view: &View, light: &Light, shader: Shader, size: u32) -> Result<Image> {
        Ok(self.render_many(gpu, grid, view, light, &[shader], size)?.remove(0))
    }

    /// Like [`RayMarcher::render`] for several shaders of one view: one upload, one march
    /// ([`RayMarcher::record_many`]) and one submit; the images in the order of `shaders`.
    pub fn render_many(&self, gpu: &Gpu, grid: &VoxelGrid, view: &View, light: &Light, shaders: &[Shader], size: u32) -> Result<Vec<Image>> {
        if size == 0 {
            return Err(Error::Invalid("reference::render: image size must be at least 1".into()));
        }
        let g = GpuGrid::upload(gpu, grid)?;
        let outs: Vec<Tensor> = shaders.iter().map(|s| Tensor::zeros(gpu, &[s.channels(), size as usize, size as usize])).collect::<Result<_>>()?;
        let pairs: Vec<(Shader, &Tensor)> = shaders.iter().copied().zip(&outs).collect();
        gpu.run(|pass| self.record_many(gpu, pass, &g, view, light, &pairs))?;
        shaders.iter().zip(&outs).map(|(s, out)| Ok(Image { channels: s.channels(), size: size as usize, data: out.to_vec(gpu)? })).collect()
    }

    /// Records a render into `pass`, writing `out` (`[C, S, S]`, `C` = [`Shader::channels`]),
    /// so a dataset generator can batch many views into one submit.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        grid: &GpuGrid,
        view: &View,
        light: &Light,
        shader: Shader,
        out: &Tensor,
    ) -> Result<()> {
        self.record_many(gpu, pass, grid, view, light, &[(shader, out)])
    }

    /// Like [`RayMarcher::record_part`] for the whole image.
    pub fn record_many(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        grid: &GpuGrid,
        view: &View,
        light: &Light,
        outs: &[(Shader, &Tensor)],
    ) -> Result<()> {
        self.record_part(gpu, pass, grid, view, light, outs, None)
    }

    /// Records the march alone: writes the G-buffer `gbuf` (`[GBUF_CHANNELS, N, N]`, `N` =
    /// the image side times [`Options::supersample`]) of `part` of the image (the whole image
    /// without), unshaded: channel 0 the mask (1 hit, 0 miss), 1 the camera-frame depth of the
    /// hit, 2..=4 the camera-frame unit normal, 5..=7 the albedo, 8 the ambient occlusion
    /// (only with `want_ao`). At one sample per pixel these are the Normal (decoded), Albedo
    /// and Mask images without the shading pass: what a caller that shades on the CPU reads.
    #[allow(clippy::too_many_arguments)]
    pub fn record_gbuffer(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        grid: &GpuGrid,
        view: &View,
        part: Option<Part>,
        want_ao: bool,
        gbuf: &Tensor,
    ) -> Result<()> {
        let op = "reference::render";
        self.check_options(op)?;
        view.validate().map_err(|m| Error::Invalid(format!("{op}: view: {m}")))?;
        let o = &self.options;
        let shape = gbuf.shape();
        if shape.len() != 3 || shape[0] != GBUF_CHANNELS || shape[1] != shape[2] || shape[1] == 0 || shape[1] % o.supersample as usize != 0 {
            return Err(crate::error::shape_err(op, format!("G-buffer has shape {shape:?}, expected [{GBUF_CHANNELS}, N, N] with N a positive multiple of the supersampling {}", o.supersample)));
        }
        let n = shape[1] as u32;
        let size = n / o.supersample;
        let part = part.unwrap_or(Part { frame: size, x0: 0, y0: 0 });
        if !(1..=MAX_FRAME).contains(&part.frame) || part.x0 >= part.frame || part.y0 >= part.frame {
            return Err(Error::Invalid(format!("{op}: part {part:?} must start inside a frame of 1..={MAX_FRAME} pixels")));
        }
        let unit = *grid.dims.iter().max().unwrap() as f32;
        // The part's centre on the camera plane and its width, object units (f64, so that
        // the whole image gets exactly 0 and `fov`).
        let frac = |p0: u32| (p0 as f64 + 0.5 * size as f64) / part.frame as f64 - 0.5;
        let part_fov = view.fov() * size as f64 / part.frame as f64;
        let r = view.rotation().transpose().to_cols_array(); // rows of R, row-major
        let mp = MarchParams {
            dims: grid.dims.map(|d| d as u32),
            size: n,
            has_colour: grid.colour.is_some() as u32,
            want_ao: want_ao as u32,
            ao_dirs_sqrt: o.ao_dirs_sqrt,
            ao_steps: 8,
            r,
            fov: part_fov as f32,
            unit,
            step: o.step,
            ao_radius: o.ao_radius * unit,
            cu0: (frac(part.x0) * view.fov()) as f32,
            cv0: (-frac(part.y0) * view.fov()) as f32,
        };
        let colour = grid.colour.as_ref().map(Arg::R).unwrap_or(Arg::Absent);
        let wg = [n.div_ceil(8), n.div_ceil(8), 1];
        gpu.dispatch(pass, MARCH, "reference_march", &mp, &[Arg::R(&grid.occupancy), colour, Arg::W(gbuf)], wg)
    }

    /// The options, or an error naming the one out of range.
    fn check_options(&self, op: &str) -> Result<()> {
        let o = &self.options;
        let step_ok = o.step > 0.0 && o.step <= 2.0;
        let sc_ok = o.suggestive_bend >= 0.0 && !o.suggestive_max_cos.is_nan() && o.suggestive_step_voxels > 0.0 && o.suggestive_step_voxels <= 8.0;
        if !(1..=8).contains(&o.supersample) || !step_ok || o.ao_dirs_sqrt == 0 || !o.ao_radius.is_finite() || !sc_ok {
            return Err(Error::Invalid(format!(
                "{op}: options {o:?} out of range (supersample 1..=8, step in (0, 2], ao_dirs_sqrt >= 1, suggestive_bend >= 0, suggestive_step_voxels in (0, 8])"
            )));
        }
        Ok(())
    }

    /// Like [`RayMarcher::record`] for several shaders of one view: the G-buffer is marched once
    /// and shaded per output, so e.g. Phong, normal, albedo and mask cost one march, not four.
    /// Every output must have the same size `S`. With `part`, the outputs are that part of
    /// the whole image (pixels as the whole image's, bit for bit up to f32 rounding of the
    /// ray origins); the line shaders (contour, toon) treat the part's edge as the image's.
    #[allow(clippy::too_many_arguments)]
    pub fn record_part(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        grid: &GpuGrid,
        view: &View,
        light: &Light,
        outs: &[(Shader, &Tensor)],
        part: Option<Part>,
    ) -> Result<()> {
        let op = "reference::render";
        let Some(&(_, first)) = outs.first() else {
            return Err(Error::Invalid(format!("{op}: no outputs requested")));
        };
        let size = first.shape().get(1).copied().unwrap_or(0);
        for &(shader, out) in outs {
            let shape = out.shape();
            if shape.len() != 3 || shape[0] != shader.channels() || shape[1] != size || shape[2] != size {
                return Err(crate::error::shape_err(
                    op,
                    format!("out has shape {shape:?}, expected [{}, {size}, {size}] for {:?}", shader.channels(), shader),
                ));
            }
        }
        light.validate().map_err(|m| Error::Invalid(format!("{op}: light: {m}")))?;
        self.check_options(op)?;
        let o = &self.options;
        let size = size as u32;
        let part = part.unwrap_or(Part { frame: size, x0: 0, y0: 0 });
        let n = size * o.supersample;
        let gbuf = Tensor::zeros(gpu, &[GBUF_CHANNELS, n as usize, n as usize])?;
        let want_ao = outs.iter().any(|&(s, _)| s == Shader::AmbientOcclusion);
        self.record_gbuffer(gpu, pass, grid, view, Some(part), want_ao, &gbuf)?;
        // The whole image's sub-pixel count (the part checked): what line widths and creases
        // are measured in.
        let frame_n = part.frame * o.supersample;
        let unit = *grid.dims.iter().max().unwrap() as f32;
        let fov = view.fov() as f32;
        let l = light.direction();
        // Half a voxel's width in sub-pixels (at least one output pixel): wider spacing would
        // let thin parts (one-voxel legs) compare their two sides.
        let crease_step = ((0.5 * frame_n as f32 / (fov * unit)).round() as i32).max(o.supersample as i32);
        for &(shader, out) in outs {
            let sp = ShadeParams {
                size,
                ss: o.supersample,
                mode: shader.mode(),
                channels: shader.channels() as u32,
                light: l.to_array(),
                ambient: light.ambient,
                colour: light.colour,
                kd: light.kd,
                ks: light.ks,
                shininess: light.shininess,
                depth_jump: o.depth_jump_pixels * fov / part.frame as f32,
                crease_cos: o.crease_degrees.to_radians().cos(),
                crease_step,
                sc_step: (o.suggestive_step_voxels * frame_n as f32 / (fov * unit)).max(o.supersample as f32),
                sc_half: 0.5 * o.supersample as f32,
                sc_min_bend: o.suggestive_bend,
                sc_max_cos: o.suggestive_max_cos,

            };
            let wg = [size.div_ceil(8), size.div_ceil(8), 1];
            gpu.dispatch(pass, SHADE, "reference_shade", &sp, &[Arg::R(&gbuf), Arg::W(out)], wg)?;
        }
        Ok(())
    }
}
