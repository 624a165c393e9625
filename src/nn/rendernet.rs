//! RenderNet (paper Section 3 and appendix) as a graph: pose resampling into a camera grid,
//! 3D convolutions, 3D residual blocks, the projection unit, 2D residual blocks, transposed
//! convolutions up to the image, and sigmoid heads. The Phong head predicts normal, albedo
//! and mask maps and shades them with the input light (Section 3.3); other shaders use a
//! direct image head. Widths, depths and sizes come from a [`Preset`].

use crate::error::{Error, Result};
use crate::graph::{Graph, Init, Op, Value};
use crate::ops::conv::{Conv, Padding};
use crate::ops::conv_transpose::ConvTranspose;
use crate::ops::loss::Loss;
use crate::ops::phong::Phong;
use crate::reference::Light;
pub use super::ec::EcSizes;

/// The largest input grid side a preset may read (`train --input`, weights' `input`): the
/// paper's 64^3 twice over; beyond it the resampling only aliases a 64^3 or 128^3 camera grid.
pub const MAX_INPUT: usize = 128;

/// Sizes of a RenderNet.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// Name used on the command line and in weight files.
    pub name: &'static str,
    /// Side of the input voxel grid (grids are resampled to it).
    pub input: usize,
    /// Side of the camera-aligned grid the input is resampled into (depth = height = width).
    pub cam: usize,
    /// Channels of the two 3D convs: a 5^3 stride-2 conv, then a 3^3 conv halving depth only.
    pub c3: [usize; 2],
    /// 3D residual blocks after them.
    pub res3d: usize,
    /// Output channels of the projection unit.
    pub proj: usize,
    /// Channels of the 2D trunk.
    pub c2: usize,
    /// 2D residual blocks.
    pub res2d: usize,
    /// Channels of each stride-2 transposed 4x4 conv; the image side is `cam/2 * 2^len`.
    pub up: Vec<usize>,
    /// RenderNet, or one of the paper's encoder-decoder baselines (which ignore the fields
    /// above but `input` and `cam`).
    pub arch: Arch,
    /// Coloured voxels: the input grid has 4 channels (occupancy, then RGB times occupancy)
    /// and the Phong albedo head predicts RGB ([`Preset::with_colour`]).
    pub colour: bool,
}

/// The network family of a [`Preset`].
#[derive(Clone, Debug, PartialEq)]
pub enum Arch {
    /// RenderNet: pose resampling, 3D convs, projection unit, 2D convs (fully convolutional
    /// in the image plane, so it renders camera-grid crops).
    RenderNet,
    /// EC or EC-deep (`nn::ec`): canonical grid to a latent vector, fully-connected layers,
    /// a 2D decoder; whole frames only.
    Ec(EcSizes),
}

impl Preset {
    /// The small preset that trains on a 2-core CPU through lavapipe: 32^3 input, 64^3
    /// camera grid, 128x128 image.
    pub fn tiny() -> Preset {
        Preset { name: "tiny", input: 32, cam: 64, c3: [8, 16], res3d: 0, proj: 64, c2: 32, res2d: 2, up: vec![32, 16], arch: Arch::RenderNet, colour: false }
    }

    /// The rung below [`Preset::tiny`] on the speed/accuracy ladder: the same grids and image,
    /// half the channels everywhere and one 2D residual block (about a quarter of the work).
    pub fn nano() -> Preset {
        Preset { name: "nano", input: 32, cam: 64, c3: [4, 8], res3d: 0, proj: 32, c2: 16, res2d: 1, up: vec![16, 8], arch: Arch::RenderNet, colour: false }
    }

    /// The rung above [`Preset::tiny`]: the same grids and image, a 2D trunk twice as wide
    /// (64 channels, projection 256->128) with 3 residual blocks, for sharper shading.
    pub fn small() -> Preset {
        Preset { name: "small", input: 32, cam: 64, c3: [8, 16], res3d: 0, proj: 128, c2: 64, res2d: 3, up: vec![32, 16], arch: Arch::RenderNet, colour: false }
    }

    /// The rung between [`Preset::small`] and [`Preset::paper`]: wider 3D convs (16/32) with
    /// one 3D residual block, a 128-channel 2D trunk with 4 residual blocks.
    pub fn base() -> Preset {
        Preset { name: "base", input: 32, cam: 64, c3: [16, 32], res3d: 1, proj: 128, c2: 128, res2d: 4, up: vec![64, 32], arch: Arch::RenderNet, colour: false }
    }

