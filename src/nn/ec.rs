//! The paper's baselines EC and EC-deep (Section 4.2, appendix "Alternative architecture"):
//! a 3D conv encoder maps the grid in its canonical pose to a latent shape vector (sigmoid),
//! pose and light are concatenated to it (EC-deep first maps each through a fully-connected
//! layer), fully-connected layers map the result to a small 2D feature map, and a decoder of
//! stride-2 transposed convs, each followed by a plain conv (EC) or two 2D residual blocks
//! (EC-deep), draws the shaded image directly (sigmoid, BCE against the target, as the
//! paper). Unlike RenderNet it must learn the pose transform itself, and its fully-connected
//! layers see the whole frame, so it renders whole frames only (no camera-grid crops).
//!
//! Sizes are scaled to the 32^3 grids and 128 px images trained here (the paper: 64^3 grids,
//! channels 64-512, a 200-number code, 1024-wide layers, 512 px).

use super::rendernet::{Builder, Head, RenderNet};
use crate::error::{Error, Result};
use crate::graph::{Graph, Op, Value};
use crate::ops::conv::{Conv, Padding};
use crate::ops::loss::Loss;

/// Sizes of an EC / EC-deep network.
#[derive(Clone, Debug, PartialEq)]
pub struct EcSizes {
    /// Channels of the four 3D encoder convs (4^3 kernels, stride 2, as the paper).
    pub enc: [usize; 4],
    /// Length of the latent shape vector.
    pub latent: usize,
    /// EC-deep: pose and light each go through a fully-connected layer of this width before
    /// the concatenation. 0: EC, the raw numbers are concatenated.
    pub embed: usize,
    /// Width of the two fully-connected layers after the concatenation.
    pub fc: usize,
    /// Side of the 2D feature map the last fully-connected layer is reshaped into.
    pub start: usize,
    /// Channels of that map and of each stride-2 transposed conv after it; the image side is
    /// `start * 2^(len - 1)`.
    pub dec: Vec<usize>,
    /// EC-deep: each plain conv of the decoder is replaced by two 2D residual blocks.
    pub deep: bool,
}

impl EcSizes {
    /// Image side this decoder draws.
    pub fn image(&self) -> usize {
        self.start << (self.dec.len() - 1)
    }

    /// The rung trained here against RenderNet `tiny`: 32^3 grids, 128 px images.
    pub fn ec() -> EcSizes {
        EcSizes { enc: [8, 16, 32, 64], latent: 200, embed: 0, fc: 256, start: 8, dec: vec![32, 32, 32, 16, 16], deep: false }
    }

    /// [`EcSizes::ec`] with EC-deep's pose/light embeddings and residual decoder.
    pub fn ec_deep() -> EcSizes {
        EcSizes { embed: 128, deep: true, ..EcSizes::ec() }
    }
}

/// Pose features EC reads (`camera::pose_for_view`'s numbers with its two angles as sine and
/// cosine), so that views either side of azimuth 0 are near in input space as they are in
/// the image: a fully-connected layer cannot learn that wrap from a raw angle.
pub fn pose_features(pose: [f32; 6]) -> [f32; 6] {
    [pose[0], pose[1].sin(), pose[1].cos(), pose[2].sin(), pose[2].cos(), 1.0]
}

/// Builds EC or EC-deep for batch `n` into `g` on the canonical-pose grid `grid`
/// (`[N, 1, R, R, R]`, R = `input`). The returned [`RenderNet`] has no maps; its pose input
/// takes [`pose_features`]; its light input (Phong head only, `camera::light_values`) is
/// concatenated like the pose. The image has 3 channels for Phong (as RenderNet's) or the
/// image head's count. With `with_loss`, BCE(image, target) under the name "phong" or "image".
pub fn build_on(mut g: Graph, grid: Value, s: &EcSizes, input: usize, head: Head, with_loss: bool) -> Result<RenderNet> {
    if input % 16 != 0 || s.dec.is_empty() || s.start == 0 {
        return Err(Error::Invalid(format!("EC needs a grid side that is a multiple of 16 (got {input}) and a decoder")));
    }
    let n = g.info(grid).shape[0];
    let mut b = Builder { g: &mut g };
    let mut x = grid;
    for (i, &c) in s.enc.iter().enumerate() {
        x = b.conv(&format!("enc3d.conv{i}"), x, c, Conv::conv3d([4; 3], [2; 3], Padding::Same))?;
        x = b.prelu(&format!("enc3d.act{i}"), x)?;
    }
    let flat = s.enc[3] * (input / 16).pow(3);
    x = b.g.apply("enc3d.flat", Op::Reshape(vec![n, flat, 1, 1]), &[x])?;
    x = b.dense("code.fc", x, s.latent)?;
    let code = b.g.apply("code", Op::Sigmoid, &[x])?;
    let pose = b.g.input("pose", &[n, 6])?;
    let light = match head {
        Head::Phong(_) => Some(b.g.input("light", &[n, 6])?),
        Head::Image(_) => None,
    };
    x = code;
    for (name, v) in [("pose", Some(pose)), ("light", light)] {
        let Some(v) = v else { continue };
        let mut v = b.g.apply(&format!("{name}.vec"), Op::Reshape(vec![n, 6, 1, 1]), &[v])?;
        if s.embed > 0 {
            v = b.dense(&format!("{name}.fc"), v, s.embed)?;
            v = b.prelu(&format!("{name}.act"), v)?;
        }
        x = b.g.apply(&format!("{name}.concat"), Op::Concat, &[x, v])?;
    }
    for i in 0..2 {
        x = b.dense(&format!("fc.{i}"), x, s.fc)?;
        x = b.prelu(&format!("fc.{i}.act"), x)?;
    }
    x = b.dense("fc.2", x, s.dec[0] * s.start * s.start)?;
    x = b.prelu("fc.2.act", x)?;
    x = b.g.apply("fc.map", Op::Reshape(vec![n, s.dec[0], s.start, s.start]), &[x])?;
    let conv3 = Conv::conv2d([3, 3], [1, 1], Padding::Same);
    for (i, &c) in s.dec[1..].iter().enumerate() {
        // Named "up.*" so training keeps them resize-convolutions, as RenderNet's.
        x = b.up(&format!("up.{i}"), x, c)?;
        x = b.prelu(&format!("up.{i}.act"), x)?;
        if s.deep {
            for j in 0..2 {
                x = b.residual(&format!("dec.{i}.res{j}"), x, conv3.clone())?;
            }
        } else {
            // 3x3 where the paper has 4x4: 'same' padding of an even kernel shifts the image.
            x = b.conv(&format!("dec.{i}.conv"), x, c, conv3.clone())?;
            x = b.prelu(&format!("dec.{i}.act"), x)?;
        }
    }
    let (c, target) = match head {
        Head::Phong(_) => (3, "phong"),
        Head::Image(c) => (c, "image"),
    };
    let image = b.head("head.image", x, c)?;
    let mut targets = Vec::new();
    let mut loss = None;
    if with_loss {
        let side = s.image();
        let t = g.input(&format!("target.{target}"), &[n, c, side, side])?;
        targets.push((target.to_string(), t));
        loss = Some(g.apply("loss", Op::Loss(Loss::Bce), &[image, t])?);
    }
    Ok(RenderNet { graph: g, grid, pose, light, image, maps: None, targets, loss })
}
