//! The texture decoder (the paper's "texture code -> 3D texture grid", section 4.3): a code of
//! [`TEXTURE_CODE`] numbers decoded into an RGB grid over the whole object cube, which, times
//! the occupancy, is the colour a coloured RenderNet reads. Trained here on the procedural
//! paints of `dataset --colour` ([`Paint::from_code`]: two colours, plain / stripes /
//! checkerboard, period, axis), so inverse rendering can recover a texture code by gradient
//! descent through the decoder and the frozen renderer ([`decoder_with_renderer`]).

use super::prior::grid_decoder;
use super::rendernet::{Builder, Head, Preset, RenderNet};
use crate::error::{Error, Result};
use crate::graph::{Graph, Init, Op, Value};
use crate::ops::loss::Loss;
use crate::voxel::VoxelGrid;
use crate::voxel::shapes::{Paint, TEXTURE_CODE};

/// The shipped texture decoder ([`TexturePreset::small`], trained by `rendernet
/// train-texture`; weights/README.md has the command and log): what texture recovery uses
/// without a weights file.
pub static TEXTURE_SMALL_WEIGHTS: &[u8] = include_bytes!("../../weights/texture-small.safetensors");

/// Sizes of a texture decoder (the code length is [`TEXTURE_CODE`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TexturePreset {
    /// Name, for messages and files.
    pub name: &'static str,
    /// Grid side (a multiple of 8: the decoder starts at `res / 8`).
    pub res: usize,
    /// Channels of the starting grid and of the three stride-2 transposed convs.
    pub dec: [usize; 4],
}

impl TexturePreset {
    /// The size trained here: 32^3 textures, the shape prior's decoder widths.
    pub fn small() -> TexturePreset {
        TexturePreset { name: "texture-small", res: 32, dec: [32, 16, 8, 8] }
    }
}

/// A built texture decoder and the values a caller feeds and reads.
pub struct TextureDecoder {
    /// The graph.
    pub graph: Graph,
    /// The code `[N, TEXTURE_CODE, 1, 1]`, numbers in 0..1.
    pub code: Value,
    /// The decoded RGB texture `[N, 3, R, R, R]` in RenderNet's input layout.
    pub texture: Value,
    /// The target texture ([`texture_values`]) and MSE against it, when built with a loss.
    pub target: Option<Value>,
    /// MSE of `texture` against `target`.
    pub loss: Option<Value>,
}

impl TextureDecoder {
    /// The decoder for batch `n`; with `with_loss`, MSE against a fed target.
    pub fn build(p: &TexturePreset, n: usize, with_loss: bool) -> Result<TextureDecoder> {
        let mut g = Graph::new();
        let code = g.input("code", &[n, TEXTURE_CODE, 1, 1])?;
        let texture = texture_grid(&mut Builder { g: &mut g }, p, code)?;
        let (mut target, mut loss) = (None, None);
        if with_loss {
            let t = g.input("target.texture", &[n, 3, p.res, p.res, p.res])?;
            loss = Some(g.apply("loss", Op::Loss(Loss::Mse), &[texture, t])?);
            target = Some(t);
        }
        Ok(TextureDecoder { graph: g, code, texture, target, loss })
    }
}

/// The decoder on `code` (`[N, TEXTURE_CODE, 1, 1]`): `a + m * d`, an RGB grid `[N, 3, R, R, R]`
/// in RenderNet's input layout. `m` is a one-channel pattern mask in 0..1 decoded like the
/// shape prior's grid (`tex.fc`, `tex.up*`, `tex.out`); `a` and `d` are RGB colours read from
/// the code by fully-connected layers (`tex.colour_a`, `tex.colour_d`) and painted over the
/// whole grid, so they learn the paint's two colours (`a`, `b - a`) exactly. A decoder that
/// drew RGB directly through the transposed convs learned even plain colours slowly
/// (held-out texture PSNR 13.4 dB after 1200 steps; weights/README.md).
fn texture_grid(b: &mut Builder, p: &TexturePreset, code: Value) -> Result<Value> {
    let n = b.g.info(code).shape[0];
    let mask = grid_decoder(b, "tex", p.res, p.dec, 1, code, "texture.mask")?;
    let mut colour = |name: &str| -> Result<Value> {
        // Zero-initialised: Xavier weights start the colours ~0.7 off, which Adam at 1e-3
        // took hundreds of steps to undo; from zero the first steps fit the colours.
        let c = b.dense_init(name, code, 3, Init::Constant(0.0), 0.0)?;
        let c = b.g.apply(&format!("{name}.grid"), Op::Reshape(vec![n, 3, 1, 1, 1]), &[c])?;
        b.g.apply(&format!("{name}.painted"), Op::Expand(vec![p.res; 3]), &[c])
    };
    let (a, d) = (colour("tex.colour_a")?, colour("tex.colour_d")?);
    let pattern = b.g.apply("texture.pattern", Op::Mul, &[d, mask])?;
    b.g.apply("texture", Op::Add, &[a, pattern])
}

/// The texture `paint` draws over the whole cube, `[3, R, R, R]` in RenderNet's input
/// layout (the decoder's target).
pub fn texture_values(paint: &Paint, res: usize) -> Result<Vec<f32>> {
    let cells = res * res * res;
    let full = VoxelGrid::new([res; 3], vec![1.0; cells]).and_then(|g| g.with_colour(paint.field(res))).map_err(|e| Error::Invalid(e.to_string()))?;
    // Channel 0 of a coloured input is the occupancy (all ones here); 1..4 are the RGB.
    Ok(super::camera::input_values_with(&full, 4).split_off(cells))
}

/// The texture decoder in front of a coloured RenderNet: inputs `code` `[N, TEXTURE_CODE, 1,
/// 1]` and the shape's occupancy `occupancy` `[N, 1, R, R, R]` (RenderNet's input layout); the
/// grid RenderNet reads is the occupancy, then the decoded RGB times the occupancy (as
/// `nn::camera::input_values_with` builds it from coloured voxels). For recovering a texture
/// code by gradient descent; load the renderer's weights and the decoder's `tex.*` with
/// [`crate::graph::Executor::load_params_parts`]. Returns the network, `code` and `occupancy`.
pub fn decoder_with_renderer(p: &TexturePreset, rp: &Preset, head: Head, n: usize, cam_hw: [usize; 2]) -> Result<(RenderNet, Value, Value)> {
    if !rp.colour {
        return Err(Error::Invalid(format!("preset '{}' takes grey grids; the texture decoder needs its colour version (Preset::with_colour)", rp.name)));
    }
    if p.res != rp.input {
        return Err(Error::Invalid(format!("the texture decoder draws {}^3 grids; preset '{}' reads {}^3", p.res, rp.name, rp.input)));
    }
    let r = p.res;
    let mut g = Graph::new();
    let code = g.input("code", &[n, TEXTURE_CODE, 1, 1])?;
    let occupancy = g.input("occupancy", &[n, 1, r, r, r])?;
    let texture = texture_grid(&mut Builder { g: &mut g }, p, code)?;
    let painted = g.apply("painted", Op::Mul, &[texture, occupancy])?;
    let grid = g.apply("grid", Op::Concat, &[occupancy, painted])?;
    Ok((RenderNet::build_on(g, grid, rp, head, cam_hw, false)?, code, occupancy))
}