    /// The paper's appendix sizes (64^3 input into a 128^3 grid, 512^2 image); for real GPUs.
    pub fn paper() -> Preset {
        Preset {
            name: "paper",
            input: 64,
            cam: 128,
            c3: [8, 16],
            res3d: 10,
            proj: 1024,
            c2: 1024,
            res2d: 10,
            up: vec![128, 64, 32],
            arch: Arch::RenderNet,
            colour: false,
        }
    }

    /// The paper's EC baseline at the size trained here (32^3 grid, 128 px; [`EcSizes::ec`]).
    pub fn ec() -> Preset {
        Preset { name: "ec", input: 32, cam: 64, c3: [0, 0], res3d: 0, proj: 0, c2: 0, res2d: 0, up: Vec::new(), arch: Arch::Ec(EcSizes::ec()), colour: false }
    }

    /// The paper's EC-deep baseline ([`EcSizes::ec_deep`]).
    pub fn ec_deep() -> Preset {
        Preset { name: "ec-deep", arch: Arch::Ec(EcSizes::ec_deep()), ..Preset::ec() }
    }

    /// The same sizes for coloured voxels (RenderNet only): RGB input channels and an RGB
    /// albedo head. The weights differ from the grey preset's in those two layers' shapes.
    pub fn with_colour(self) -> Preset {
        Preset { colour: true, ..self }
    }

    /// The same network reading its grid at `input`^3 (every grid is resampled to it before
    /// the camera resampling): 32 for the shipped presets' defaults, 64 as the paper. The
    /// weights do not depend on it (every conv runs on the camera grid), so weights trained
    /// at one input side load at any other; `train --input` records the side they were
    /// trained at in their metadata (`input`), and [`Preset::for_weights`] reads it back.
    pub fn with_input(self, input: usize) -> Preset {
        Preset { input, ..self }
    }

    /// This preset as `weights` (safetensors bytes; `name` labels them in errors) were trained:
    /// coloured if their first conv takes RGB ([`crate::nn::render::weights_take_colour`]),
    /// and reading grids at the side their metadata records (`input`, written by `train`;
    /// weights without it keep the preset's). A malformed `input` is an error naming `name`.
    pub fn for_weights(self, weights: &[u8], name: &str) -> Result<Preset> {
        let p = if crate::nn::render::weights_take_colour(weights, name)? && self.fully_convolutional() { self.with_colour() } else { self };
        let (_, meta) = safetensors::SafeTensors::read_metadata(weights).map_err(|e| Error::Invalid(format!("{name}: not a safetensors file: {e}")))?;
        let Some(v) = meta.metadata().as_ref().and_then(|m| m.get("input").cloned()) else { return Ok(p) };
        match v.parse::<usize>() {
            Ok(r) if (2..=MAX_INPUT).contains(&r) => Ok(p.with_input(r)),
            _ => Err(Error::Invalid(format!("{name}: metadata 'input' is '{v}'; expected a grid side from 2 to {MAX_INPUT}"))),
        }
    }

    /// Channels of the input grid: 4 with colour (occupancy, RGB times occupancy), else 1.
    pub fn in_channels(&self) -> usize {
        if self.colour { 4 } else { 1 }
    }

    /// Channels of the Phong head's albedo map: 3 with colour, else 1 (grey).
    pub fn albedo_channels(&self) -> usize {
        if self.colour { 3 } else { 1 }
    }

    /// Whether the network renders camera-grid windows (RenderNet) or only whole frames
    /// (the EC baselines, whose fully-connected layers see the whole frame).
    pub fn fully_convolutional(&self) -> bool {
        self.arch == Arch::RenderNet
    }

    /// The numbers fed to the pose input for `view` on a `cam_hw` camera grid, cropped to
    /// `crop` (RenderNet only): `camera::pose_for_view`, or its EC features.
    pub fn pose_values(&self, view: &crate::reference::View, cam_hw: usize, crop: Option<[usize; 4]>) -> [f32; 6] {
        let pose = crate::nn::camera::pose_for_view(view, self.input, cam_hw, crop);
        match self.arch {
            Arch::RenderNet => pose,
            Arch::Ec(_) => super::ec::pose_features(pose),
        }
    }

    /// Looks a preset up by name.
    pub fn by_name(name: &str) -> Result<Preset> {
        match name {
            "nano" => Ok(Self::nano()),
            "tiny" => Ok(Self::tiny()),
            "small" => Ok(Self::small()),
            "base" => Ok(Self::base()),
            "paper" => Ok(Self::paper()),
            "ec" => Ok(Self::ec()),
            "ec-deep" => Ok(Self::ec_deep()),
            _ => Err(Error::Invalid(format!("unknown preset '{name}'; expected nano, tiny, small, base, paper, ec or ec-deep"))),
        }
    }

    /// Image side for a camera grid of side `cam_hw`.
    pub fn image_for(&self, cam_hw: usize) -> usize {
        match &self.arch {
            Arch::RenderNet => cam_hw / 2 * (1 << self.up.len()),
            Arch::Ec(s) => cam_hw * s.image() / self.cam,
        }
    }

    /// Depth of the camera grid after the two 3D convs (stride 2, then depth stride 2).
    fn depth_after(&self) -> usize {
        self.cam.div_ceil(2).div_ceil(2)
    }
}

/// What the network renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Head {
    /// Normal, albedo and mask maps shaded by the Phong op with the input light.
    Phong(Phong),
    /// One image with this many channels (toon, contour: 1; AO: 1).
    Image(usize),
}

/// The Phong constants the reference renderer uses for `light`, for the Phong head.
pub fn phong_of(light: &Light) -> Phong {
    Phong { ambient: light.ambient, kd: light.kd, ks: light.ks, shininess: light.shininess }
}

/// A built network and the values a caller feeds and reads.
pub struct RenderNet {
    /// The graph (hand it to an `Executor`).
    pub graph: Graph,
    /// Input grid `[N, C, R, R, R]` (C: [`Preset::in_channels`]; axes as
    /// `camera::input_values`).
    pub grid: Value,
    /// Pose `[N, 6]` (`camera::pose_for_view`).
    pub pose: Value,
    /// Light `[N, 6]` (`camera::light_values`); Phong head only.
    pub light: Option<Value>,
    /// The rendered image `[N, 3 or C, S, S]`.
    pub image: Value,
    /// Normal, albedo and mask maps (Phong head only).
    pub maps: Option<[Value; 3]>,
    /// Training targets and the loss, when built with `with_loss`.
    pub targets: Vec<(String, Value)>,
    /// The scalar loss.
    pub loss: Option<Value>,
}

/// Adds named layers (weights and biases as parameters) to a graph; shared by the models.
pub(crate) struct Builder<'a> {
    pub(crate) g: &'a mut Graph,
}

impl Builder<'_> {
    pub(crate) fn param(&mut self, name: &str, shape: &[usize], init: Init) -> Result<Value> {
        self.g.param(name, shape, init)
    }

    pub(crate) fn conv(&mut self, name: &str, x: Value, cout: usize, conv: Conv) -> Result<Value> {
        let (w, b) = self.conv_params(name, x, cout, &conv)?;
        self.g.apply(name, Op::Conv(conv), &[x, w, b])
    }

    /// The weight (Xavier) and bias of conv `name` from `x` to `cout` channels.
    fn conv_params(&mut self, name: &str, x: Value, cout: usize, conv: &Conv) -> Result<(Value, Value)> {
        let cin = self.g.info(x).shape[1];
        let mut wshape = vec![cout, cin];
        let rank = self.g.info(x).shape.len();
        wshape.extend(&conv.kernel[5 - rank..]);
        let w = self.param(&format!("{name}.weight"), &wshape, Init::Xavier)?;
        let b = self.param(&format!("{name}.bias"), &[cout], Init::Constant(0.001))?;
        Ok((w, b))
    }

    /// The Phong heads (normal 3, albedo `ca`, mask 1 channels, 3x3 convs from `x`) as one conv
    /// over their concatenated weights: `x` is read and packed once and each tile computes
    /// all their channels (on lavapipe about half the time of three convs, README
    /// "Benchmarks"). Parameters and node names stay the three heads' (`head.normal` ...: each
    /// head's logits, narrowed out of the joint output). `seen` is added to the albedo's
    /// logits (coloured models). Returns the normal, albedo and mask maps.
    fn phong_heads(&mut self, x: Value, ca: usize, seen: impl FnOnce(&mut Self) -> Result<Option<Value>>) -> Result<[Value; 3]> {
        let conv = Conv::conv2d([3, 3], [1, 1], Padding::Same);
        let (wn, bn) = self.conv_params("head.normal", x, 3, &conv)?;
        // Built between the heads' parameters so parameters keep their order (their initial
        // values are seeded by value index, which the joint conv shifted for the albedo and
        // mask heads: a fresh training run starts them from other draws than before it).
        let seen = seen(self)?;
        let (wa, ba) = self.conv_params("head.albedo", x, ca, &conv)?;
        let (wm, bm) = self.conv_params("head.mask", x, 1, &conv)?;
        let sizes = vec![3, ca, 1];
        let w = self.g.apply("head.weight", Op::ConcatAxis0(sizes.clone()), &[wn, wa, wm])?;
        let b = self.g.apply("head.bias", Op::ConcatAxis0(sizes), &[bn, ba, bm])?;
        let h = self.g.apply("head", Op::Conv(conv), &[x, w, b])?;
        let normal = self.g.apply("head.normal", Op::Narrow(0, 3), &[h])?;
        let normal = self.g.apply("head.normal.sigmoid", Op::Sigmoid, &[normal])?;
        let mut albedo = self.g.apply("head.albedo", Op::Narrow(3, ca), &[h])?;
        if let Some(seen) = seen {
            albedo = self.g.apply("head.albedo.seen", Op::Add, &[albedo, seen])?;
        }
        let albedo = self.g.apply("head.albedo.sigmoid", Op::Sigmoid, &[albedo])?;
        let mask = self.g.apply("head.mask", Op::Narrow(3 + ca, 1), &[h])?;
        let mask = self.g.apply("head.mask.sigmoid", Op::Sigmoid, &[mask])?;
        Ok([normal, albedo, mask])
    }

    /// A transposed conv `t` with PyTorch's `[Cin, Cout, k...]` weights (Xavier).
    pub(crate) fn conv_transpose(&mut self, name: &str, x: Value, cout: usize, t: ConvTranspose) -> Result<Value> {
        let cin = self.g.info(x).shape[1];
        let rank = self.g.info(x).shape.len();
        let mut wshape = vec![cin, cout];
        wshape.extend(&t.conv.kernel[5 - rank..]);
        let w = self.param(&format!("{name}.weight"), &wshape, Init::Xavier)?;
        let b = self.param(&format!("{name}.bias"), &[cout], Init::Constant(0.001))?;
        self.g.apply(name, Op::ConvTranspose(t), &[x, w, b])
    }

    /// A fully-connected layer on `[N, K, 1, 1]`: the projection op with weights `[O, K, 1, 1]`
    /// (PyTorch's Linear `[O, K]` with two unit axes).
    pub(crate) fn dense(&mut self, name: &str, x: Value, out: usize) -> Result<Value> {
        self.dense_init(name, x, out, Init::Xavier, 0.001)
    }

    /// [`Builder::dense`] with the weights started by `init` and the bias at `bias`.
    pub(crate) fn dense_init(&mut self, name: &str, x: Value, out: usize, init: Init, bias: f32) -> Result<Value> {
        let k = self.g.info(x).shape[1];
        let w = self.param(&format!("{name}.weight"), &[out, k, 1, 1], init)?;
        let b = self.param(&format!("{name}.bias"), &[out], Init::Constant(bias))?;
        self.g.apply(name, Op::Projection, &[x, w, b])
    }

    pub(crate) fn up(&mut self, name: &str, x: Value, cout: usize) -> Result<Value> {
        let cin = self.g.info(x).shape[1];
        let w = self.param(&format!("{name}.weight"), &[cin, cout, 4, 4], Init::XavierUpsample)?;
        let b = self.param(&format!("{name}.bias"), &[cout], Init::Constant(0.001))?;
        let t = ConvTranspose::conv2d([4, 4], [2, 2], Padding::Same);
        self.g.apply(name, Op::ConvTranspose(t), &[x, w, b])
    }

    pub(crate) fn prelu(&mut self, name: &str, x: Value) -> Result<Value> {
        let c = self.g.info(x).shape[1];
        let a = self.param(&format!("{name}.alpha"), &[c], Init::Constant(0.0))?;
        self.g.apply(name, Op::Prelu, &[x, a])
    }

    /// conv - PReLU - conv + identity, the paper's residual block (3^3 or 3x3).
    pub(crate) fn residual(&mut self, name: &str, x: Value, conv: Conv) -> Result<Value> {
        let c = self.g.info(x).shape[1];
        let h = self.conv(&format!("{name}.conv1"), x, c, conv.clone())?;
        let h = self.prelu(&format!("{name}.act"), h)?;
        let h = self.conv(&format!("{name}.conv2"), h, c, conv)?;
        self.g.apply(&format!("{name}.add"), Op::Add, &[h, x])
    }

    /// A coloured network's colour path: the camera grid composited front to back along
    /// depth (`Op::Composite`: coverage and the RGB seen through each column), brought to the
    /// image's size (`2^(ups-1)` times the camera grid's) by `ups - 1` stride-2 4x4 transposed
    /// convs to 3 channels (one 3x3 conv when `ups` is 1), the last one starting at zero so a
    /// network widened from grey weights renders exactly as they do (`colour.up.{i}.weight` /
    /// `.bias`).
    pub(crate) fn colour_seen(&mut self, camera_grid: Value, ups: usize) -> Result<Value> {
        let mut x = self.g.apply("colour.composite", Op::Composite, &[camera_grid])?;
        let steps = ups.saturating_sub(1).max(1);
        for i in 0..steps {
            let (name, cin, last) = (format!("colour.up.{i}"), self.g.info(x).shape[1], i + 1 == steps);
            // Only the last layer starts at zero: a zero layer before it would pass no gradient.
            let init = if last { Init::Constant(0.0) } else { Init::XavierUpsample };
            let (shape, op) = if ups == 1 {
                ([3, cin, 3, 3], Op::Conv(Conv::conv2d([3, 3], [1, 1], Padding::Same)))
            } else {
                ([cin, 3, 4, 4], Op::ConvTranspose(ConvTranspose::conv2d([4, 4], [2, 2], Padding::Same)))
            };
            let w = self.param(&format!("{name}.weight"), &shape, init)?;
            let b = self.param(&format!("{name}.bias"), &[3], Init::Constant(0.0))?;
            x = self.g.apply(&name, op, &[x, w, b])?;
            if !last {
                x = self.prelu(&format!("{name}.act"), x)?;
            }
        }
        Ok(x)
    }

    pub(crate) fn head(&mut self, name: &str, x: Value, c: usize) -> Result<Value> {
        let h = self.conv(name, x, c, Conv::conv2d([3, 3], [1, 1], Padding::Same))?;
        self.g.apply(&format!("{name}.sigmoid"), Op::Sigmoid, &[h])
    }
}

impl RenderNet {
    /// Builds the network for batch `n` on a camera-grid window of `cam_hw` = `[H, W]`
    /// (the full `[cam, cam]` to render, smaller windows for patch training; depth is always
    /// whole). With `with_loss`, adds target inputs and the training loss: for Phong,
    /// MSE(image) + MSE(normal map) + MSE(albedo map) + BCE(mask); for an image head, BCE (greyscale).
    pub fn build(p: &Preset, head: Head, n: usize, cam_hw: [usize; 2], with_loss: bool) -> Result<RenderNet> {
        let mut g = Graph::new();
        let r = p.input;
        let grid = g.input("grid", &[n, p.in_channels(), r, r, r])?;
        Self::build_on(g, grid, p, head, cam_hw, with_loss)
    }

    /// [`RenderNet::build`] on a graph that already computes the input grid `grid`
    /// (`[N, C, R, R, R]`, R the preset's input side, C its [`Preset::in_channels`]), e.g. a shape decoder's output, so
    /// gradients reach what made the grid.
    pub fn build_on(mut g: Graph, grid: Value, p: &Preset, head: Head, cam_hw: [usize; 2], with_loss: bool) -> Result<RenderNet> {
        if cam_hw.iter().any(|&s| s % 4 != 0 || s == 0) {
            return Err(Error::Invalid(format!("camera window {cam_hw:?}: sides must be positive multiples of 4")));
        }
        let r = p.input;
        let n = g.info(grid).shape[0];
        let c = p.in_channels();
        if g.info(grid).shape != [n, c, r, r, r] {
            return Err(Error::Invalid(format!("grid {:?}: preset '{}' needs [N, {c}, {r}, {r}, {r}]", g.info(grid).shape, p.name)));
        }
        if let Arch::Ec(s) = &p.arch {
            if p.colour {
                return Err(Error::Invalid(format!("preset '{}': the EC baselines take grey grids only (no colour)", p.name)));
            }
            if cam_hw != [p.cam, p.cam] {
                let side = s.image();
                return Err(Error::Invalid(format!("preset '{}' renders whole {side}x{side} frames only (camera window {cam_hw:?} asked)", p.name)));
            }
            return super::ec::build_on(g, grid, s, r, head, with_loss);
        }
        let mut b = Builder { g: &mut g };
        let pose = b.g.input("pose", &[n, 6])?;
        let camera_grid = b.g.apply("resample", Op::Resample([p.cam, cam_hw[0], cam_hw[1]]), &[grid, pose])?;
        let x = b.conv("enc3d.conv1", camera_grid, p.c3[0], Conv::conv3d([5, 5, 5], [2, 2, 2], Padding::Same))?;
        let x = b.prelu("enc3d.act1", x)?;
        let x = b.conv("enc3d.conv2", x, p.c3[1], Conv::conv3d([3, 3, 3], [2, 1, 1], Padding::Same))?;
        let mut x = b.prelu("enc3d.act2", x)?;
        for i in 0..p.res3d {
            x = b.residual(&format!("res3d.{i}"), x, Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same))?;
        }
        debug_assert_eq!(b.g.info(x).shape[2], p.depth_after());
        let k = p.c3[1] * p.depth_after();
        let w = b.param("proj.weight", &[p.proj, k, 1, 1], Init::Xavier)?;
        let bias = b.param("proj.bias", &[p.proj], Init::Constant(0.001))?;
        let x = b.g.apply("proj", Op::Projection, &[x, w, bias])?;
        let x = b.prelu("proj.act", x)?;
        let x = b.conv("enc2d.conv", x, p.c2, Conv::conv2d([3, 3], [1, 1], Padding::Same))?;
        let mut x = b.prelu("enc2d.act", x)?;
        for i in 0..p.res2d {
            x = b.residual(&format!("res2d.{i}"), x, Conv::conv2d([3, 3], [1, 1], Padding::Same))?;
        }
        for (i, &c) in p.up.iter().enumerate() {
            x = b.up(&format!("up.{i}"), x, c)?;
            x = b.prelu(&format!("up.{i}.act"), x)?;
        }
        let s = b.g.info(x).shape.clone();
        let (hh, ww) = (s[2], s[3]);
        let (image, maps, light) = match head {
            Head::Phong(ph) => {
                // Coloured: the visible colour, composited along the camera grid's depth, is
                // added to the albedo head's logits at the image's size.
                let ups = p.up.len();
                let seen = |b: &mut Builder| if p.colour { b.colour_seen(camera_grid, ups).map(Some) } else { Ok(None) };
                let [normal, albedo, mask] = b.phong_heads(x, p.albedo_channels(), seen)?;
                let light = b.g.input("light", &[n, 6])?;
                let img = b.g.apply("phong", Op::Phong(ph), &[normal, albedo, mask, light])?;
                (img, Some([normal, albedo, mask]), Some(light))
            }
            Head::Image(c) => (b.head("head.image", x, c)?, None, None),
        };
        let mut targets = Vec::new();
        let mut loss = None;
        if with_loss {
            let mut t = |g: &mut Graph, name: &str, c: usize| -> Result<Value> {
                let v = g.input(&format!("target.{name}"), &[n, c, hh, ww])?;
                targets.push((name.to_string(), v));
                Ok(v)
            };
            loss = Some(match (head, maps) {
                (Head::Phong(_), Some([normal, albedo, mask])) => {
                    let ti = t(&mut g, "phong", 3)?;
                    let tn = t(&mut g, "normal", 3)?;
                    let ta = t(&mut g, "albedo", p.albedo_channels())?;
                    let tm = t(&mut g, "mask", 1)?;
                    let li = g.apply("loss.phong", Op::Loss(Loss::Mse), &[image, ti])?;
                    let ln = g.apply("loss.normal", Op::Loss(Loss::Mse), &[normal, tn])?;
                    let la = g.apply("loss.albedo", Op::Loss(Loss::Mse), &[albedo, ta])?;
                    let lm = g.apply("loss.mask", Op::Loss(Loss::Bce), &[mask, tm])?;
                    let l = g.apply("loss.sum1", Op::Add, &[li, ln])?;
                    let l = g.apply("loss.sum2", Op::Add, &[l, la])?;
                    g.apply("loss", Op::Add, &[l, lm])?
                }
                _ => {
                    let c = g.info(image).shape[1];
                    let ti = t(&mut g, "image", c)?;
                    g.apply("loss", Op::Loss(Loss::Bce), &[image, ti])?
                }
            });
        }
        Ok(RenderNet { graph: g, grid, pose, light, image, maps, targets, loss })
    }
}
